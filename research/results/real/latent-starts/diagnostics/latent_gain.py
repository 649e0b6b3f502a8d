"""Diagnostic: `latent` with a per-channel shift of the decoded NBRDF's last bias beside z (a colour gain in the
mapped space), against z alone; the four measurements, draws 0-2, 200 cosine steps from 3e-2, full batch.

    OMP_NUM_THREADS=2 python research/results/real/latent-starts/diagnostics/latent_gain.py \
        > research/results/real/latent-starts/diagnostics/latent_gain.txt
"""

from pathlib import Path

import numpy as np
import torch

from frenbrdf.io.measured import read_truth
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.losses import reconstruction_loss
from frenbrdf.models.nbrdf import NBRDF, mapped_samples, nbrdf_forward
from frenbrdf.models.reconstruct import _learning_rates, _loss_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, sample_bins, truth_samples
from frenbrdf.evaluation.statistics import paired_interval

MEASUREMENTS = Path(__file__).resolve().parents[6] / "shared" / "data" / "rgl-measured"  # ../shared beside the checkout
STEPS, LR = 200, 3e-2

model = load_model("pretrained")
loss = _loss_config(model)
scene = Scene(resolution=256)
mask = material_mask(scene)
psnr = {"z": [], "z+gain": []}


def decoded(z, shift):
    params = list(model.network.decoder(z))
    params[-1] = params[-1] + shift  # the mapped output is ln((f + ε)/(f_ref + ε)): a shift is a gain
    return params


for path in sorted(MEASUREMENTS.glob("*.bsdf")) or exit(f"no .bsdf files in {MEASUREMENTS}"):
    truth = read_truth(path)
    truth_image = tonemap(render_linear(truth, scene))
    for draw in (0, 1, 2):
        rng = np.random.default_rng(draw)
        drawn = truth_samples(truth, sample_bins(truth.table(), rng, 4000), rng)
        mapped, coords, cos_in = (torch.from_numpy(np.asarray(a, dtype=np.float32))[None]
                                  for a in mapped_samples(model.mapping, *drawn))
        start = torch.from_numpy(model.encode(*drawn).astype(np.float32))[None]
        for variant in psnr:
            z, shift = start.clone().requires_grad_(True), torch.zeros(1, 3, requires_grad=True)
            optimiser = torch.optim.Adam([z, shift] if variant == "z+gain" else [z], lr=LR)
            for lr in _learning_rates(LR, STEPS, "cosine"):
                for group in optimiser.param_groups:
                    group["lr"] = float(lr)
                predicted = nbrdf_forward(decoded(z, shift), coords)
                objective = (reconstruction_loss(predicted, mapped, cos_in, loss.kind)
                             + loss.lambda_latent * (z ** 2).mean())
                optimiser.zero_grad()
                objective.backward()
                optimiser.step()
            with torch.no_grad():
                nbrdf = NBRDF([p.detach() for p in decoded(z, shift)], model.mapping)
            metrics = image_metrics(truth_image, tonemap(render_linear(nbrdf, scene)), mask)
            psnr[variant].append(metrics["psnr"])
            print(path.stem, draw, variant, f"{metrics['psnr']:.2f} dB, ΔE {metrics['delta_e']:.2f}, gain shift",
                  shift.detach().numpy().round(3).tolist(), flush=True)
change = paired_interval(np.array(psnr["z+gain"]) - np.array(psnr["z"]))
print(f"z {np.mean(psnr['z']):.2f} dB, z+gain {np.mean(psnr['z+gain']):.2f} dB, change {change['mean']:+.2f} "
      f"[{change['low']:+.2f}, {change['high']:+.2f}] over {change['n']} pairs")
