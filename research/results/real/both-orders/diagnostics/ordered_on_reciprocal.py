"""Diagnostic (the rule in ordered-rule.md): full with keep_order True against False on reciprocal materials sampled
in both orders: the 7 RGL fits version 4 never trained on, as their published NBRDFs.

    PYTHONPATH=python python research/results/real/both-orders/diagnostics/ordered_on_reciprocal.py OUT.json \
        ../shared/data/rgl-nbrdf/{cm_white,colodur_connemara_4c,paper_green,paper_red,ilm_l3_37_metallic,paper_blue,vch_frozen_amethyst}_rgb.h5
"""
import dataclasses
import sys
from pathlib import Path

import numpy as np

from frenbrdf.io.atomic import save_json
from frenbrdf.data.materials import load_material_file
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction, sample_bins, truth_samples

out, files = sys.argv[1], sys.argv[2:]
model, scene = load_model("pretrained"), Scene(resolution=256)
mask = material_mask(scene)
rows = {}
for f in files:
    fit = load_material_file(Path(f))
    table, truth_image = fit.merl_table(), tonemap(render_linear(fit, scene))
    for draw in (0, 1, 2):
        rng = np.random.default_rng(draw)
        drawn = truth_samples(fit, sample_bins(table, rng, 4000), rng)
        for name, keep in (("reciprocal", False), ("ordered", True)):
            config = dataclasses.replace(refine_config("full"), seed=draw, keep_order=keep)
            result, image, seconds = refined_reconstruction(model, drawn, scene, config)
            assert result.nbrdf.ordered == keep
            m = image_metrics(truth_image, image, mask)
            rows.setdefault(Path(f).stem, {}).setdefault(name, []).append(
                {"psnr": m["psnr"], "delta_e": m["delta_e"], "s": seconds})
            print(Path(f).stem, draw, name, round(m["psnr"], 2), round(m["delta_e"], 3), flush=True)
save_json(out, rows)  # atomically
