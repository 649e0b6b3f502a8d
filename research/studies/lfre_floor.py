"""Why does L_fre do so little? Its floor, where its error lives, and whether it tracks the renders.

    OMP_NUM_THREADS=1 python research/studies/lfre_floor.py --runs merl-protocol/runs/frenbrdf/seed-* \\
        merl-protocol/runs/nbrdf/seed-* --weights ../shared/data/merl-nbrdf --out research/figures

The MERL-derived tables are published NBRDF fits evaluated at every bin, so the exact BRDF behind
each table is known. Evaluated at L_fre's grid nodes and mapped as the model maps, it is the best
prediction any model could make; its L_fre against the truth the loss trains on (the table's valid
bins kNN-interpolated onto the grid, then analysed) is the loss's **floor**, the part no model can
remove: interpolation, band limit, and the nodes below the horizon, where the truth is extrapolated
from the nearest valid bins and the BRDF is not. For each run's test materials, at the default
L_fre settings:

- L_fre of the reconstruction (encoder only, 4000 samples, as ``frenbrdf evaluate``) and the floor;
- the share of each in degree bands and per θ_h slice;
- the rank correlation over materials of L_fre with the render PSNR and ΔE: does a lower L_fre mean
  a better render?

``--variant`` measures an L_fre variant of :data:`frenbrdf.presets.FREQUENCY_VARIANTS` instead of the
paper's reading (``--damping`` overrides the measured fit's λ); ``--data`` reads the materials from another
folder than the runs'; materials without a published fit in ``--weights`` are skipped.

Writes ``<out>/<name>.{json,md}`` (``--name``, default ``lfre_floor``, or ``lfre_floor_<variant>``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import torch
from scipy.stats import spearmanr

from frenbrdf.data.nbrdf_import import evaluate_keras_nbrdf
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.io.merl import read_merl
from frenbrdf.models.losses import frequency_variant, spectral_distance
from frenbrdf.numerics.sht import SHT
from frenbrdf.render.scoring import FrequencyMetric, reconstruction_rows
from frenbrdf.training import Run

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import run_metadata  # noqa: E402

BANDS = ((0, 0), (1, 4), (5, 16), (17, 10_000))


def exact_coefficients(metric: FrequencyMetric, model, weights: Path) -> np.ndarray:
    """The published NBRDF behind a table at L_fre's grid nodes, mapped as ``model`` maps: ``(S, 3, ncoeff)``."""
    if model.mapping.per_bin:
        raise ValueError("the floor is measured for models with a per-channel f_ref (not the hyperbrdf preset)")
    loss = metric.parts(model)[1]
    coords = loss.node_coords.numpy().astype(np.float64)
    physical = np.maximum(evaluate_keras_nbrdf(read_keras_nbrdf(weights), coords[:, :3], coords[:, 3:]), 0.0)
    mapped = model.mapping.forward(physical, model.mapping.reference)
    with torch.no_grad():
        return loss.coefficients_from_nodes(torch.from_numpy(mapped[None]))[0].numpy()


def shares(squared: np.ndarray, degrees: np.ndarray) -> dict:
    """Fractions of Σ (c − c')² ``(S, 3, ncoeff)`` per degree band and per slice."""
    total = squared.sum()
    by_band = {f"l {low}–{min(high, int(degrees.max()))}" if high > low else f"l {low}":
               float(squared[..., (degrees >= low) & (degrees <= high)].sum() / total) for low, high in BANDS}
    return {"bands": by_band, "slices": [float(x) for x in squared.sum(axis=(1, 2)) / total]}


def measure(run: Run, weights_dir: Path, metric: FrequencyMetric, degrees: np.ndarray, resolution: int,
            data: Path | None = None) -> list[dict]:
    model = run.model()
    files = [(data or run.data) / f"{name}.binary" for name in run.split.test
             if (weights_dir / f"{name}.h5").exists()]
    latents: dict = {}
    rows = reconstruction_rows(model, files, resolution=resolution, frequency_metric=False, progress=False,
                               latents=latents)
    for row, path in zip(rows, files, strict=True):
        true = metric.true_coefficients(model, read_merl(path))
        predicted = metric.predicted_coefficients(model, latents[path.stem])
        exact = exact_coefficients(metric, model, weights_dir / f"{path.stem}.h5")
        row |= {"lfre": float(spectral_distance(predicted, true)), "floor": float(spectral_distance(exact, true)),
                "lfre_to_exact": float(spectral_distance(predicted, exact)),
                "model_shares": shares((predicted - true) ** 2, degrees),
                "floor_shares": shares((exact - true) ** 2, degrees),
                "truth_shares": shares(true ** 2, degrees)}
    return rows


def mean_shares(rows: list[dict], key: str) -> dict:
    return {"bands": {band: float(np.mean([r[key]["bands"][band] for r in rows])) for band in rows[0][key]["bands"]},
            "slices": [float(x) for x in np.mean([r[key]["slices"] for r in rows], axis=0)]}


def markdown(summary: dict) -> str:
    lines = ["| runs | materials | L_fre of the reconstruction | floor (the exact BRDF) | floor / L_fre | "
             "reconstruction vs the exact BRDF | Spearman(L_fre, PSNR) | Spearman(L_fre, ΔE) |", "|---" * 8 + "|"]
    for label, s in summary["groups"].items():
        lines.append(f"| {label} | {s['materials']} | {s['lfre']:.3f} | {s['floor']:.3f} | {s['floor'] / s['lfre']:.0%} "
                     f"| {s['lfre_to_exact']:.3f} | {s['spearman_psnr']:+.2f} | {s['spearman_delta_e']:+.2f} |")
    lines += ["", "Share of Σ (c − c')² by degree band and by θ_h slice (mean over materials):", "",
              "| of | " + " | ".join(next(iter(summary["groups"].values()))["model_shares"]["bands"]) +
              " | slices " + ", ".join(map(str, summary["slices"])) + " |", "|---" * (len(BANDS) + 2) + "|"]
    for label, s in summary["groups"].items():
        for key, name in (("model_shares", "reconstruction − truth"), ("floor_shares", "exact BRDF − truth"),
                          ("truth_shares", "the truth itself")):
            shares_ = s[key]
            lines.append(f"| {label}: {name} | " + " | ".join(f"{v:.0%}" for v in shares_["bands"].values()) +
                         " | " + ", ".join(f"{v:.0%}" for v in shares_["slices"]) + " |")
    return "\n".join(lines) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", nargs="+", required=True, type=Path, help="run folders trained on MERL-derived tables")
    parser.add_argument("--weights", required=True, type=Path, help="folder of the published NBRDF fits (.h5)")
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--out", type=Path, default=Path("research/figures"))
    parser.add_argument("--variant", default="paper", help="the L_fre variant measured (frenbrdf.presets.FREQUENCY_VARIANTS)")
    parser.add_argument("--damping", type=float, help="λ of the measured fit (default: the config's)")
    parser.add_argument("--data", type=Path, help="the materials' folder (default: each run's)")
    parser.add_argument("--name", help="file name of the results, without suffix")
    args = parser.parse_args()
    start = time.perf_counter()
    config = frequency_variant(args.variant, **({"damping": args.damping} if args.damping else {}))
    metric = FrequencyMetric(config)
    degrees = SHT(config.nlat, config.nlon, config.lmax, config.grid).degrees_orders()[:, 0]
    name = args.name or ("lfre_floor" if args.variant == "paper" else f"lfre_floor_{args.variant}")
    groups: dict[str, list[dict]] = {}
    for path in args.runs:
        run = Run(path)
        rows = measure(run, args.weights, metric, degrees, args.resolution, args.data)
        groups.setdefault(run.method, []).extend(rows)
        print(f"{path}: L_fre {np.mean([r['lfre'] for r in rows]):.3f}, floor {np.mean([r['floor'] for r in rows]):.3f}",
              flush=True)
    summary = {"slices": list(config.slices), "variant": args.variant, "frequency": vars(config), "groups": {}}
    for label, rows in groups.items():
        lfre = [r["lfre"] for r in rows]
        summary["groups"][label] = {
            "materials": len(rows), **{key: float(np.mean([r[key] for r in rows])) for key in
                                      ("lfre", "floor", "lfre_to_exact", "psnr", "delta_e")},
            "spearman_psnr": float(spearmanr(lfre, [r["psnr"] for r in rows]).statistic),
            "spearman_delta_e": float(spearmanr(lfre, [r["delta_e"] for r in rows]).statistic),
            **{key: mean_shares(rows, key) for key in ("model_shares", "floor_shares", "truth_shares")}}
    report = {"runs": [str(p) for p in args.runs], "run": run_metadata(), "summary": summary, "materials": groups,
              "seconds": time.perf_counter() - start}
    args.out.mkdir(parents=True, exist_ok=True)
    save_json(args.out / f"{name}.json", report)
    write_text(args.out / f"{name}.md", markdown(summary))
    print(markdown(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
