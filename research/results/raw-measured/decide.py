"""raw-measured's rule (README.md): `mfraw` (seed 0 of each fold, the measurements never augmented) against the
recipe's same-seed fold runs, per measurement over the 19 and per table over the 40; with ``--arm mfmore``,
research/results/more-measured's, the same rule.

    python research/results/raw-measured/decide.py OUT [--arm mfraw]

OUT holds read.sh's `ARM-fF-s0/compare.json` and `tables/compare.json`. Writes OUT/decision.json and prints the
rule's tests and what is reported beside them.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(RESULTS / "real-in-data"))
from seeds import mean as mean_of  # noqa: E402  ("PSNR / ΔE" over the names a figure has)
from seeds import per_material  # noqa: E402  (material → (PSNR, ΔE, runs))

# fold-tie's baselines and paired differences, loaded by path (both scripts are called decide.py).
_spec = importlib.util.spec_from_file_location("fold_tie_decide", RESULTS / "fold-tie" / "decide.py")
assert _spec is not None and _spec.loader is not None
fold_tie = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fold_tie)
HERE_RUNS, XEON_RUNS, KINDS, HUE_LOST = fold_tie.HERE_RUNS, fold_tie.XEON_RUNS, fold_tie.KINDS, fold_tie.HUE_LOST
change, rows_of = fold_tie.change, fold_tie.rows_of

def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    parser.add_argument("--arm", default="mfraw")
    args = parser.parse_args(argv)
    label = args.arm
    arm_rows = rows_of(sorted(args.out.glob(f"{label}-f*-s0/compare.json")))
    here_rows, xeon_rows = rows_of([HERE_RUNS]), rows_of([XEON_RUNS / "measured" / "compare.json"])
    arm = {b: per_material(arm_rows, label, b) for b in ("none", "latent", "full")}
    base = {b: per_material(here_rows, "mf", b) for b in ("none", "latent")} | {"full": per_material(xeon_rows, "mf", "full")}
    if any(len(arm[b]) != 19 for b in arm):
        raise SystemExit(f"{label} read {[len(arm[b]) for b in arm]} measurements (encoder, latent, full); expected 19")
    tables = rows_of([args.out / "tables" / "compare.json", XEON_RUNS / "tables" / "compare.json"])
    tables_arm = {b: per_material(tables, label, b) for b in ("none", "latent")}
    tables_base = {b: per_material(tables, "mf", b) for b in ("none", "latent")}
    if any(len(tables_arm[b]) != 40 for b in tables_arm):
        raise SystemExit(f"{label} read {[len(tables_arm[b]) for b in tables_arm]} tables (encoder, latent); expected 40")

    readings = {b: {"psnr": change(arm[b], base[b], 0), "delta_e": change(arm[b], base[b], 1)} for b in arm}
    on_tables = {b: change(tables_arm[b], tables_base[b], 0) for b in ("none", "latent")}
    encoder, latent = readings["none"], readings["latent"]
    tests = {
        "helps: latent PSNR's lower end above 0, or the encoder's above 0 with latent's mean not below 0":
            latent["psnr"]["low"] > 0 or (encoder["psnr"]["low"] > 0 and latent["psnr"]["mean"] >= 0),
        "harmless: encoder PSNR's lower end above -0.5 dB": encoder["psnr"]["low"] > -0.5,
        "harmless: encoder's mean ΔE change below +0.5": encoder["delta_e"]["mean"] < 0.5,
        "harmless: latent PSNR's lower end above -0.5 dB": latent["psnr"]["low"] > -0.5,
        "harmless: latent's mean ΔE change below +0.5": latent["delta_e"]["mean"] < 0.5,
        "harmless: tables' encoder lower end above -0.5 dB": on_tables["none"]["low"] > -0.5,
        "harmless: tables' latent lower end above -0.5 dB": on_tables["latent"]["low"] > -0.5,
    }
    reported = {
        f"figures (PSNR / ΔE), {label} and the baseline": {b: [mean_of(arm[b], arm[b]), mean_of(base[b], base[b])]
                                                         for b in arm},
        f"by kind, {label} and the baseline": {b: {k: [mean_of(arm[b], n), mean_of(base[b], n)] for k, n in KINDS.items()}
                                             for b in arm},
        f"by kind, {label} − the baseline (PSNR, ΔE)": {
            b: {k: [round(sum(arm[b][m][i] - base[b][m][i] for m in n) / len(n), 2) for i in (0, 1)]
                for k, n in KINDS.items()} for b in arm},
        f"tables (PSNR / ΔE), {label} and mf seed 0 (Xeon)": {b: [mean_of(tables_arm[b], tables_arm[b]),
                                                              mean_of(tables_base[b], tables_base[b])]
                                                          for b in ("none", "latent")},
        f"ΔE > {HUE_LOST:g}": {b: {m: round(v[1], 2) for m, v in arm[b].items() if v[1] > HUE_LOST} for b in arm},
        "per measurement, PSNR change": {b: {m: round(arm[b][m][0] - base[b][m][0], 2) for m in sorted(arm[b])}
                                         for b in arm},
    }
    decision = {"helps": all(v for k, v in tests.items() if k.startswith("helps")),
                "harmless": all(v for k, v in tests.items() if k.startswith("harmless")),
                "tests": tests, "readings": readings, "tables": on_tables, "reported": reported}
    decision["passes"] = decision["helps"] and decision["harmless"]
    (args.out / "decision.json").write_text(json.dumps(decision, indent=1, ensure_ascii=False) + "\n")
    fold_tie.show(decision, on_tables)


if __name__ == "__main__":
    main()
