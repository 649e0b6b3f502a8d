"""Diagnostic: how far a non-reciprocal NBRDF would take full. The NBRDF's second input (H_y) is always 0 (H is
rotated onto the xz-plane), so in the weight stage it can carry which order a pair came in (+1 as the table's,
-1 reversed) without changing the decoded NBRDF's output: its first-layer weights on that input are zeroed first.
The refined NBRDF is then rendered with the same flag. Samples in both orders (truth_samples) either way.

    PYTHONPATH=python python research/results/real/both-orders/diagnostics/orientation_input.py OUT.json \
        ../shared/data/rgl-measured/*.bsdf
"""
import dataclasses
import sys
from pathlib import Path

import numpy as np
import torch

import frenbrdf.models.nbrdf as N
import frenbrdf.models.reconstruct as R
import frenbrdf.render.renderer as renderer
from frenbrdf.io.atomic import save_json
from frenbrdf.io.measured import read_truth
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, sample_bins, truth_samples
from frenbrdf.numerics.coords import half_diff_vectors

original_coordinates, original_mapped, original_refine = N.nbrdf_coordinates, R.mapped_samples, R._refine_weights
STATE = {"orientation": None}


def orientation(wi, wo):
    _, d = half_diff_vectors(np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64))
    x, y = d[..., 0], d[..., 1]
    return np.where((y < 0) | ((y == 0) & (x < 0)), -1.0, 1.0)


def flagged_coordinates(wi, wo, ordered=False):
    coords = original_coordinates(wi, wo)
    coords[..., 1] = orientation(wi, wo)
    return coords


def remembering_mapped(mapping, values, directions):
    STATE["orientation"] = orientation(*directions)
    return original_mapped(mapping, values, directions)


def flagged_refine(params, samples, loss, config, result):
    params = [p.clone() for p in params]
    params[0][:, :, 1] = 0  # the input was 0 everywhere: zeroing its weights changes no output
    coords = samples.coords.clone()
    coords[0, :, 1] = torch.from_numpy(STATE["orientation"].astype(np.float32))
    return original_refine(params, R._Samples(coords, samples.values, samples.cos_in), loss, config, result)


def run(model, drawn, scene, config, flag):
    R.mapped_samples, R._refine_weights = (remembering_mapped, flagged_refine) if flag else (original_mapped, original_refine)
    N.nbrdf_coordinates = flagged_coordinates if flag else original_coordinates
    renderer._nbrdf_inputs.cache_clear()
    try:
        result = R.reconstruct(model, *drawn, refine=config)
        return tonemap(render_linear(result.nbrdf, scene))
    finally:
        N.nbrdf_coordinates, R.mapped_samples, R._refine_weights = original_coordinates, original_mapped, original_refine
        renderer._nbrdf_inputs.cache_clear()


def main():
    out, files = sys.argv[1], sys.argv[2:]
    model, scene = load_model("pretrained"), Scene(resolution=256)
    mask = material_mask(scene)
    rows = {}
    for f in files:
        truth = read_truth(Path(f))
        table, truth_image = truth.table(), tonemap(render_linear(truth, scene))
        for draw in (0, 1, 2):
            rng = np.random.default_rng(draw)
            drawn = truth_samples(truth, sample_bins(table, rng, 4000), rng)
            config = dataclasses.replace(refine_config("full"), seed=draw, keep_order=False)  # the patch orders
            for name, flag in (("reciprocal", False), ("order input", True)):
                m = image_metrics(truth_image, run(model, drawn, scene, config, flag), mask)
                rows.setdefault(Path(f).stem, {}).setdefault(name, []).append({"psnr": m["psnr"], "delta_e": m["delta_e"], "s": 0})
                print(Path(f).stem, draw, name, round(m["psnr"], 2), round(m["delta_e"], 3), flush=True)
    save_json(out, rows)  # atomically


if __name__ == "__main__":
    main()
