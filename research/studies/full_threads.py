"""How much `full`'s result on one material depends on the machine's arithmetic: the shipped model reconstructs each
measurement from the same samples and the same refinement seed, once in a process with one thread and once with
two, and the two renders are scored against the measurement's.

    python research/studies/full_threads.py ../shared/data/rgl-measured/*.bsdf --out research/results/full-threads \
        [--budget full]

``--budget``: compare_models.py's budget syntax (``full@schedule=constant,weight_lr=0.003`` is `full` before
2026-11-30).

Each setting runs in a process of its own (``OMP_NUM_THREADS``, which PyTorch reads at start-up); writes
``OUT/threads-N.json`` (PSNR by material) and ``OUT/summary.json`` (the differences) and prints them.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from frenbrdf.io.atomic import save_json

THREADS = (1, 2)


def read_one_setting(paths: list[str], out: Path, samples: int, budget: str) -> None:
    """In this process (its thread count fixed at start-up): ``budget`` on each measurement, 4,000 random bins of
    draw 0 as compare_models.py draws them, refinement seed 0, render PSNR at 128²."""
    import torch

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from compare_models import budget_config, condition_rng

    from frenbrdf import Model
    from frenbrdf.io import read_material
    from frenbrdf.io.patterns import pattern_samples
    from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
    from frenbrdf.render.scoring import image_metrics, refined_reconstruction

    model, scene = Model.pretrained(), Scene(resolution=128)
    mask = material_mask(scene)
    psnr = {}
    for path in paths:
        truth = read_material(path)
        drawn = pattern_samples(truth, "merl-bins", samples, condition_rng(0, "merl-bins"))
        _, image, _ = refined_reconstruction(model, drawn, scene, budget_config(budget))
        psnr[Path(path).stem] = image_metrics(tonemap(render_linear(truth, scene)), image, mask)["psnr"]
    save_json(out / f"threads-{torch.get_num_threads()}.json", psnr)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--budget", default="full")
    parser.add_argument("--one-setting", action="store_true", help=argparse.SUPPRESS)  # the child processes
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if args.one_setting:
        read_one_setting(args.measurements, args.out, args.samples, args.budget)
        return 0
    for threads in THREADS:
        subprocess.run([sys.executable, __file__, *args.measurements, "--out", str(args.out), "--samples",
                        str(args.samples), "--budget", args.budget, "--one-setting"], check=True,
                       env={**os.environ, "OMP_NUM_THREADS": str(threads)})
    one, two = (json.loads((args.out / f"threads-{n}.json").read_text()) for n in THREADS)
    change = {name: two[name] - one[name] for name in sorted(one)}
    values = np.array(list(change.values()))
    summary = {"two_minus_one": change, "mean": float(values.mean()), "mean_abs": float(np.abs(values).mean()),
               "largest_abs": float(np.abs(values).max()), "mean_psnr": {"1": float(np.mean(list(one.values()))),
                                                                         "2": float(np.mean(list(two.values())))}}
    save_json(args.out / "summary.json", summary)
    for name, value in sorted(change.items(), key=lambda item: item[1]):
        print(f"{name:32s} {one[name]:6.2f} → {two[name]:6.2f} dB ({value:+.2f})")
    print(f"mean {summary['mean']:+.2f} dB, mean |difference| {summary['mean_abs']:.2f}, largest "
          f"{summary['largest_abs']:.2f}; mean PSNR {summary['mean_psnr']['1']:.2f} and {summary['mean_psnr']['2']:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
