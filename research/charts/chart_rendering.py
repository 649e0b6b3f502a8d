"""Chart 5: Mitsuba render error against samples per pixel and against time, per sampling strategy.

    python research/charts/chart_rendering.py --decode merl-protocol/runs/frenbrdf/seed-0 \\
        merl-protocol/merl/two-layer-gold.binary

Options: ``--spp 1 4 16 64 256``, ``--reference-spp 4096``, ``--resolution 128``,
``--repeats 3``, ``--threads 1`` (Dr.Jit's threads: the seconds are one core's),
``--variant`` (default: :func:`frenbrdf.render.mitsuba.set_variant`, ``llvm_ad_rgb`` when a
libLLVM works: the system's or the one the mitsuba extra installs), ``--out research/figures``, ``--name chart5_rendering``.

Materials: three analytic MERL tables of :mod:`frenbrdf.data.synth` (a near-mirror chromium,
GGX α = 0.02; a rough red plastic, Lambert + GGX α = 0.3; a Lambertian grey) and, with
``--decode RUN MATERIAL``, the NBRDF that the run's model decodes from 4000 random
measured bins of a MERL file (drawn as ``frenbrdf evaluate`` draws them, seed 0).

Each material is rendered by :func:`frenbrdf.render.mitsuba.render_material` (a sphere under an
environment map and two directional lights, path tracer of depth 3): once at
``--reference-spp`` with the fitted importance sampling (seed 1), then at every ``--spp``
with ``sampling="fitted"`` and with ``sampling="cosine"`` (cosine-weighted hemisphere
only), seed 0. Every (material, sampling, spp) gets one warm-up render, which compiles
its kernels, then ``--repeats`` timed renders; the chart uses their median (the whole
``render_material`` call: scene set-up and render). The error is the RMSE of the
tone-mapped image (exposure 1, clamp, gamma 2.2; every pixel, background included)
against the reference; the JSON also holds the RMSE of the linear image relative to the
reference's mean. The reference has noise too: at 4096 spp a quarter of the 256 spp
noise, which adds about 3 % to the 256 spp errors.

Writes ``<out>/<name>.png`` and, beside it, ``<name>.csv`` (one row per material,
sampling and spp) and ``<name>.json`` (those and the settings, the fitted sampling
mixtures, every timing).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from frenbrdf.data.analytic import METALS, AnalyticMaterial, merl_table
from frenbrdf.render import mitsuba as fm

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import pyplot, run_metadata, save_chart, save_figure, time_calls  # noqa: E402

DEFAULT_SPP = (1, 4, 16, 64, 256)
SAMPLINGS = ("fitted", "cosine")


def analytic_materials() -> dict[str, np.ndarray]:
    """The three analytic materials of the chart, as MERL tables."""
    n, k = METALS["chromium"]
    return {
        "chromium, GGX α 0.02": merl_table(AnalyticMaterial("chromium", metal_n=n, metal_k=k, roughness=0.02)),
        "rough plastic, α 0.3": merl_table(AnalyticMaterial("rough-plastic", diffuse=(0.5, 0.12, 0.08),
                                                            specular=1.0, roughness=0.3)),
        "Lambertian grey": merl_table(AnalyticMaterial("lambert", diffuse=(0.6, 0.6, 0.6))),
    }


def decoded_nbrdf(run: str | os.PathLike, merl_file: str | os.PathLike, samples: int = 4000):
    """The NBRDF that a run's model decodes from ``samples`` random measured bins of a MERL file."""
    from frenbrdf import Model, read_merl
    from frenbrdf.io.sampling import sample_bins, truth_samples
    from frenbrdf.render.renderer import Scene
    from frenbrdf.render.scoring import encode_and_render

    model = Model.load(run)
    table = read_merl(merl_file)
    rng = np.random.default_rng(0)
    z, _ = encode_and_render(model, *truth_samples(table, sample_bins(table, rng, samples), rng), Scene(resolution=8))
    return model.decode(z)[0]


def rendering_chart(materials: dict, out_dir, *, spps=DEFAULT_SPP, reference_spp: int = 4096, resolution: int = 128,
                    repeats: int = 3, name: str = "chart5_rendering") -> dict:
    """Measures render error against spp and time for each material and sampling; writes the chart and its data.

    Parameters
    ----------
    materials
        Display name → anything :func:`frenbrdf.render.mitsuba.load_material` takes.
    out_dir
        Folder of ``<name>.png``, ``<name>.csv`` and ``<name>.json``.
    spps
        Samples per pixel of the measured renders.
    reference_spp
        Samples per pixel of the reference (fitted sampling, another seed).
    resolution
        Image width and height.
    repeats
        Timed renders per point, after one warm-up render.

    Returns
    -------
    dict
        What ``<name>.json`` holds.
    """
    import drjit as dr
    import mitsuba as mi

    start = time.perf_counter()
    run = run_metadata()
    if repeats < 1 or not spps or min(spps) < 1 or reference_spp < 1:
        raise ValueError(f"need repeats ≥ 1 and spp ≥ 1, got repeats={repeats}, spps={spps}, "
                         f"reference_spp={reference_spp}")
    variant = fm.register()
    rows, details = [], {}
    for label, source in materials.items():
        material = fm.load_material(source)  # one Material: its sampling mixture is fitted once, here
        mixture = material.sampling
        begin = time.perf_counter()
        reference = fm.render_material(material, spp=reference_spp, resolution=resolution, seed=1)
        details[label] = {"sampling": {"cosine": mixture.cosine,
                                       "lobes": [{"alpha": lobe.alpha, "weight": lobe.weight}
                                                 for lobe in mixture.lobes]},
                          "reference_s": time.perf_counter() - begin, "times": {}}
        display_reference = fm.tonemap(reference)
        for sampling in SAMPLINGS:
            for spp in spps:
                last = {}

                def render(material=material, spp=spp, sampling=sampling, last=last):  # bound now, not late
                    last["image"] = fm.render_material(material, spp=spp, resolution=resolution, seed=0,
                                                       sampling=sampling)

                timing = time_calls(render, repeats)  # the warm-up compiles the kernels of this spp
                image = last["image"]
                rmse = float(np.sqrt(np.mean((fm.tonemap(image) - display_reference) ** 2)))
                linear = float(np.sqrt(np.mean((image - reference) ** 2)) / reference.mean())
                rows.append({"material": label, "sampling": sampling, "spp": spp, "seconds": timing.median_s,
                             "display_rmse": rmse, "linear_relative_rmse": linear})
                details[label]["times"][f"{sampling} {spp}"] = {"first_s": timing.first_s, "timed_s": timing.samples_s}
                print(f"{label:>24} {sampling:>6} {spp:>4} spp: {timing.median_s:7.3f} s, "
                      f"display RMSE {rmse:.4f}", flush=True)

    machine = (f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; Mitsuba {mi.__version__} "
               f"({variant}, Dr.Jit {dr.__version__}, {dr.thread_count()} threads)")
    report = {"variant": variant, "machine": machine, "resolution": resolution, "reference_spp": reference_spp,
              "repeats": repeats, "spp": list(spps), "materials": details, "rows": rows,
              "seconds": time.perf_counter() - start, "run": run}
    title = f"Mitsuba {variant}, {resolution}² sphere, reference {reference_spp} spp, {dr.thread_count()} thread(s)"
    save_chart(out_dir, name, rows, report, lambda path: plot(rows, path, title=title))
    return report


def plot(rows: list[dict], path: Path, title: str = "") -> None:
    """Display RMSE against spp and against seconds (log-log); solid: fitted sampling, dashed: cosine."""
    plt = pyplot()
    materials = list(dict.fromkeys(r["material"] for r in rows))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    figure, axes = plt.subplots(1, 2, figsize=(11, 5.6))
    for colour, material in zip(colours, materials, strict=False):  # the colour cycle is longer
        for sampling, style in zip(SAMPLINGS, ("-", "--"), strict=True):
            mine = [r for r in rows if r["material"] == material and r["sampling"] == sampling]
            for axis, key in zip(axes, ("spp", "seconds"), strict=True):
                axis.plot([r[key] for r in mine], [r["display_rmse"] for r in mine], style, marker="o",
                          color=colour, label=f"{material}, {sampling}")
    spps = sorted({r["spp"] for r in rows})
    top = max(r["display_rmse"] for r in rows if r["spp"] == spps[0])
    axes[0].plot(spps, [top * (s / spps[0]) ** -0.5 for s in spps], ":", color="grey", label="∝ spp^-1/2")
    for axis, label in zip(axes, ("samples per pixel", "seconds per render (median)"), strict=True):
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_xlabel(label)
        axis.set_ylabel("RMSE vs reference (tone-mapped)")
        axis.grid(alpha=0.3, which="both")
    axes[0].set_xticks(spps)
    axes[0].set_xticklabels([str(s) for s in spps])
    axes[0].minorticks_off()
    handles, labels = axes[0].get_legend_handles_labels()
    columns = 3
    figure.legend(handles, labels, loc="lower center", ncol=columns, fontsize=8, frameon=False)
    figure.suptitle(title, fontsize=10)
    figure.tight_layout(rect=(0, 0.035 * (1 + len(labels) // columns), 1, 1))
    save_figure(figure, path)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--decode", nargs=2, metavar=("RUN", "MATERIAL"),
                        help="also render the NBRDF a run's model decodes from a MERL file")
    parser.add_argument("--spp", type=int, nargs="+", default=list(DEFAULT_SPP))
    parser.add_argument("--reference-spp", type=int, default=4096)
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--repeats", type=int, default=3, help="timed renders per point, after a warm-up")
    parser.add_argument("--threads", type=int, default=1, help="Dr.Jit threads (0: its default, every core)")
    parser.add_argument("--variant", default=None, help="Mitsuba variant (default: frenbrdf.render.mitsuba.set_variant())")
    parser.add_argument("--out", type=Path, default=Path("research/figures"))
    parser.add_argument("--name", default="chart5_rendering", help="file names: <name>.png, .csv, .json")
    args = parser.parse_args(argv)
    fm.set_variant(args.variant)
    if args.threads:
        import drjit as dr

        dr.set_thread_count(args.threads)
    materials = analytic_materials()
    if args.decode:
        run, merl_file = args.decode
        materials[f"{Path(merl_file).stem} (decoded NBRDF)"] = decoded_nbrdf(run, merl_file)
    report = rendering_chart(materials, args.out, spps=tuple(args.spp), reference_spp=args.reference_spp,
                             resolution=args.resolution, repeats=args.repeats, name=args.name)
    print(f"{report['seconds']:.0f} s → {args.out / args.name}.png")


if __name__ == "__main__":
    main()
