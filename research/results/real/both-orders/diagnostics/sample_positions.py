"""Diagnostic: full from 4000 samples at the bins (the table's values), at random points inside each bin
(jitter), or at the bins in a random order of each pair (swap, the forerunner of truth_samples); values of
jitter and swap from the .bsdf itself."""
import sys, dataclasses, numpy as np
from pathlib import Path
from frenbrdf.io.atomic import save_json
from frenbrdf.io.measured import as_table, read_truth
from frenbrdf.io.merl import SHAPE, merl_bin_to_angles
from frenbrdf.numerics.coords import rusinkiewicz_to_directions
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config, reconstruct
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, sample_bins, bin_directions

def jittered(table, truth, rng, n):
    out_wi, out_wo = [], []
    got = 0
    while got < n:
        bins = sample_bins(table, rng, n)
        idx = np.stack(np.unravel_index(bins, SHAPE[1:]), -1).astype(float) + rng.uniform(0, 1, (len(bins), 3))
        ang = merl_bin_to_angles(idx)
        rus = np.stack([ang[:, 0], rng.uniform(0, 2 * np.pi, len(bins)), ang[:, 1], ang[:, 2]], -1)
        wi, wo = rusinkiewicz_to_directions(rus)
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        out_wi.append(wi[ok]); out_wo.append(wo[ok]); got += ok.sum()
    wi, wo = np.concatenate(out_wi)[:n], np.concatenate(out_wo)[:n]
    return np.maximum(truth(wi, wo), 0), (wi, wo)

scene = Scene(resolution=256); mask = material_mask(scene)
model = load_model("pretrained")
rows = {}
modes = sys.argv[1].split(","); out = sys.argv[2]
for f in sys.argv[3:]:
    truth = read_truth(Path(f)); table = as_table(truth)
    ti = tonemap(render_linear(truth, scene))
    for draw in (0, 1, 2):
        for mode in modes:
            rng = np.random.default_rng(draw)
            if mode == "bins":
                bins = sample_bins(table, rng, 4000)
                values, dirs = table.reshape(3, -1)[:, bins].T, bin_directions(bins)
            elif mode == "swap":
                bins = sample_bins(table, rng, 4000)
                wi, wo = bin_directions(bins)
                flip = rng.random(len(bins)) < 0.5
                wi, wo = np.where(flip[:, None], wo, wi), np.where(flip[:, None], wi, wo)
                values, dirs = np.maximum(truth(wi, wo), 0), (wi, wo)
            else:
                values, dirs = jittered(table, truth, rng, 4000)
            result = reconstruct(model, values, dirs, refine=dataclasses.replace(refine_config("full"), seed=draw,
                                                                                       keep_order=False))  # as when run
            image = tonemap(render_linear(result.nbrdf, scene))
            m = image_metrics(ti, image, mask)
            rows.setdefault(Path(f).stem, {}).setdefault(mode, []).append({"psnr": m["psnr"], "delta_e": m["delta_e"], "s": sum(result.timings.values())})
            print(Path(f).stem, draw, mode, round(m["psnr"], 2), round(m["delta_e"], 3), flush=True)
save_json(out, rows)  # atomically
