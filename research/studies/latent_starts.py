"""Does `latent` reach further from other starting points than the encoder's z?

    python research/studies/latent_starts.py ../shared/data/rgl-measured/*.bsdf --tables local/v4/work/data \
        --draws 0 1 2 --out research/results/real/latent-starts

The latent space's best point on a measurement might be a local minimum the encoder's z happens to lie
near. For each measurement and draw (the samples real_measurements.py draws), the shipped model's
``latent`` budget (200 steps) runs from the encoder's z and from the latents of the ``--starts`` tables
whose decoded NBRDFs fit the samples best before any step (each table of ``--tables``, the model's
training data, encoded from 4000 of its own samples); the start whose result fits the samples best is
chosen, as a multi-start ``latent`` would choose. Writes ``starts.json`` and ``starts.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from frenbrdf.data.folders import list_materials
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.sampling import sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.nbrdf import mapped_samples
from frenbrdf.models.reconstruct import _loss_config, _sample_loss, _Samples, refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parents[2] / "benches")]  # benches/
from common import run_metadata  # noqa: E402


def bank_latents(model, tables: Path, seed: int = 123) -> dict[str, np.ndarray]:
    """Each table's latent, encoded from 4000 of its own samples."""
    rng = np.random.default_rng(seed)
    latents = {}
    for path in tqdm(list_materials(tables), desc="bank", leave=False):
        table = read_material(path)
        latents[path.stem] = model.encode(*truth_samples(table, sample_bins(table, rng, 4000), rng))
    return latents


def fit_loss(model, z: np.ndarray, samples: _Samples) -> float:
    with torch.no_grad():
        params = model.network.decoder(torch.from_numpy(z.astype(np.float32))[None])
    return _sample_loss(params, samples, _loss_config(model).kind)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("measurements", nargs="+", type=Path, help=".bsdf files")
    parser.add_argument("--tables", type=Path, required=True, help="the model's training tables (MERL files)")
    parser.add_argument("--starts", type=int, default=4, help="bank latents to start from besides the encoder's z")
    parser.add_argument("--draws", type=int, nargs="+", default=[0])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = load_model("pretrained")
    bank = bank_latents(model, args.tables)
    held_out = {path.stem for path in args.measurements} & set(bank)
    if held_out:
        sys.exit(f"--tables holds fits of the measurements themselves: {sorted(held_out)}")
    scene = Scene(resolution=256)
    mask = material_mask(scene)
    config = dataclasses.replace(refine_config("latent"), progress=False)
    encode = model.encode
    rows = []
    for path in args.measurements:
        truth = read_material(path)
        truth_image = tonemap(render_linear(truth, scene))
        for draw in args.draws:
            rng = np.random.default_rng(draw)
            drawn = truth_samples(truth, sample_bins(truth.table(), rng, 4000), rng)
            mapped, coords, cos_in = mapped_samples(model.mapping, *drawn)
            samples = _Samples(*(torch.from_numpy(np.asarray(a, dtype=np.float32))[None]
                                 for a in (coords, mapped, cos_in)))
            nearest = sorted(bank, key=lambda name: fit_loss(model, bank[name], samples))[:args.starts]
            results = {}
            for start in ["encoder", *nearest]:
                if start != "encoder":
                    model.encode = lambda values, directions, z=bank[start]: z
                try:
                    result, image, _ = refined_reconstruction(model, drawn, scene,
                                                              dataclasses.replace(config, seed=draw))
                finally:
                    model.encode = encode
                results[start] = {"loss": result.losses["latent"], **image_metrics(truth_image, image, mask)}
            chosen = min(results, key=lambda start: results[start]["loss"])
            rows.append({"material": path.stem, "draw": draw, "chosen": chosen, "starts": results})
            print(path.stem, draw, {k: round(v["psnr"], 2) for k, v in results.items()}, "chosen:", chosen, flush=True)
    encoder = np.array([row["starts"]["encoder"]["psnr"] for row in rows])
    chosen = np.array([row["starts"][row["chosen"]]["psnr"] for row in rows])
    change = paired_interval(chosen - encoder)
    summary = {"encoder_start_psnr": float(encoder.mean()), "multi_start_psnr": float(chosen.mean()),
               "change": change, "chosen_other_than_encoder": sum(row["chosen"] != "encoder" for row in rows),
               "pairs": len(rows)}
    args.out.mkdir(parents=True, exist_ok=True)
    save_json(args.out / "starts.json", {"run": run_metadata(), "starts": args.starts, "summary": summary,
                                         "rows": rows})
    lines = ["| material | draw | from the encoder's z | best other start | chosen by sample loss |",
             "|---|---|---|---|---|"]
    for row in rows:
        others = {k: v for k, v in row["starts"].items() if k != "encoder"}
        best = max(others, key=lambda k: others[k]["psnr"])
        lines.append(f"| {row['material']} | {row['draw']} | {row['starts']['encoder']['psnr']:.2f} | "
                     f"{others[best]['psnr']:.2f} ({best}) | {row['chosen']} |")
    lines.append(f"\nMeans: from the encoder's z {encoder.mean():.2f} dB, multi-start {chosen.mean():.2f} dB, "
                 f"change {change['mean']:+.2f} [{change['low']:+.2f}, {change['high']:+.2f}] over {len(rows)} pairs.")
    write_text(args.out / "starts.md", "\n".join(lines) + "\n")
    print(lines[-1])


if __name__ == "__main__":
    main()
