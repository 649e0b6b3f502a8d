"""NBRDF evaluations per second inside Mitsuba 3, and the time of a sphere render.

    python benches/peers/mitsuba_nbrdf.py [--n 2097152] [--repeats 5] [--variant llvm_ad_rgb]
                                    [--spp 64] [--resolution 256] [--out bench-results]

Times the ``frenbrdf`` BSDF's ``eval`` (BRDF × cos θ_o, Dr.Jit, inside Mitsuba's
compiled kernels) on one batch of ``--n`` random direction pairs, after a warm-up call
that compiles the kernel (its time is reported apart), best of ``--repeats`` calls, for NBRDFs of 6→21→21→3
(Sztrajman's size) and 6→32→32→3 (our default), with a per-channel and a per-bin
reference BRDF, and for a MERL table (trilinear lookup); and, for comparison, the same
NBRDFs evaluated by the package's numpy/torch path (:meth:`frenbrdf.NBRDF.__call__`:
Rust half/difference vectors, torch MLP, mapping) and the bare torch MLP on precomputed
inputs. Every timed result is first checked against the numpy evaluation.

First calls and first renders compile their kernels: the benchmark gives Dr.Jit a fresh
on-disk kernel cache unless ``--warm-cache``.

Then renders a 256×256 sphere at 64 spp (:func:`frenbrdf.render.mitsuba.render_material`) of a
synthetic gold metal (GGX α = 0.05) table and of an NBRDF (a published fit from
``../shared/data/merl-nbrdf`` when present), first call (with compilation) and second,
and measures the noise of the 64 spp image against a 1024 spp one with fitted importance
sampling and with cosine sampling only. Writes ``bench-results/mitsuba_nbrdf.{md,json}``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from frenbrdf.data.analytic import METALS, AnalyticMaterial, merl_table
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import NBRDF, NBRDFConfig, nbrdf_coordinates, nbrdf_forward
from frenbrdf.render import mitsuba as fm

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]  # its folder, benches/
from common import time_calls, unit_vectors  # noqa: E402

SHARED_FIT = Path(__file__).resolve().parents[2] / "shared" / "data" / "merl-nbrdf" / "chrome-steel.h5"
#: What the NBRDF paper reports for its C++ Mitsuba plugin (evaluations per second).
PAPER_RATE = 12.5e6


def random_nbrdf(hidden, reference, seed: int = 0) -> NBRDF:
    """An NBRDF with random weights (timing does not depend on their values)."""
    generator = torch.Generator().manual_seed(seed)
    params = [torch.randn(1, *shape, generator=generator) / np.sqrt(shape[-1])
              for shape in NBRDFConfig(hidden).shapes()]
    return NBRDF(params, LogRelativeMapping(reference))


def best_time(function, repeats: int) -> float:
    """The fastest of ``repeats`` calls, no warm-up: the machine is shared, and other work only slows calls down."""
    return time_calls(function, repeats, warmup=False).best_s


def time_mitsuba_eval(material: fm.Material, wi: np.ndarray, wo: np.ndarray, repeats: int) -> dict:
    import drjit as dr
    import mitsuba as mi

    bsdf = mi.load_dict(fm.bsdf_dict(material))
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))
    directions = mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))
    dr.eval(si, directions)
    dr.sync_thread()

    def run():
        value = bsdf.eval(ctx, si, directions)
        dr.eval(value)
        dr.sync_thread()
        return value

    start = time.perf_counter()
    value = run()
    first = time.perf_counter() - start
    # Correctness before timing: against the numpy evaluation (float64) on a subset.
    check = slice(0, 20000)
    expected = material.brdf(wi[check], wo[check]) * wo[check, 2:3]
    got = np.array(value).T[check]
    error = float(np.max(np.abs(got - expected) / (np.abs(expected) + 1e-4 * np.abs(expected).max() + 1e-12)))
    if error > 1e-3:
        raise AssertionError(f"{material.name}: Mitsuba eval differs from numpy by {error:.2e} (relative)")
    seconds = best_time(run, repeats)
    return {"first_call_s": first, "eval_s": seconds, "evals_per_s": len(wi) / seconds, "max_rel_error": error}


def time_torch(nbrdf: NBRDF, wi: np.ndarray, wo: np.ndarray, repeats: int) -> dict:
    """The package's own evaluation, on at most 2^20 pairs, with torch's default threads and with one.

    On a busy machine torch's thread pool can be far slower than one thread (chunked
    small products synchronise often); the table shows the faster setting.
    """
    wi, wo = wi[:1 << 20], wo[:1 << 20]
    pairs = (wi, wo)
    coords = torch.from_numpy(nbrdf_coordinates(wi, wo).astype(np.float32))[None]
    default_threads = torch.get_num_threads()
    result = {}
    for threads in sorted({default_threads, 1}, reverse=True):
        torch.set_num_threads(threads)
        call = best_time(lambda: nbrdf(*pairs), repeats)
        with torch.inference_mode():
            mlp = best_time(lambda: nbrdf_forward(nbrdf.params, coords), repeats)
        result[threads] = {"call_per_s": len(wi) / call, "mlp_per_s": len(wi) / mlp}
    torch.set_num_threads(default_threads)
    best = max(result, key=lambda t: result[t]["call_per_s"])
    return {"threads": best, **result[best], "by_threads": result}


def time_render(material, spp: int, resolution: int) -> dict:
    start = time.perf_counter()
    image = fm.render_material(material, spp=spp, resolution=resolution)
    first = time.perf_counter() - start
    start = time.perf_counter()
    image = fm.render_material(material, spp=spp, resolution=resolution)
    second = time.perf_counter() - start
    if not np.all(np.isfinite(image)) or image.max() <= 0:
        raise AssertionError("the render is not finite or is black")
    return {"first_s": first, "second_s": second, "mean_radiance": float(image.mean())}


def noise(material, spp: int, resolution: int, reference_spp: int) -> dict:
    """RMSE of the tone-mapped 64 spp image against a 1024 spp one, per sampling strategy."""
    reference = fm.tonemap(fm.render_material(material, spp=reference_spp, resolution=resolution, seed=1))
    result = {}
    for sampling in ("fitted", "cosine"):
        image = fm.tonemap(fm.render_material(material, spp=spp, resolution=resolution, sampling=sampling))
        error = np.abs(image - reference)
        result[sampling] = {"display_rmse": float(np.sqrt(np.mean(error ** 2))),
                            "pixels_off_by_0.1": float(np.mean(error.max(axis=-1) > 0.1))}
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=1 << 21, help="direction pairs per eval call")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--variant", default=None, help="Mitsuba variant (default: frenbrdf.render.mitsuba.set_variant())")
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--out", type=Path, default=Path("bench-results"))
    parser.add_argument("--warm-cache", action="store_true",
                        help="keep Dr.Jit's on-disk kernel cache (default: a fresh one, so first calls compile)")
    args = parser.parse_args()

    if not args.warm_cache:
        # Dr.Jit keeps compiled kernels in $HOME/.drjit; a fresh HOME makes first calls compile.
        scratch = tempfile.TemporaryDirectory()
        os.environ["HOME"] = scratch.name
    variant = fm.set_variant(args.variant)
    fm.register()
    import drjit as dr
    import mitsuba as mi

    rng = np.random.default_rng(0)
    wi, wo = unit_vectors(rng, args.n, hemisphere=True), unit_vectors(rng, args.n, hemisphere=True)
    gold = merl_table(AnalyticMaterial("gold-ggx-0.05", metal_n=METALS["gold"][0], metal_k=METALS["gold"][1],
                                       roughness=0.05))
    per_bin_reference = np.maximum(merl_table(AnalyticMaterial("reference", diffuse=(0.3, 0.3, 0.3), specular=1.0,
                                                               roughness=0.2)), 0.0)
    cases = []
    for hidden in ((21, 21), (32, 32)):
        for reference_kind, reference in (("per channel", np.full(3, 0.1)), ("per bin", per_bin_reference)):
            nbrdf = random_nbrdf(hidden, reference)
            size = f"6→{'→'.join(map(str, hidden))}→3"
            material = fm.material_from_nbrdf(nbrdf, name=f"nbrdf {size}, f_ref {reference_kind}")
            case = {"material": material.name, "kind": "nbrdf", "size": size, "reference": reference_kind,
                    **time_mitsuba_eval(material, wi, wo, args.repeats)}
            if reference_kind == "per channel":
                case["torch"] = time_torch(nbrdf, wi, wo, args.repeats)
            cases.append(case)
            print(case, flush=True)
    cases.append({"material": "MERL table (trilinear)", "kind": "merl",
                  **time_mitsuba_eval(fm.material_from_table(gold, name="MERL table (trilinear)"), wi, wo,
                                      args.repeats)})
    print(cases[-1], flush=True)

    if SHARED_FIT.exists():
        nbrdf_material = fm.load_material(SHARED_FIT)
    else:
        nbrdf_material = fm.material_from_nbrdf(random_nbrdf((21, 21), np.full(3, 0.1)), name="random 6→21→21→3")
    renders = {"gold table": time_render(gold, args.spp, args.resolution),
               f"NBRDF {nbrdf_material.name}": time_render(nbrdf_material, args.spp, args.resolution)}
    print(renders, flush=True)
    noise_result = noise(gold, args.spp, args.resolution, args.reference_spp)
    print(noise_result, flush=True)

    machine = (f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs (load average "
               f"{os.getloadavg()[0]:.1f} at the end); Mitsuba {mi.__version__} "
               f"({variant}, Dr.Jit {dr.__version__}, {dr.thread_count()} threads); torch {torch.__version__} "
               f"({torch.get_num_threads()} threads)")
    lines = [f"BRDF evaluations inside Mitsuba, {args.n:,} random direction pairs per call (numpy/torch: "
             f"{min(args.n, 1 << 20):,}), best of {args.repeats} calls after a compiling warm-up. {machine}.", "",
             "| material | Mitsuba eval (M/s) | first call, compiling (s) | numpy/torch `NBRDF(wi, wo)` (M/s) "
             "| torch MLP only (M/s) | max rel. error vs numpy |", "|---|---|---|---|---|---|"]
    for case in cases:
        torch_rates = (f"{case['torch']['call_per_s'] / 1e6:.2f} ({case['torch']['threads']} thr.) | "
                       f"{case['torch']['mlp_per_s'] / 1e6:.2f}" if "torch" in case else "– | –")
        lines.append(f"| {case['material']} | {case['evals_per_s'] / 1e6:.2f} | {case['first_call_s']:.2f} | "
                     f"{torch_rates} | {case['max_rel_error']:.1e} |")
    lines += ["", f"The NBRDF paper reports {PAPER_RATE / 1e6:.1f} M evaluations/s for its C++ Mitsuba plugin "
                  "(its hardware, not this machine).", "",
              f"Render of a sphere, {args.resolution}×{args.resolution}, {args.spp} spp, path tracer depth 3, "
              "environment map + 2 directional lights:", "",
              "| material | first render, compiling (s) | second render (s) |", "|---|---|---|"]
    for name, render in renders.items():
        lines.append(f"| {name} | {render['first_s']:.2f} | {render['second_s']:.2f} |")
    lines += ["", f"Noise of the {args.spp} spp gold image against {args.reference_spp} spp (tone-mapped, "
                  "gamma 2.2):", "", "| sampling | display RMSE | pixels off by > 0.1 |", "|---|---|---|"]
    for sampling, result in noise_result.items():
        lines.append(f"| {sampling} | {result['display_rmse']:.4f} | {100 * result['pixels_off_by_0.1']:.2f} % |")

    args.out.mkdir(parents=True, exist_ok=True)
    write_text(args.out / "mitsuba_nbrdf.md", "\n".join(lines) + "\n")
    save_json(args.out / "mitsuba_nbrdf.json",
              {"variant": variant, "machine": machine, "n": args.n, "repeats": args.repeats, "eval": cases,
               "render": {"spp": args.spp, "resolution": args.resolution, **renders}, "noise": noise_result,
               "paper_rate": PAPER_RATE})
    print("\n".join(lines))


if __name__ == "__main__":
    main()
