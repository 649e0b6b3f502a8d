"""Comparisons that decide: methods over several seeds, with paired intervals.

Each seed is its own split and initialisation, and every method of a seed is evaluated on
that seed's test materials, so methods pair up within a seed. For a metric, a method's
value per seed is its mean over the test materials; the table gives the mean ± standard
deviation of those over the seeds and, for each method against the reference (FreNBRDF),
a **paired t-interval over seeds**: the per-seed differences d_s, their mean ± t_{n−1} ·
sd(d) / √n at 95 %. A difference is significant only where its interval excludes 0; with
one seed there is no interval, and nothing is called significant.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

REFERENCE = "frenbrdf"


def paired_interval(differences, confidence: float = 0.95) -> dict:
    """Mean of paired differences with its t-interval: ``{"mean", "low", "high", "n", "significant"}``
    (``low``/``high`` None for fewer than two differences)."""
    d = np.asarray(differences, dtype=np.float64)
    if d.size == 0 or not np.all(np.isfinite(d)):
        raise ValueError(f"paired differences must be finite and at least one, got {d.tolist()}")
    mean = float(d.mean())
    if d.size < 2:
        return {"mean": mean, "low": None, "high": None, "n": 1, "significant": False}
    half = float(stats.t.ppf(0.5 + confidence / 2, d.size - 1) * d.std(ddof=1) / math.sqrt(d.size))
    low, high = mean - half, mean + half
    return {"mean": mean, "low": low, "high": high, "n": int(d.size), "significant": bool(low > 0 or high < 0)}


def compare_seeds(summaries: dict[int, dict[str, dict[str, float]]], keys, reference: str = REFERENCE) -> dict:
    """Per metric: each method's mean and sd over seeds, and each method's paired difference against
    ``reference``.

    ``summaries``: seed → method → metric → value (the ``summary`` of each seed's evaluation).
    """
    seeds = sorted(summaries)
    methods = list(summaries[seeds[0]])
    if any(list(summaries[s]) != methods for s in seeds):
        raise ValueError(f"every seed needs the same methods; got {[list(summaries[s]) for s in seeds]}")
    if reference not in methods:
        raise ValueError(f"the reference method {reference!r} is not among {methods}")
    table = {}
    for key in keys:
        values = {m: [summaries[s][m][key] for s in seeds] for m in methods}
        table[key] = {
            "methods": {m: {"mean": float(np.mean(v)), "sd": float(np.std(v, ddof=1)) if len(v) > 1 else None,
                            "by_seed": v} for m, v in values.items()},
            "differences": {m: paired_interval(np.subtract(values[m], values[reference]))
                            for m in methods if m != reference},
        }
    return {"seeds": seeds, "methods": methods, "reference": reference, "metrics": table}


def markdown(comparison: dict, labels: dict[str, str]) -> str:
    """The comparison as a Markdown table: mean ± sd per method, then each difference with its interval
    (bold where it excludes 0)."""
    methods, reference, seeds = comparison["methods"], comparison["reference"], comparison["seeds"]
    others = [m for m in methods if m != reference]
    header = ["", *methods, *(f"{m} − {reference} (95 % CI)" for m in others)]
    lines = ["| " + " | ".join(header) + " |", "|---" * len(header) + "|"]
    for key, row in comparison["metrics"].items():
        cells = [labels.get(key, key)]
        for m in methods:
            entry = row["methods"][m]
            cells.append(f"{entry['mean']:.3g}" + (f" ± {entry['sd']:.2g}" if entry["sd"] is not None else ""))
        for m in others:
            d = row["differences"][m]
            text = f"{d['mean']:+.3g}" + (f" [{d['low']:+.3g}, {d['high']:+.3g}]" if d["low"] is not None else "")
            cells.append(f"**{text}**" if d["significant"] else text)
        lines.append("| " + " | ".join(cells) + " |")
    note = (f"Mean ± standard deviation over {len(seeds)} seeds ({', '.join(map(str, seeds))}), each its own split "
            "and initialisation; differences against "
            f"{reference} are paired within a seed, with a 95 % t-interval over the seeds (bold: the interval "
            "excludes 0, the difference is significant; otherwise it is within noise).")
    return note + "\n\n" + "\n".join(lines) + "\n"
