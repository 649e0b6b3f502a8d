"""decoder-finetune's encoder refit (README.md): a fold's base run config made into the config that trains an
encoder for its fine-tuned decoder: the decoder frozen (``decoder_from``), the encoder starting from the base run's
(``init_from``), at most 150 epochs, patience 30, the rate halved after 10 without a better validation loss.

    python research/results/decoder-finetune/refit_config.py BASE_RUN FINETUNED OUT.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.io.atomic import write_text

if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    base, finetuned, out = sys.argv[1:]
    config = json.loads((Path(base) / "config.json").read_text())
    config = {k: v for k, v in config.items() if k not in ("data", "out", "seed")}
    config.update(decoder_from=finetuned, init_from=base, epochs=150, patience=30, lr_plateau=10, render_every=0)
    write_text(out, json.dumps(config, indent=1) + "\n")
