"""``frenbrdf`` whose training batches never augment a real measurement, in this process only: the raw-measured
study's runs (research/results/raw-measured) train the shipped recipe through it.

    python research/studies/raw_measured_frenbrdf.py train --data DATA --seed 0 --out RUN ...

(from the repository root, as real-in-data's train.sh runs it with ``FRENBRDF``).
A batch slot holding one of the 19 measurements of ``measured_folds/folds.json`` is taken as measured: never gained,
hue-turned or mixed with another material (it may still be the second material of another slot's mix). Every other
slot is drawn by the recipe's augmentation as before; validation, the best epoch's choice and the readings are
today's. Nothing in the package changes.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.cli import main
from frenbrdf.training.augment import TABLE, BatchDrawer

FOLDS = Path(__file__).resolve().parent / "measured_folds" / "folds.json"
MEASURED = frozenset(name for names in json.loads(FOLDS.read_text())["kinds"].values() for name in names)


def keep_measurements_raw() -> None:
    """Makes :class:`BatchDrawer` give every measurement's slot the plain table role."""
    plain_draw, plain_roles = BatchDrawer.draw, BatchDrawer.roles

    def draw(self, batch, generator):
        self.measured_slots = np.array([self.data.bank.names[m] in MEASURED for m in batch])
        return plain_draw(self, batch, generator)

    def roles(self, n, generator):
        drawn = plain_roles(self, n, generator)
        return np.where(self.measured_slots, TABLE, drawn)

    BatchDrawer.draw, BatchDrawer.roles = draw, roles


if __name__ == "__main__":
    keep_measurements_raw()
    sys.exit(main(sys.argv[1:]))
