"""The checked argparse types of the CLI's options: each refuses a value outside its range, naming the range."""

from __future__ import annotations

import argparse
import importlib
import math

#: The most epochs, renders, edits or materials an integer option of the CLI takes (more would run for years).
MAX_COUNT = 1_000_000
#: The most samples per pixel of a --mitsuba render.
MAX_SPP = 1 << 16


def limit(module: str, name: str):
    """A limit the library sets (``module.name``), read when an option is parsed: its module is imported then,
    not at every start of the CLI."""
    return lambda: getattr(importlib.import_module(module, "frenbrdf"), name)


def whole(low: int, high, what: str = ""):
    """An argparse type: a whole number in ``low … high`` (an int, or a function giving it: :func:`limit`);
    the message says the range. ``what``: the noun for messages ("a seed")."""
    def parse(text: str) -> int:
        top = high() if callable(high) else high
        digits = text.strip().removeprefix("-").removeprefix("+")
        # ASCII digits only ("²".isdigit() is true), and few of them (int() refuses more than 4300).
        if not (digits.isascii() and digits.isdigit() and len(digits) <= 30 and low <= int(text) <= top):
            raise argparse.ArgumentTypeError(f"{f'{what} is' if what else 'expected'} a whole number in "
                                             f"{low:,} … {top:,}, got {text!r}")
        return int(text)

    return parse


def seed(text: str) -> int:
    from ..configs import MAX_SEED

    return whole(0, MAX_SEED, "a seed")(text)


# The checked argparse types of the integer options.
positive_count, count = whole(1, MAX_COUNT), whole(0, MAX_COUNT)
bank_size = whole(1, limit(".data.synth", "MAX_BANK"))
table_samples = whole(1, limit(".io.merl", "N_BINS"))  # drawn from a MERL table's bins
resolution = whole(8, limit(".render.renderer", "MAX_RESOLUTION"))
evaluate_resolution = whole(8, limit(".evaluation.evaluate", "MAX_RESOLUTION"))
edit_resolution = whole(8, limit(".material.edit", "MAX_RESOLUTION"))
nbrdf_width = whole(1, limit(".models.nbrdf", "MAX_WIDTH"))
fit_epochs = whole(1, limit(".training.decoder_fit", "MAX_EPOCHS"))
lmax = whole(1, limit(".models.losses", "MAX_LMAX"))
coverage_k = whole(0, limit(".models.coverage", "MAX_K"))


def _number(text: str) -> float:
    """``float(text)``, or NaN where it is not a number (so every range check below refuses it)."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def decibels(text: str) -> float:
    """An argparse type: a finite number of dB > 0 (NaN and inf are numbers to ``float()``)."""
    value = _number(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number of dB > 0, got {text!r}")
    return value


def between(low: float, high: float, expected: str, *, low_excluded: bool = False):
    """An argparse type: a number in [low, high] (``low_excluded``: in (low, high]); the message says
    ``expected``. NaN and inf are numbers to ``float()``: both fall outside every range."""
    def parse(text: str) -> float:
        value = _number(text)
        if not ((low < value if low_excluded else low <= value) and value <= high):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return value

    return parse


# The checked argparse types of the bounded number options.
unit_interval = between(0, 1, "a number in 0 … 1")  # an edit's position t
rate = between(0, 1, "a learning rate in (0, 1]", low_excluded=True)  # larger Adam steps overflow
rate_or_zero = between(0, 1, "a learning rate in [0, 1] (0: kept as is)")
loss_weight = between(0, 100, "a weight in 0 … 100")


def sample_count(text: str) -> int | None:
    from ..io.samples import MIN_SAMPLES

    if text == "all":
        return None
    if not text.isdigit() or int(text) < MIN_SAMPLES:  # as many as a file of samples must hold
        raise argparse.ArgumentTypeError(f"expected a number ≥ {MIN_SAMPLES} or 'all', got {text!r}")
    return int(text)


def bank_mix(text: str) -> str:
    """An argparse type: the name of a bank's mix of kinds (:data:`frenbrdf.data.synth.MIXES`)."""
    from ..data.synth import MIXES

    if text not in MIXES:
        raise argparse.ArgumentTypeError(f"expected a mix, one of {', '.join(MIXES)}; got {text!r}")
    return text


def pattern(text: str) -> str:
    """An argparse type: the name of a sampling pattern (:data:`frenbrdf.io.patterns.PATTERNS`)."""
    from ..io.patterns import PATTERNS

    if text not in PATTERNS:
        raise argparse.ArgumentTypeError(f"expected a sampling pattern, one of {', '.join(PATTERNS)}; got {text!r}")
    return text
