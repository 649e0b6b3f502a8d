"""Files: the raw formats (MERL tables, RGL ``.bsdf`` measurements), checkpoints, and the atomic
writes every output goes through. Below the models: nothing here builds a network."""
