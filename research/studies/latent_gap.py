"""Why does `latent` through a device's pairs stay below `latent` from random bins: the search, or the samples?

    python research/studies/latent_gap.py --tables DATA/*.binary --measurements ../shared/data/rgl-measured/*.bsdf \
        --out research/results/latent-gap

`latent` minimises the loss on the samples it is given. Through a device's pairs (1,500) it ends several dB below
what it reaches from random bins. Two causes give that gap, and they call for different remedies:

- **search**: the samples' own loss has a lower point near the material's best latent, but the steps from the
  encoder's z do not get there (better starts, more steps would help);
- **information**: the samples' loss is lower at a latent that renders worse than the material's best one, so
  fitting those samples better cannot close the gap (only a prior, or pairs that see more, can).

For each material the study finds a *reference* latent, `latent` on ``--reference-samples`` random bins (the
latent space's best reach on that material, near enough), and for each pattern's samples compares three latents
on those samples' loss and on the render: `latent` from the encoder's z (what a user gets), the reference
itself, and `latent` on the pattern's samples *started from the reference*. Per pattern it counts the search
cases (the reference, or `latent` started from it, fits the pattern's samples better than the user's result) and
how far the start from the reference drifts in the render when the pattern's samples pull on it (information).

Writes ``gap.json`` (every material × pattern) and ``gap.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.nbrdf import mapped_samples
from frenbrdf.models.reconstruct import _loss_config, _Record, _refine_latent, _sample_loss, _Samples, refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]
from compare_models import condition_rng  # noqa: E402

from common import run_metadata  # noqa: E402

PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
LATENTS = ("user", "reference", "from reference")


def tensors(model, drawn) -> _Samples:
    """The samples as :func:`frenbrdf.models.reconstruct.reconstruct` holds them."""
    mapped, coords, cos_in = mapped_samples(model.mapping, *drawn)
    return _Samples(*(torch.from_numpy(np.asarray(a, dtype=np.float32))[None] for a in (coords, mapped, cos_in)))


def refined(model, start: np.ndarray, samples: _Samples, config) -> np.ndarray:
    """Stage 1 of `latent` (the shipped budget) from ``start`` on ``samples``."""
    z, _ = _refine_latent(model, torch.from_numpy(start.astype(np.float32))[None], samples, None, _loss_config(model),
                          config, _Record())
    return z[0].numpy().astype(np.float64)


def sample_loss(model, z: np.ndarray, samples: _Samples) -> float:
    with torch.no_grad():
        params = model.network.decoder(torch.from_numpy(z.astype(np.float32))[None])
    return _sample_loss(params, samples, _loss_config(model).kind)


def material_rows(model, path: Path, args, scene: Scene, mask: np.ndarray, config) -> list[dict]:
    truth = read_material(path)
    table = as_table(truth) if isinstance(truth, np.ndarray) else None
    truth_image = tonemap(render_linear(truth, scene))

    def scored(z: np.ndarray, samples: _Samples) -> dict:
        image = tonemap(render_linear(model.decode(z)[0], scene))
        metrics = image_metrics(truth_image, image, mask)
        return {"loss": sample_loss(model, z, samples), "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]}

    dense = pattern_samples(truth, "merl-bins", args.reference_samples, condition_rng(99, "merl-bins"), table=table)
    reference = refined(model, model.encode(*dense), tensors(model, dense), config)
    rows = []
    for pattern in args.patterns:
        drawn = pattern_samples(truth, pattern, args.samples, condition_rng(0, pattern), table=table)
        samples = tensors(model, drawn)
        latents = {"user": refined(model, model.encode(*drawn), samples, config), "reference": reference,
                   "from reference": refined(model, reference, samples, config)}
        rows.append({"material": path.stem, "pattern": pattern,
                     **{name: scored(z, samples) for name, z in latents.items()}})
    return rows


def summary(rows: list[dict]) -> list[dict]:
    """Per pattern: mean PSNR of each latent, the search cases and the drift from the reference."""
    out = []
    for pattern in dict.fromkeys(row["pattern"] for row in rows):
        mine = [row for row in rows if row["pattern"] == pattern]
        psnr = {name: np.array([row[name]["psnr"] for row in mine]) for name in LATENTS}
        searched = [row["reference"]["loss"] < row["user"]["loss"] for row in mine]
        other_minimum = [row["from reference"]["loss"] < row["user"]["loss"] for row in mine]
        out.append({"pattern": pattern, "materials": len(mine),
                    **{f"{name} psnr": float(values.mean()) for name, values in psnr.items()},
                    "reference fits better": int(sum(searched)),
                    "from reference fits better": int(sum(other_minimum)),
                    "reference - user": paired_interval(psnr["reference"] - psnr["user"]),
                    "drift": paired_interval(psnr["from reference"] - psnr["reference"]),
                    "from reference - user": paired_interval(psnr["from reference"] - psnr["user"])})
    return out


def table_md(groups: dict[str, list[dict]]) -> str:
    lines = []
    for group, rows in groups.items():
        lines += [f"### {group}", "",
                  "| pattern | n | `latent` (user) | reference | from the reference | reference fits the pattern's "
                  "samples better | from the reference fits them better | drift (from reference − reference) | "
                  "from reference − user |",
                  "|---|---|---|---|---|---|---|---|---|"]

        def interval(mean, low, high, **_):
            return f"{mean:+.2f}" if low is None else f"{mean:+.2f} [{low:+.2f}, {high:+.2f}]"
        for row in summary(rows):
            lines.append(f"| {row['pattern']} | {row['materials']} | {row['user psnr']:.2f} | "
                         f"{row['reference psnr']:.2f} | {row['from reference psnr']:.2f} | "
                         f"{row['reference fits better']} of {row['materials']} | "
                         f"{row['from reference fits better']} of {row['materials']} | {interval(**row['drift'])} | "
                         f"{interval(**row['from reference - user'])} |")
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tables", type=Path, nargs="*", default=[], help="MERL files no training saw")
    parser.add_argument("--measurements", type=Path, nargs="*", default=[], help=".bsdf files no training saw")
    parser.add_argument("--model", default="pretrained")
    parser.add_argument("--patterns", nargs="+", default=list(PATTERNS))
    parser.add_argument("--samples", type=int, default=1500)
    parser.add_argument("--reference-samples", type=int, default=20000)
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = load_model(args.model)
    scene = Scene(resolution=args.resolution)
    mask = material_mask(scene)
    config = dataclasses.replace(refine_config("latent"), progress=False)
    groups = {"tables": args.tables, "measurements": args.measurements}
    rows = {group: [] for group in groups}
    for group, paths in groups.items():
        for path in tqdm(paths, desc=group):
            rows[group] += material_rows(model, path, args, scene, mask, config)
    rows = {group: found for group, found in rows.items() if found}
    args.out.mkdir(parents=True, exist_ok=True)
    save_json(args.out / "gap.json", {"run": run_metadata(), "args": {k: str(v) for k, v in vars(args).items()},
                                      "summary": {group: summary(found) for group, found in rows.items()},
                                      "rows": rows})
    write_text(args.out / "gap.md", table_md(rows))
    print(table_md(rows))


if __name__ == "__main__":
    main()
