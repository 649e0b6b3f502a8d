"""How much of the encoder's gap through a device is its `best-fit` choice? (issue 47; decides nothing by itself)

    python research/studies/encoder_choice.py MATERIALS... --out DIR [--patterns ...] [--count 1500] [--draws 0 1]

For each material and pattern, the shipped model's encoders each give a latent; each is decoded and rendered, and
its render PSNR / ΔE against the truth's is recorded beside the losses the choice reads: the samples' plain
reconstruction loss (what `best-fit` takes today) and the same loss with each sample weighted by its coverage
(:func:`frenbrdf.models.coverage.coverage_weights`, k = ``--coverage``, the weights `latent` applies through a
device). Written: ``DIR/rows.json`` (one row per material, pattern and encoder) and ``DIR/summary.md``: per
pattern, the plain choice, the coverage-weighted choice, the mean of the encoders' latents and the best encoder
each material could have had (the oracle, which reads the truth: a bound, not a method).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

from frenbrdf import Model
from frenbrdf.io.atomic import write_text
from frenbrdf.material.outputs import DEVICE_COVERAGE_K
from frenbrdf.models.coverage import coverage_weights
from frenbrdf.models.losses import LossConfig, samples_loss
from frenbrdf.models.nbrdf import mapped_samples
from frenbrdf.render import Scene, material_mask, render_linear, tonemap

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pattern_readings import readings  # noqa: E402

PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


@torch.no_grad()
def member_rows(model: Model, values, directions, coverage_k: int) -> list[dict]:
    """Each encoder's latent and its decoding's plain and coverage-weighted loss on the samples."""
    encoding = model.encoding(values, directions)
    mapped, coords, cos_in = mapped_samples(model.mapping, values, directions)
    at, truth, cos = (torch.from_numpy(a.astype(np.float32))[None] for a in (coords, mapped, cos_in))
    weights = torch.from_numpy(coverage_weights(*directions, coverage_k).astype(np.float32))[None]
    kind = model.loss.get("kind", LossConfig.kind)
    rows = []
    for index, z in enumerate(encoding.latents):
        params = model.network.decoder(torch.from_numpy(z.astype(np.float32))[None])
        rows.append({"encoder": index, "z": z,
                     "loss": float(samples_loss(params, at, truth, cos, kind)),
                     "coverage_loss": float(samples_loss(params, at, truth, cos * weights, kind))})
    return rows


def summarise(rows: list[dict], patterns) -> str:
    lines = ["| pattern | plain `best-fit` | coverage-weighted choice | mean of latents | oracle (reads the truth) |",
             "|---|---|---|---|---|"]
    for name in patterns:
        here = [r for r in rows if r["pattern"] == name]
        materials = sorted({r["material"] for r in here})
        picks = {key: [] for key in ("plain", "coverage", "mean", "oracle")}
        for material in materials:
            for draw in sorted({r["draw"] for r in here}):
                group = [r for r in here if r["material"] == material and r["draw"] == draw]
                members = [r for r in group if r["encoder"] != "mean"]
                picks["plain"].append(min(members, key=lambda r: r["loss"]))
                picks["coverage"].append(min(members, key=lambda r: r["coverage_loss"]))
                picks["mean"].append(next(r for r in group if r["encoder"] == "mean"))
                picks["oracle"].append(max(members, key=lambda r: r["psnr"]))
        cells = [f"{np.mean([r['psnr'] for r in p]):.2f} / {np.mean([r['delta_e'] for r in p]):.2f}"
                 for p in picks.values()]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("materials", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--patterns", nargs="+", default=list(PATTERNS))
    parser.add_argument("--count", type=int, default=1500)
    parser.add_argument("--draws", type=int, nargs="+", default=[0])
    parser.add_argument("--coverage", type=int, default=DEVICE_COVERAGE_K)
    parser.add_argument("--resolution", type=int, default=128)
    args = parser.parse_args(argv)
    model = Model.pretrained()
    scene = Scene(resolution=args.resolution)
    mask = material_mask(scene)
    rows = []
    for reading in readings(args.materials, args.patterns, args.draws, args.count, scene, mask):
        members = member_rows(model, reading.values, reading.directions, args.coverage)
        members.append({"encoder": "mean", "z": np.mean([m["z"] for m in members], axis=0),
                        "loss": float("nan"), "coverage_loss": float("nan")})
        for member in members:
            metrics = reading.metrics(tonemap(render_linear(model.decode(member.pop("z"))[0], scene)), mask)
            rows.append({"material": reading.material, "pattern": reading.pattern, "draw": reading.draw, **member,
                         "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]})
    args.out.mkdir(parents=True, exist_ok=True)
    write_text(args.out / "rows.json", json.dumps(rows, indent=1) + "\n")
    summary = summarise(rows, args.patterns)
    write_text(args.out / "summary.md", summary)
    print(summary)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
