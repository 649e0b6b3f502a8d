"""What a training work folder's split, or a training config's held-out list, says, as the studies' shell scripts
take it (RUN: a folder with run/split.json and data/, as release/train_shipped_model.py writes).

    python research/studies/split_names.py tables RUN               # RUN/data/NAME.binary of each test material
    python research/studies/split_names.py trained-on RUN LABEL...  # LABEL=NAME for each real measurement the run
                                                                     # trained or validated on (compare_models.py's
                                                                     # --trained-on)
    python research/studies/split_names.py held-out CONFIG DIR FIRST LAST  # DIR/NAME.binary of the config's
                                                                           # holdout[FIRST:LAST]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

MEASUREMENTS = Path("../shared/data/rgl-measured")


def main(argv: list[str]) -> None:
    if len(argv) == 5 and argv[0] == "held-out":
        names = json.loads(Path(argv[1]).read_text())["holdout"][int(argv[3]):int(argv[4])]
        print(" ".join(f"{argv[2]}/{name}.binary" for name in names))
        return
    if len(argv) < 2 or argv[0] not in ("tables", "trained-on"):
        sys.exit(__doc__)
    run = Path(argv[1])
    split = json.loads((run / "run" / "split.json").read_text())
    if argv[0] == "tables":
        print(" ".join(str(run / "data" / f"{name}.binary") for name in split["test"]))
    else:
        seen = set(split["train"]) | set(split["val"])
        names = sorted(p.stem for p in MEASUREMENTS.glob("*.bsdf") if p.stem in seen)
        print(" ".join(f"{label}={name}" for label in argv[2:] for name in names))


if __name__ == "__main__":
    main(sys.argv[1:])
