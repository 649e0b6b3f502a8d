"""look-ensemble's fold reading (README.md; reported only): each fold's measurements, which neither its seed-0 fold run
nor that run's looks trained on, read by the run with one look (seed 1, version 11's recipe) and with three looks
averaged (seeds 1-3, version 12's), both taken twice; encoder alone, 1,500 pairs, draw 5, random bins and the five
devices. ``OUT/one/rows.json``, ``OUT/three/rows.json`` and ``OUT/summary.md``.

    python research/results/look-ensemble/folds.py --runs local/rid --looks local/slf --out OUT
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "research" / "studies"))
from look_rule import PATTERNS, by_material, table  # noqa: E402
from pattern_readings import reconstruction_rows  # noqa: E402
from second_look import with_looks  # noqa: E402

from frenbrdf import Model  # noqa: E402
from frenbrdf.io.atomic import save_json, write_text  # noqa: E402
from frenbrdf.models.autoencoder import load_model  # noqa: E402

FOLDS = ROOT / "research" / "studies" / "measured_folds" / "folds.json"
MEASURED = ROOT.parent / "shared" / "data" / "rgl-measured"


def fold_names() -> list[list[str]]:
    """Each fold's measurements (research/studies/measured_folds/folds.json)."""
    return json.loads(FOLDS.read_text())["folds"]


def fold_models(runs: Path, looks: Path, fold: int) -> dict[str, Model]:
    """The seed-0 run of ``fold`` with its seed-1 look (``"one"``) and with its three looks averaged (``"three"``),
    both taken twice."""
    base = load_model(runs / f"mf-f{fold}-s0")
    found = [looks / f"look-f{fold}", looks / f"look-f{fold}-s2", looks / f"look-f{fold}-s3"]
    return {"one": with_looks(base, found[:1], steps=2), "three": with_looks(base, found, steps=2)}


def means(rows: list[dict]) -> str:
    """PSNR / ΔE through each pattern, means over the materials."""
    return " | ".join(f"{np.mean(list(by_material(rows, p, 'psnr').values())):.2f} / "
                      f"{np.mean(list(by_material(rows, p, 'delta_e').values())):.2f}" for p in PATTERNS)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=Path, required=True, help="the fold runs' folder (mf-fF-s0)")
    parser.add_argument("--looks", type=Path, required=True, help="the looks' folder (look-fF, look-fF-s2, -s3)")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--draws", type=int, nargs="+", default=[5])
    parser.add_argument("--count", type=int, default=1500)
    args = parser.parse_args(argv)
    rows: dict[str, list[dict]] = {"one": [], "three": []}
    for fold, names in enumerate(fold_names()):
        models = fold_models(args.runs, args.looks, fold)
        materials = [MEASURED / f"{name}.bsdf" for name in names]
        for row in reconstruction_rows(models, "arm", materials, PATTERNS, args.draws, args.count, ["none"]):
            rows[row.pop("arm")].append(row)
    for arm, found in rows.items():
        (args.out / arm).mkdir(parents=True, exist_ok=True)
        save_json(args.out / arm / "rows.json", found)
    differences, _ = table(args.out / "three" / "rows.json", args.out / "one" / "rows.json")
    summary = (f"PSNR dB / ΔE, means over the 19 measurements ({' | '.join(PATTERNS)}):\n\n"
               f"- one look: {means(rows['one'])}\n- three looks averaged: {means(rows['three'])}\n\n"
               f"three − one, per measurement, 95 % interval:\n\n{differences}\n")
    write_text(args.out / "summary.md", summary)
    print(summary)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
