"""Files: the raw formats (MERL tables, RGL ``.bsdf`` measurements, saved and Keras NBRDFs, files of samples),
checkpoints, and the atomic writes every output goes through. Below the models: nothing here builds a network.

A material's files are read and written through one table of formats (:mod:`frenbrdf.io.formats`)."""

from .formats import FORMATS, read_material, read_samples, read_table, write_material, write_samples

__all__ = ["FORMATS", "read_material", "read_samples", "read_table", "write_material", "write_samples"]
