"""``frenbrdf`` whose training batches hold the real measurements about four times as often, in this process only:
the more-measured study's runs (research/results/more-measured) train the shipped recipe through it.

    python research/studies/more_measured_frenbrdf.py train --data DATA --seed 0 --out RUN ...

(from the repository root, as real-in-data's train.sh runs it with ``FRENBRDF``).
Each batch slot, with probability ``SHARE``, takes instead a training material that is one of the 19 measurements
of ``measured_folds/folds.json``, drawn uniformly (by the run's generator); the slot is then augmented by the
recipe as any other. With 12 or 13 measurements among 187 or 188 training materials (each fold's split), a
measurement fills about a quarter of the slots instead of one in fifteen. Validation, the best epoch's choice and
the readings are today's. Nothing in the package changes.
"""

from __future__ import annotations

import sys
from pathlib import Path

import torch

from frenbrdf.cli import main
from frenbrdf.training.augment import BatchDrawer

sys.path.insert(0, str(Path(__file__).resolve().parent))
from raw_measured_frenbrdf import MEASURED  # noqa: E402

#: The chance that a batch slot is given a measurement.
SHARE = 0.2


def draw_measurements_more() -> None:
    """Makes :class:`BatchDrawer` replace a share ``SHARE`` of each batch's slots by training measurements."""
    plain_draw = BatchDrawer.draw

    def draw(self, batch, generator):
        if not hasattr(self, "measured"):  # the training split's measurements, found at the first step
            self.measured = [i for i in range(self.data.n_train) if self.data.bank.names[i] in MEASURED]
        measured = self.measured
        if measured:
            swap = (torch.rand(len(batch), generator=generator) < SHARE).tolist()
            picks = torch.randint(len(measured), (len(batch),), generator=generator).tolist()
            batch = [measured[p] if s else m for m, s, p in zip(batch, swap, picks, strict=True)]
        return plain_draw(self, batch, generator)

    BatchDrawer.draw = draw


if __name__ == "__main__":
    draw_measurements_more()
    sys.exit(main(sys.argv[1:]))
