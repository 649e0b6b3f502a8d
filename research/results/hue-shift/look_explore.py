"""hue-shift's exploration figure (README.md): the held-out `irid_flake_paint2` from the encoder of each `kin` run,
cut from each reading's ``compare.png`` (first row: truth, then the run), truth first, in one row.

    python research/results/hue-shift/look_explore.py local/irid research/results/hue-shift/explore.jpg
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

#: The runs in the README's order, each with the column of its reading's sheet that holds it: the recipe's (seed 3,
#: ring-augment's reading of two runs, and seed 4) and `hue_shift` 1.5's (seeds 3 and 4).
RUNS = {"kin": 1, "kinaug4": 1, "kinlin3": 1, "kinlin4": 1}


def panels(sheet: Image.Image, rows: int) -> list[tuple[int, int]]:
    """The x-ranges of the first row's panels (the columns mostly not white: the renders), widened to hold their
    titles."""
    drawn = (np.asarray(sheet.crop((0, 0, sheet.width, rows))).min(axis=2) < 240).sum(axis=0) > rows // 2
    edges = np.flatnonzero(np.diff(np.concatenate([[0], drawn.astype(int), [0]])))
    return [(max(0, start - 12), min(sheet.width, end + 12)) for start, end in zip(edges[::2], edges[1::2], strict=True)]


def main(work: Path, dest: Path) -> None:
    sheets = {name: Image.open(work / f"{name}-read" / "compare.png").convert("RGB") for name in RUNS}
    rows = sheets["kinaug4"].height // 3  # each sheet: three measurements in rows, truth then a column a run
    left, right = panels(sheets["kinaug4"], rows)[0]
    cuts = [sheets["kinaug4"].crop((left, 0, right, rows))]  # the truth
    for name, column in RUNS.items():
        left, right = panels(sheets[name], rows)[column]
        cuts.append(sheets[name].crop((left, 0, right, rows)))
    figure = Image.new("RGB", (sum(cut.width for cut in cuts), rows), "white")
    x = 0
    for cut in cuts:
        figure.paste(cut, (x, 0))
        x += cut.width
    figure.save(dest, quality=90)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
