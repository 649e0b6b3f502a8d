"""Seconds of a refinement budget on real measurements, this tree against earlier commits, in one run.

    python research/studies/refine_timing.py ../shared/data/rgl-measured/*.bsdf --against 0e6fb5a

Each measurement's ``--samples`` random valid bins (draw 0, as ``real_measurements.py`` draws them) are
reconstructed with ``--budget`` by this tree's ``frenbrdf.models.reconstruct`` and by the same module as it
was at each ``--against`` commit (read with ``git show``, the rest of the package this tree's), interleaved,
``--repeats`` times after one untimed warm-up; the best of the repeats per material, then the mean over the
materials. Each module runs its own ``--budget``, or that budget with ``--width`` and ``--weight-steps`` (the
same work in every module, where budgets changed between the commits). Threads: torch's default unless
``--threads`` (the native weight stage's: ``RAYON_NUM_THREADS``). A speed comparison, not a quality one: the
final sample loss is printed only to show that the variants did the same work.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from frenbrdf.io import read_material
from frenbrdf.io.sampling import as_table, sample_bins, truth_samples
from frenbrdf.models import reconstruct as this_tree
from frenbrdf.models.autoencoder import load_model

MODULE = "python/frenbrdf/models/reconstruct.py"


def module_at(commit: str, folder: Path):
    """``frenbrdf.models.reconstruct`` as it was at ``commit`` (its relative imports resolve in this tree)."""
    root = Path(__file__).resolve().parents[2]
    source = subprocess.run(["git", "show", f"{commit}:{MODULE}"], cwd=root, capture_output=True, text=True)
    if source.returncode:
        raise SystemExit(f"cannot read {MODULE} at {commit}: {source.stderr.strip()}")
    path = folder / f"reconstruct_{commit}.py"
    path.write_text(source.stdout)
    spec = importlib.util.spec_from_file_location(f"frenbrdf.models._reconstruct_{commit}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files (or MERL tables)")
    parser.add_argument("--model", default="pretrained")
    parser.add_argument("--budget", default="full", choices=tuple(this_tree.BUDGETS))
    parser.add_argument("--against", nargs="*", default=[],
                        help="commits whose reconstruct.py to time beside this tree's")
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, help="torch threads (default: torch's)")
    parser.add_argument("--width", type=int, help="override the budget's NBRDF width in every module")
    parser.add_argument("--weight-steps", type=int, help="override the budget's weight steps in every module")
    args = parser.parse_args(argv)
    overrides = {key: value for key, value in (("width", args.width), ("weight_steps", args.weight_steps))
                 if value is not None}
    if args.threads:
        torch.set_num_threads(args.threads)
    model = load_model(args.model)
    inputs = []
    for path in map(Path, args.measurements):
        truth, rng = read_material(path), np.random.default_rng(0)
        inputs.append((path.stem, *truth_samples(truth, sample_bins(as_table(truth), rng, args.samples), rng)))
    with tempfile.TemporaryDirectory() as folder:
        variants = {"this tree": this_tree, **{commit: module_at(commit, Path(folder)) for commit in args.against}}
        configs = {label: dataclasses.replace(module.refine_config(args.budget), **overrides)
                   for label, module in variants.items()}
        name, values, directions = inputs[0]
        for label, module in variants.items():  # warm-up: thread pools and caches
            module.reconstruct(model, values[:100], tuple(d[:100] for d in directions), refine=configs[label])
        best = {label: {} for label in variants}
        for _ in range(args.repeats):
            for name, values, directions in inputs:
                for label, module in variants.items():
                    start = time.perf_counter()
                    result = module.reconstruct(model, values, directions, refine=configs[label])
                    seconds = time.perf_counter() - start
                    best[label][name] = min(best[label].get(name, np.inf), seconds)
                    final_loss = list(result.losses.values())[-1]
                    print(f"{label:>12}  {name:<28} {seconds:6.3f} s  final loss {final_loss:.5f}", flush=True)
    print(f"\n{args.budget} {overrides or ''}, {args.samples} samples, {torch.get_num_threads()} threads, best of "
          f"{args.repeats}:")
    for label, seconds in best.items():
        print(f"{label:>12}  mean {np.mean(list(seconds.values())):.3f} s  "
              + "  ".join(f"{name} {value:.3f}" for name, value in seconds.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
