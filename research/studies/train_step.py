"""Training-step time of each method at default settings, and the share of L_fre.

    python research/studies/train_step.py [--data DIR] [--steps 20] [--device cpu|cuda]

Without ``--data`` it writes 16 materials of the default synthetic bank to a temporary
folder. For FreNBRDF it times the same step with and without the frequency term (same
model, same samples), so the difference is what L_fre adds; it also times the parts of
L_fre alone. Writes ``bench-results/train_step.{md,json}``.

    python research/studies/train_step.py --variants paper no-floor tone highlights [--data DIR]

times the FreNBRDF step with each L_fre variant (:data:`frenbrdf.presets.FREQUENCY_VARIANTS`) and without
L_fre, interleaved in the same minutes (fastest of ``--steps`` each), and writes
``bench-results/train_step_variants.{md,json}`` with each variant's cost relative to the first.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import torch

from frenbrdf.models.losses import frequency_variant
from frenbrdf.training import config_for

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import material_folder, run_metadata  # noqa: E402
from step_timing import time_frequency_variants, time_training_step  # noqa: E402


def time_method(method: str, data: Path, steps: int, device: torch.device, slices=None) -> dict:
    """One method's preset, timed by ``step_timing.time_training_step`` (``benches/step_timing.py``, shared with
    chart 2)."""
    cfg = config_for(method, data=str(data), out="", progress=False, cache_dir=str(data / ".cache"))
    if slices is not None:
        cfg.loss.frequency.slices = slices
    return time_training_step(cfg, steps, device)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--slices", help="θ_h bin indices of the L_fre slices, e.g. 0,24,48,72 (default: the config's)")
    parser.add_argument("--out", type=Path, default=Path("bench-results"))
    parser.add_argument("--variants", nargs="+", help="time these L_fre variants against each other instead")
    args = parser.parse_args()
    device = torch.device(args.device)
    if args.variants:
        return time_variants(args, device)
    with tempfile.TemporaryDirectory() as scratch:
        data = material_folder(args.data, scratch)
        slices = tuple(int(i) for i in args.slices.split(",")) if args.slices else None
        results = [time_method(method, data, args.steps, device, slices) for method in ("frenbrdf", "nbrdf", "hyperbrdf")]
    lines = [f"Training step at default settings on {device} (torch threads: {torch.get_num_threads()}), "
             f"median of {args.steps} steps; L_fre slices: {args.slices or 'default'}.", "",
             "| method | NBRDF | step (ms) | without L_fre (ms) | L_fre adds |", "|---|---|---|---|---|"]
    for r in results:
        without = f"{1e3 * r['step_without_fre_s']:.1f}" if "step_without_fre_s" in r else "–"
        share = f"{100 * r['fre_added_share']:.0f} %" if "fre_added_share" in r else "–"
        lines.append(f"| {r['method']} | 6→{'→'.join(map(str, r['nbrdf_hidden']))}→3 | {1e3 * r['step_s']:.1f} | "
                     f"{without} | {share} |")
    fre = results[0]
    lines += ["", f"L_fre alone: NBRDF at the grid nodes {1e3 * fre['fre_nbrdf_eval_s']:.1f} ms; "
                  f"forward + backward (incl. SHT and its adjoint) {1e3 * fre['fre_forward_backward_s']:.1f} ms."]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "train_step.md").write_text("\n".join(lines) + "\n")
    (args.out / "train_step.json").write_text(json.dumps(results, indent=2) + "\n")
    print("\n".join(lines))


def time_variants(args, device: torch.device) -> None:
    """The FreNBRDF step with each L_fre variant and without L_fre, interleaved; ratios to the first variant."""
    with tempfile.TemporaryDirectory() as scratch:
        data = material_folder(args.data, scratch)
        cfg = config_for("frenbrdf", data=str(data), out="", progress=False, cache_dir=str(Path(scratch) / "cache"))
        seconds = time_frequency_variants(cfg, {name: frequency_variant(name) for name in args.variants}, args.steps,
                                          device)
    first, without = seconds[args.variants[0]], seconds["without L_fre"]
    lines = [f"Training step of the frenbrdf preset on {device} (torch threads: {torch.get_num_threads()}), fastest of "
             f"{args.steps} interleaved steps, {cfg.batch_materials} materials × {cfg.context_samples} + "
             f"{cfg.query_samples} samples; data: {args.data or 'the default bank (16 materials)'}.", "",
             f"| L_fre variant | step (ms) | vs {args.variants[0]} | vs no L_fre |", "|---|---|---|---|"]
    lines += [f"| {name} | {1e3 * value:.1f} | {value / first:.2f}× | {value / without - 1:+.0%} |"
              for name, value in seconds.items()]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "train_step_variants.md").write_text("\n".join(lines) + "\n")
    (args.out / "train_step_variants.json").write_text(json.dumps(
        {"seconds": seconds, "steps": args.steps, "device": str(device), "run": run_metadata()}, indent=2) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
