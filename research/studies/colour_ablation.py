"""The colour ablation of research/colour.md: one variant of a method preset, trained and measured.

    python research/studies/colour_ablation.py NAME --data bank/ [--method frenbrdf] [--over JSON] [--seed S]
        [--training demo] [--latent-steps 300] [--ood merl/ --ood-every 4] [--work colour-ablation/]

Trains ``--method``'s preset with ``--over`` (nested TrainConfig keys as JSON, e.g.
``'{"model": {"decoder": {"last_layer_scale": 1.0}}}'``) at the ``--training`` length, on one
torch thread, into ``WORK/NAME-sS/`` (a finished run is reused), then measures every test
material at 128² over the lit pixels: PSNR and mean CIEDE2000 ΔE of the encoder's latent
and, with ``--latent-steps N``, of the latent optimised on the same samples with the decoder
frozen (:func:`frenbrdf.models.reconstruct.reconstruct`, stage 1 only): where even that latent
decodes to the wrong hue the decoder cannot represent the colour, where it decodes right the
encoder failed to find it. With ``--ood DIR``, every ``--ood-every``-th material of another folder
(by name) is measured too, encoder only (out of distribution). Writes ``WORK/NAME-sS/ablation.json``
and prints one line.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from frenbrdf.configs import from_dict, merge, to_dict
from frenbrdf.data.folders import list_materials
from frenbrdf.io.atomic import save_json
from frenbrdf.io.merl import N_BINS, read_merl
from frenbrdf.io.sampling import bin_directions, sample_bins
from frenbrdf.models.reconstruct import RefineConfig, reconstruct
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, reconstruction_rows
from frenbrdf.training import Run, TrainConfig, config_for, train


def measure(run: Run, data: Path, latent_steps: int, samples: int = 4000, seed: int = 0) -> list[dict]:
    """Per test material: display-mean RGB, PSNR and ΔE of the encoder's latent (and of the optimised one)."""
    model, scene = run.model(), Scene(resolution=128)
    mask, rng = material_mask(scene), np.random.default_rng(seed)
    rows = []
    for name in run.split.test:
        table = read_merl(data / f"{name}.binary")
        bins = sample_bins(table, rng, samples)
        values, directions = table.reshape(3, N_BINS)[:, bins].T, bin_directions(bins)
        truth = tonemap(render_linear(table, scene))
        row = {"material": name, "truth_rgb": truth[mask].mean(0).round(3).tolist()}
        latents = {"encoder": model.encode(values, directions)}
        if latent_steps:
            refine = RefineConfig(latent_steps=latent_steps, seed=seed)
            latents["optimised"] = reconstruct(model, values, directions, refine=refine).z
        for label, z in latents.items():
            image = tonemap(render_linear(model.decode(z)[0], scene))
            metrics = image_metrics(truth, image, mask)
            row[label] = {"psnr": metrics["psnr"], "delta_e": metrics["delta_e"],
                          "rgb": image[mask].mean(0).round(3).tolist()}
        rows.append(row)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("name")
    parser.add_argument("--data", required=True, help="folder of MERL files")
    parser.add_argument("--method", default="frenbrdf")
    parser.add_argument("--over", default="{}", help="nested TrainConfig keys (JSON) over the preset")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--training", default="demo", help="a training length of frenbrdf.presets.TRAINING")
    parser.add_argument("--latent-steps", type=int, default=0, help="also optimise the latent this many steps")
    parser.add_argument("--ood", help="also measure materials of this folder (out of distribution), encoder only")
    parser.add_argument("--ood-every", type=int, default=4, help="every N-th material of --ood by name (default 4)")
    parser.add_argument("--work", default="colour-ablation", help="folder of the runs")
    args = parser.parse_args()
    torch.set_num_threads(1)

    out = Path(args.work) / f"{args.name}-s{args.seed}"
    cfg = config_for(args.method, training=args.training, data=args.data, out=str(out), seed=args.seed,
                     progress=False)
    cfg = from_dict(TrainConfig, merge(to_dict(cfg), json.loads(args.over), TrainConfig), args.name)
    start = time.perf_counter()
    if not (out / "best.pt").exists():
        train(cfg, overwrite=True)  # its own work folder
    seconds = time.perf_counter() - start
    rows = measure(Run(out), Path(args.data), args.latent_steps, seed=args.seed)
    summary = {label: {metric: float(np.mean([r[label][metric] for r in rows])) for metric in ("psnr", "delta_e")}
               for label in ("encoder", "optimised") if label in rows[0]}
    if args.ood:
        ood = reconstruction_rows(Run(out).model(), list_materials(args.ood)[::args.ood_every], resolution=128,
                                  frequency_metric=False, progress=False)
        summary["out of distribution"] = {metric: float(np.mean([r[metric] for r in ood]))
                                          for metric in ("psnr", "delta_e")}
        rows += [{"material": r["material"], "out of distribution": r} for r in ood]
    save_json(out / "ablation.json", {"name": args.name, "seed": args.seed, "method": args.method, "over": args.over,
                                      "train_seconds": seconds, "summary": summary, "materials": rows})
    print(f"{args.name} seed {args.seed}: " + "; ".join(
        f"{label} PSNR {s['psnr']:.2f} ΔE {s['delta_e']:.2f}" for label, s in summary.items()), flush=True)


if __name__ == "__main__":
    main()
