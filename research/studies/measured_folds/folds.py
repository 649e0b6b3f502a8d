"""The fold study's folds and kinds (folds.json), as the shell scripts take them.

    python research/studies/measured_folds/folds.py others FOLD   # the measurements of every other fold
    python research/studies/measured_folds/folds.py fold FOLD     # the measurements of that fold
    python research/studies/measured_folds/folds.py groups        # compare_models.py's --group: KIND=NAME,...
    python research/studies/measured_folds/folds.py all           # every measurement of every fold
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

FOLDS = json.loads((Path(__file__).resolve().parent / "folds.json").read_text())


def main(argv: list[str]) -> None:
    if argv[:1] == ["others"] and len(argv) == 2:
        print(" ".join(name for k, fold in enumerate(FOLDS["folds"]) if k != int(argv[1]) for name in fold))
    elif argv[:1] == ["fold"] and len(argv) == 2:
        print(" ".join(FOLDS["folds"][int(argv[1])]))
    elif argv == ["all"]:
        print(" ".join(name for fold in FOLDS["folds"] for name in fold))
    elif argv == ["groups"]:
        print(" ".join(kind.replace(" ", "-") + "=" + ",".join(names) for kind, names in FOLDS["kinds"].items()))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
