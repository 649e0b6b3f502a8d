"""Diagnostic: the weight stage's per-sample weight cos_i**p."""
import sys, dataclasses, numpy as np
from pathlib import Path
from frenbrdf.io.atomic import save_json
from frenbrdf.io.measured import as_table, read_truth
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models import reconstruct as R
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction, sample_bins, truth_samples

POWER = [1.0]
_orig = R._refine_weights
def patched(params, samples, loss, config, result):
    s = R._Samples(samples.coords, samples.values, samples.cos_in.clamp(min=0) ** POWER[0])
    return _orig(params, s, loss, config, result)
R._refine_weights = patched

powers = [float(p) for p in sys.argv[1].split(",")]
out = sys.argv[2]
files = sys.argv[3:]
scene = Scene(resolution=256); mask = material_mask(scene)
model = load_model("pretrained")
rows = {}
for f in files:
    truth = read_truth(Path(f)); table = as_table(truth)
    ti = tonemap(render_linear(truth, scene))
    for draw in (0, 1, 2):
        bins = sample_bins(table, np.random.default_rng(draw), 4000)
        for p in powers:
            POWER[0] = p
            config = dataclasses.replace(refine_config("full"), seed=draw)
            result, image, _ = refined_reconstruction(model, truth_samples(table, bins, None), scene, config)  # the table's order
            m = image_metrics(ti, image, mask)
            rows.setdefault(Path(f).stem, {}).setdefault(str(p), []).append(
                {"psnr": m["psnr"], "delta_e": m["delta_e"], "s": sum(result.timings.values())})
            print(Path(f).stem, draw, p, round(m["psnr"], 2), round(m["delta_e"], 3), flush=True)
save_json(out, rows)  # atomically
