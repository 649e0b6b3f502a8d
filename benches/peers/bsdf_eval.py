"""Evaluations per second of the native RGL ``.bsdf`` evaluator against Mitsuba 3's
``measured`` plugin, measured side by side in one run.

    python benches/peers/bsdf_eval.py [--file PATH.bsdf] [--n 20000] [--repeats 5] [--rounds 15] [--json results.json]

1. The same ``--n`` random direction pairs (float32-rounded, so both see identical inputs)
   evaluated by ``frenbrdf._native.BsdfMeasurement.eval`` (one batched call, rayon), in its
   default float32 path (vectorised across pairs) and in float64 (``double=True``), and by
   Mitsuba's ``measured`` BSDF twice: in ``llvm_ad_rgb``, one vectorised ``eval`` over all
   pairs (its kernel compiled in the warm-up), timed in ``--rounds`` rounds that alternate with
   ours (each round the best of three calls of each; the ratio is taken round by round, as the
   machine's speed drifts between rounds), and in ``scalar_rgb``, one ``eval`` call per
   pair from a Python loop. (Mitsuba 3.9.1 evaluates these files in its JIT variants;
   mitsuba3#664 reported them crashing in 3.2.) Mitsuba's values (f·cos θ_o) are divided by
   cos θ_o and checked against ours before anything is timed. The scalar ratio includes
   Python's per-call overhead on Mitsuba's side.
2. One MERL table's 1,458,000 bins (90 θ_h × 90 θ_d × 180 φ_d, each at its bin position
   ``frenbrdf._native.merl_bin_to_angles``, φ_h = 0) evaluated into a MERL table by
   ``BsdfMeasurement.merl_table`` (float32; goal ≤ 0.05 s on 2 cores), what
   ``MeasuredBSDF.table`` calls. Bins with a direction below the horizon (MERL's unmeasured
   bins) are cheap.

Prints the CPU's model (``lscpu``) and the thread count. Times are medians after a warm-up.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from frenbrdf import _native
from frenbrdf.io.atomic import save_json
from frenbrdf.render.mitsuba.variants import _import_mitsuba

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]  # its folder, benches/
from common import cpu_model, median_seconds, time_interleaved  # noqa: E402

SHARED_DATA = Path(os.environ.get("FRENBRDF_SHARED_DATA", Path(__file__).resolve().parents[3] / "shared" / "data"))
DEFAULT_FILE = SHARED_DATA / "rgl-measured" / "vch_golden_yellow_rgb.bsdf"


def direction_pairs(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Uniform pairs over the upper hemisphere (z ≥ 0.02), rounded to float32."""
    rng = np.random.default_rng(seed)

    def upper() -> np.ndarray:
        z = rng.uniform(0.02, 1.0, n)
        phi = rng.uniform(0.0, 2 * np.pi, n)
        rho = np.sqrt(1.0 - z * z)
        return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1).astype(np.float32).astype(np.float64)

    return upper(), upper()


def merl_bin_directions() -> tuple[np.ndarray, np.ndarray]:
    """(wi, wo) at every MERL bin, θ_h slowest, φ_d fastest."""
    bins = np.stack(np.meshgrid(np.arange(90.0), np.arange(90.0), np.arange(180.0), indexing="ij"), -1).reshape(-1, 3)
    angles = _native.merl_bin_to_angles(bins)
    rusinkiewicz = np.stack([angles[:, 0], np.zeros(len(angles)), angles[:, 1], angles[:, 2]], axis=1)
    return _native.rusinkiewicz_to_directions(rusinkiewicz)


def mitsuba_eval(path: Path, wi: np.ndarray, wo: np.ndarray) -> tuple[np.ndarray, float]:
    """Mitsuba's f (its eval over cos θ_o) at the pairs in ``scalar_rgb``, and the loop's time."""
    mi, _ = _import_mitsuba()
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    wi_list, wo_list = wi.tolist(), wo.tolist()
    out = np.empty((len(wi), 3))

    def loop() -> None:
        for k in range(len(wi_list)):
            si.wi = mi.Vector3f(wi_list[k])
            out[k] = bsdf.eval(ctx, si, mi.Vector3f(wo_list[k]))

    loop()
    start = time.perf_counter()
    loop()
    return np.maximum(out / wo[:, 2:], 0.0), time.perf_counter() - start


def mitsuba_llvm_eval(path: Path, wi: np.ndarray, wo: np.ndarray) -> tuple[np.ndarray, Callable[[], object]] | None:
    """Mitsuba's f at the pairs in ``llvm_ad_rgb`` (one vectorised call), and that call to time; None where the
    LLVM backend does not work here."""
    from frenbrdf.render.mitsuba import llvm_available

    if not llvm_available():
        return None
    mi, dr = _import_mitsuba()
    mi.set_variant("llvm_ad_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))
    directions = mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))

    def evaluate():
        value = bsdf.eval(ctx, si, directions)
        dr.eval(value)
        dr.sync_thread()  # the LLVM backend launches kernels asynchronously
        return value

    out = np.array(evaluate()).T
    return np.maximum(out / wo[:, 2:], 0.0), evaluate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--file", type=Path, default=DEFAULT_FILE, help="an RGB .bsdf file of the RGL database")
    parser.add_argument("--n", type=int, default=20_000, help="direction pairs of the peer comparison")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--rounds", type=int, default=15,
                        help="alternating rounds of ours and Mitsuba llvm_ad_rgb for their ratio")
    parser.add_argument("--json", type=Path, help="also write the results here")
    args = parser.parse_args()
    if not args.file.is_file():
        sys.exit(f"{args.file} not found: pass --file or set FRENBRDF_SHARED_DATA")

    measurement = _native.BsdfMeasurement.read(args.file)
    wi, wo = direction_pairs(args.n)
    ours, ours_double = measurement.eval(wi, wo), measurement.eval(wi, wo, double=True)
    reference, mitsuba_s = mitsuba_eval(args.file, wi, wo)
    scale = reference.max()
    for values in (ours, ours_double):
        np.testing.assert_allclose(values, reference, rtol=2e-4, atol=2e-6 * scale)
    error = np.abs(ours - reference)
    llvm = mitsuba_llvm_eval(args.file, wi, wo)
    if llvm is not None:
        np.testing.assert_allclose(ours, llvm[0], rtol=2e-4, atol=2e-6 * scale)
        # Ours and Mitsuba's in alternating rounds: the ratio, round by round, under the same conditions.
        llvm_rounds = time_interleaved(lambda: measurement.eval(wi, wo), llvm[1], args.rounds).ratio_summary()

    # Ours at these pairs is timed once: in the rounds beside Mitsuba's where it can run.
    ours_s = (median_seconds(lambda: measurement.eval(wi, wo), args.repeats) if llvm is None
              else llvm_rounds["first_median_s"])
    ours_double_s = median_seconds(lambda: measurement.eval(wi, wo, double=True), args.repeats)
    big_wi, big_wo = direction_pairs(1_000_000, seed=1)
    ours_big_s = median_seconds(lambda: measurement.eval(big_wi, big_wo), args.repeats)
    measurement.merl_table()  # the bins' directions are computed on the first call, and kept
    merl_s = median_seconds(measurement.merl_table, args.repeats)
    merl_double_s = median_seconds(lambda: measurement.merl_table(double=True), args.repeats)
    merl_wi, merl_wo = merl_bin_directions()
    above = float(np.mean((merl_wi[:, 2] > 0) & (merl_wo[:, 2] > 0)))

    results = {
        "cpu": cpu_model(),
        "threads": _native.num_threads(),
        "file": args.file.name,
        "pairs": args.n,
        "max_abs_error": float(error.max()),
        "max_value": float(scale),
        "ours_evals_per_s": args.n / ours_s,
        "ours_double_evals_per_s": args.n / ours_double_s,
        "ours_evals_per_s_1M_batch": 1e6 / ours_big_s,
        "mitsuba_scalar_rgb_evals_per_s": args.n / mitsuba_s,
        "ratio_ours_over_mitsuba": mitsuba_s / ours_s,
        "mitsuba_llvm_ad_rgb_evals_per_s": None if llvm is None else args.n / llvm_rounds["second_median_s"],
        "ratio_ours_over_mitsuba_llvm_rounds": None if llvm is None else llvm_rounds,
        # Not interleaved: Mitsuba's median from the rounds over ours in float64 timed on its own.
        "ratio_ours_double_over_mitsuba_llvm": None if llvm is None else llvm_rounds["second_median_s"] / ours_double_s,
        "merl_table_bins": len(merl_wi),
        "merl_table_fraction_above_horizon": above,
        "merl_table_s": merl_s,
        "merl_table_double_s": merl_double_s,
    }
    print(f"CPU: {results['cpu']} ({results['threads']} threads); {args.file.name}")
    print(f"agreement on {args.n} pairs: max abs error {error.max():.2e} (max value {scale:.3g})")
    print(f"ours float32: {results['ours_evals_per_s']:,.0f} evaluations/s ({args.n} pairs), "
          f"{results['ours_evals_per_s_1M_batch']:,.0f}/s (1,000,000 pairs)")
    print(f"ours float64: {results['ours_double_evals_per_s']:,.0f} evaluations/s ({args.n} pairs)")
    print(f"Mitsuba: {results['mitsuba_scalar_rgb_evals_per_s']:,.0f} evaluations/s (scalar_rgb, one call per pair)")
    print(f"ratio ours float32 / Mitsuba scalar_rgb: {results['ratio_ours_over_mitsuba']:.1f}×")
    if llvm is None:
        print("Mitsuba llvm_ad_rgb: not usable here (no libLLVM that works)")
    else:
        print(f"Mitsuba: {results['mitsuba_llvm_ad_rgb_evals_per_s']:,.0f} evaluations/s (llvm_ad_rgb, one "
              f"vectorised call), ours {args.n / llvm_rounds['first_median_s']:,.0f}/s in the same rounds")
        print(f"ratio ours float32 / Mitsuba llvm_ad_rgb over {llvm_rounds['rounds']} alternating rounds: median "
              f"{llvm_rounds['median']:.2f}× (quartiles {llvm_rounds['quartiles'][0]:.2f}–{llvm_rounds['quartiles'][1]:.2f}×, "
              f"range {llvm_rounds['range'][0]:.2f}–{llvm_rounds['range'][1]:.2f}×); float64 (timed apart) "
              f"{results['ratio_ours_double_over_mitsuba_llvm']:.2f}×")
    print(f"one MERL table ({len(merl_wi):,} bins, {above:.0%} with both directions above the horizon): "
          f"{merl_s:.3f} s (float32), {merl_double_s:.3f} s (float64)")
    if args.json:
        save_json(args.json, results)  # atomically


if __name__ == "__main__":
    main()
