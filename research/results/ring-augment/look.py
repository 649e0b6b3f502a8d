"""ring-augment's figure (README.md): `irid_flake_paint2` from the encoder of each one-material run beside the truth,
cut from each reading's ``compare.png`` (truth, then the run; draw 0), in one row; then the two small-set readings'
sheets as they are.

    python research/results/ring-augment/look.py local/irid research/results/ring-augment
"""

from __future__ import annotations

import sys
from pathlib import Path

from PIL import Image

#: The one-material runs, in the README's order, and what each kept of the recipe's augmentation.
ONE = {"one-recipe": "recipe", "one-noaug": "none", "one-nohue": "no hue turns", "one-nomix": "no mixes",
       "one-gains": "gains alone"}


def main(work: Path, dest: Path) -> None:
    sheets = {name: Image.open(work / f"{name}-read" / "compare.png").convert("RGB") for name in ONE}
    first = next(iter(sheets.values()))
    half = first.width // 2
    row = Image.new("RGB", (half * (len(ONE) + 1), first.height), "white")
    row.paste(first.crop((0, 0, half, first.height)), (0, 0))  # the truth
    for i, sheet in enumerate(sheets.values(), start=1):
        row.paste(sheet.crop((half, 0, sheet.width, sheet.height)), (half * i, 0))
    row.save(dest / "one-material.jpg", quality=90)
    for name in ("seven", "kin"):
        Image.open(work / f"{name}-read" / "compare.png").convert("RGB").save(dest / f"{name}.jpg", quality=90)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(Path(sys.argv[1]), Path(sys.argv[2]))
