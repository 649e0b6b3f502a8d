"""The sampling-patterns study's decision, by the rule fixed before its runs (research/results/sampling-patterns).

    python research/studies/sampling_patterns/decide.py research/results/sampling-patterns/compare.json

Reads the rows of ``compare_models.py`` and, on the held-out tables only (the 19 real measurements are judged
afterwards and decide nothing), at ``COUNT`` samples, encoder only:

1. *Sampling*: a mixture of ``MIXTURES`` (its mean-pooled variant) replaces ``paper-mean`` if its PSNR averaged
   over the ``INSTRUMENT_PATTERNS`` is higher, the 95 % interval over the materials of the per-material
   difference above 0, and its random-bin (``merl-bins``) PSNR is not worse beyond noise (that difference's
   interval not wholly below 0); of several that pass, the one with the largest mean gain on the patterns.
2. *Pooling*: the density-pooled variant of the winner of 1 (``instruments-density``, ``mixed-density`` or
   ``paper-density``) replaces it by the same test against it.

Each variant's figure per material is the mean over its runs (seeds). Prints the two tests and the choice, and
writes ``decision.json`` beside the rows.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # research/studies
from compare_models import per_material_psnr  # noqa: E402

INSTRUMENT_PATTERNS = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
COUNT = 1500
MIXTURES = ("instruments", "mixed")


def per_material(rows: list[dict], variant: str, patterns) -> dict[str, float]:
    """Material → the variant's encoder PSNR averaged over ``patterns`` (at ``COUNT``) and its runs."""
    return per_material_psnr(rows, variant, patterns, count=COUNT)


def test(rows: list[dict], candidate: str, incumbent: str) -> dict:
    """The rule's test of ``candidate`` against ``incumbent``: both intervals and whether the candidate wins."""
    out = {}
    for name, patterns in (("instruments", INSTRUMENT_PATTERNS), ("merl-bins", ("merl-bins",))):
        new, old = per_material(rows, candidate, patterns), per_material(rows, incumbent, patterns)
        out[name] = paired_interval([new[m] - old[m] for m in sorted(new.keys() & old.keys())])
    out["wins"] = bool(out["instruments"]["low"] > 0 and out["merl-bins"]["high"] > 0)
    return out


def main(argv=None) -> int:
    path = Path((argv or sys.argv[1:])[0])
    rows = json.loads(path.read_text())["rows"]
    sampling = {name: test(rows, f"{name}-mean", "paper-mean") for name in MIXTURES}
    passed = [name for name in MIXTURES if sampling[name]["wins"]]
    mixture = max(passed, key=lambda name: sampling[name]["instruments"]["mean"]) if passed else "paper"
    pooling = test(rows, f"{mixture}-density", f"{mixture}-mean")
    chosen = f"{mixture}-density" if pooling["wins"] else f"{mixture}-mean"
    decision = {"count": COUNT, "patterns": INSTRUMENT_PATTERNS, "sampling": sampling, "pooling": pooling,
                "chosen": chosen}
    save_json(path.with_name("decision.json"), decision)
    tests = [(f"sampling: {name}-mean vs paper-mean", sampling[name]) for name in MIXTURES]
    for name, result in [*tests, (f"pooling: {mixture}-density vs {mixture}-mean", pooling)]:
        print(name, {key: (f"{v['mean']:+.2f} [{v['low']:+.2f}, {v['high']:+.2f}]" if isinstance(v, dict) else v)
                     for key, v in result.items()})
    print("chosen:", chosen)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
