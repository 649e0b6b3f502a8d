"""Training-step time with and without augmentation: the batch drawn and one optimisation step.

    python research/studies/augment_step.py [--data DIR] [--steps 10] [--device cpu|cuda] [--method frenbrdf]

Times, interleaved, a whole step of the training loop (:class:`frenbrdf.training.augment.BatchDrawer`
drawing the batch, then :func:`frenbrdf.training.optimisation_step`) at the method's default
sizes, once per augmentation preset (``paper``: tables only; ``augmented``, the default: mixes
and colour gains; ``procedural``: also analytic materials), and the batch drawing alone. Without ``--data`` it writes 16 materials of the default synthetic bank to
a temporary folder. Writes ``bench-results/augment_step.{md,json}``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import torch

from frenbrdf.data.folders import list_materials, split_materials
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.models.autoencoder import AutoEncoder
from frenbrdf.models.losses import FrequencyLoss
from frenbrdf.presets import AUGMENTATION
from frenbrdf.training import config_for, optimisation_step, prepare
from frenbrdf.training.augment import BatchDrawer
from frenbrdf.training.loop import make_optimizer

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import material_folder  # noqa: E402
from step_timing import timed_seconds  # noqa: E402


def step_functions(method: str, augmentation: str, data: Path, device: torch.device) -> dict:
    """The batch drawing alone, and drawing + optimisation step, of one configuration."""
    cfg = config_for(method, augmentation=augmentation, data=str(data), out="", progress=False,
                     cache_dir=str(data / ".cache"))
    files = {path.stem: path for path in list_materials(data)}
    prepared = prepare(cfg, split_materials(files, cfg.seed, cfg.split), files)
    torch.manual_seed(0)
    network = AutoEncoder(cfg.model).to(device)
    frequency = FrequencyLoss(cfg.loss.frequency).to(device) if prepared.truth is not None else None
    optimizer = make_optimizer(network, cfg)
    drawer = BatchDrawer(cfg, prepared, with_truth=cfg.loss.eta > 0)
    generator = torch.Generator().manual_seed(0)
    batch = list(range(min(cfg.batch_materials, prepared.n_train)))

    def step():
        drawn = drawer.draw(batch, generator).to(device)
        optimisation_step(network, frequency, optimizer, cfg.loss, cfg.grad_clip, drawn.context, drawn.query,
                          drawn.truth, truth_mask=drawn.truth_mask)

    return {f"{augmentation} step": step, f"{augmentation} draw": lambda: drawer.draw(batch, generator)}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--method", default="frenbrdf")
    parser.add_argument("--out", type=Path, default=Path("bench-results"))
    args = parser.parse_args()
    device = torch.device(args.device)
    with tempfile.TemporaryDirectory() as scratch:
        data = material_folder(args.data, scratch)
        functions = {}
        for name in AUGMENTATION:
            functions.update(step_functions(args.method, name, data, device))
        seconds = timed_seconds(functions, args.steps, device)
    lines = [f"{args.method} training step at default sizes on {device} (torch threads: {torch.get_num_threads()}), "
             f"median of {args.steps} steps, batch drawing included.", "",
             "| augmentation | step (ms) | of which drawing the batch (ms) |", "|---|---|---|"]
    for name in AUGMENTATION:
        lines.append(f"| {name} | {1e3 * seconds[f'{name} step']:.0f} | {1e3 * seconds[f'{name} draw']:.0f} |")
    args.out.mkdir(parents=True, exist_ok=True)
    write_text(args.out / "augment_step.md", "\n".join(lines) + "\n")
    save_json(args.out / "augment_step.json", {"method": args.method, "device": str(device), "steps": args.steps,
                                               "seconds": seconds})
    print("\n".join(lines))


if __name__ == "__main__":
    main()
