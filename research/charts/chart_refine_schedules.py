"""Chart 8c: the refinement stages' learning rates, schedules and latent steps, at a fixed cost.

    OMP_NUM_THREADS=1 python research/charts/chart_refine_schedules.py --run RUN --ood RGL_FITS \\
        --max-materials 8 --name chart8c_refine_schedules

Each point of :data:`POINTS` is one :class:`~frenbrdf.models.reconstruct.RefineConfig`, measured as
chart 8 measures (:func:`chart_refine.refine_chart`: 4000 samples, renders against the true table,
CPU seconds of one thread). The named budgets of ``frenbrdf.models.reconstruct.BUDGETS`` are chosen
from them by a rule written before measuring (research/figures/README.md, chart 8c), on the ``--ood``
materials: never on the four real measurements that judge the result.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frenbrdf.models.reconstruct import BUDGETS, RefineConfig

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from chart_refine import add_run_arguments, refine_chart  # noqa: E402

from common import pyplot, save_figure  # noqa: E402

#: (family, label, config): the budgets until chart 8c first, then the candidates.
POINTS = [
    ("latent", "L100 const 1e-2", RefineConfig(latent_steps=100)),
    ("latent", "L100 cos 3e-2", RefineConfig(latent_steps=100, latent_lr=3e-2, schedule="cosine")),
    ("latent", "L100 cos 1e-1", RefineConfig(latent_steps=100, latent_lr=1e-1, schedule="cosine")),
    ("latent", "L200 cos 3e-2", RefineConfig(latent_steps=200, latent_lr=3e-2, schedule="cosine")),
    ("latent", "L400 const 1e-2", RefineConfig(latent_steps=400)),
    ("full", "L100+W1000 const 1e-3", RefineConfig(latent_steps=100, weight_steps=1000)),
    ("full", "L100+W1000 const 3e-3", RefineConfig(latent_steps=100, weight_steps=1000, weight_lr=3e-3)),
    ("full", "L100+W1000 cos 3e-3", RefineConfig(latent_steps=100, weight_steps=1000, weight_lr=3e-3,
                                                 schedule="cosine")),
    ("full", "L100+W1000 cos 1e-2", RefineConfig(latent_steps=100, weight_steps=1000, weight_lr=1e-2,
                                                 schedule="cosine")),
    ("full", "L100+W1000 cos 3e-2/3e-3", RefineConfig(latent_steps=100, latent_lr=3e-2, weight_steps=1000,
                                                      weight_lr=3e-3, schedule="cosine")),
]

#: ``--points budgets``: the encoder and the named budgets as they are now (to compare trained runs).
NAMED_BUDGETS = [("encoder", "none", BUDGETS["none"]), ("latent", "latent", BUDGETS["latent"]),
                 ("full", "full", BUDGETS["full"])]


def draw(rows: list[dict], path: Path) -> None:
    """PSNR and ΔE of every point, one panel per family, a bar per set."""
    plt = pyplot()
    sets = list(dict.fromkeys(r["set"] for r in rows))
    figure, axes = plt.subplots(2, 2, figsize=(12, 6.5))
    for column, family in enumerate(("latent", "full")):  # the encoder's row, where measured, is in the CSV
        labels = list(dict.fromkeys(r["budget"] for r in rows if r["family"] == family))
        for row, (metric, name) in enumerate((("psnr", "render PSNR (dB) ↑"), ("delta_e", "ΔE ↓"))):
            axis = axes[row, column]
            width = 0.8 / len(sets)
            for k, set_label in enumerate(sets):
                chosen = {r["budget"]: r for r in rows if r["set"] == set_label and r["family"] == family}
                axis.bar([i + k * width for i in range(len(labels))], [chosen[b][metric] for b in labels], width,
                         label=set_label)
            axis.set_xticks([i + 0.4 - width / 2 for i in range(len(labels))], labels, rotation=20, fontsize=7)
            axis.set_ylabel(name)
            axis.set_ylim(bottom=min(r[metric] for r in rows if r["family"] == family) * 0.9)
            axis.set_title(family, fontsize=9)
            axis.grid(alpha=0.3, axis="y")
    axes[0, 0].legend(fontsize=7)
    figure.suptitle("Chart 8c: refinement schedules at a fixed cost", fontsize=10)
    figure.tight_layout()
    save_figure(figure, path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_run_arguments(parser, name="chart8c_refine_schedules", max_materials=8)
    parser.add_argument("--points", choices=("schedules", "budgets"), default="schedules",
                        help="schedules: chart 8c's candidates (POINTS); budgets: the encoder and today's named "
                        "budgets, to compare trained runs")
    args = parser.parse_args(argv)
    refine_chart(args.run, args.out, ood=args.ood, max_materials=args.max_materials, name=args.name,
                 progress=not args.quiet, points=POINTS if args.points == "schedules" else NAMED_BUDGETS,
                 data=args.data, draw_chart=draw)
    print(f"wrote {Path(args.out) / args.name}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
