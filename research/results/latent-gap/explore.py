"""The latent-gap exploration (README.md; decides nothing): remedies for the two parts of `latent`'s gap through
device patterns, on every third of the 45 families of seed 10 (made for this, read by nothing before), through
random bins, uniform, in-plane, image-based and specular-only pairs (1,500 each). The mean render PSNR per
pattern and variant, and each variant's mean seconds a material.

- against the samples' pull away from the best render (the information part): a stronger latent penalty
  (the model's λ2 times 10 or 100, towards 0), or a penalty towards the start (the encoder's z, weight μ);
- against the worse minimum (the search part): starts from the model's training materials' latents, the two
  whose decodings fit the samples best before any step, beside the encoder's z; the result that fits the samples
  best is kept;
- against a pattern's uneven coverage (the samples' part again): each sample's loss weighted by the inverse of
  the samples' density where random bins are uniform (a k-NN estimate), so that the samples' loss estimates the
  loss over the whole table, as random bins' does.

    python research/results/latent-gap/explore.py local/c4/families10 TRAINING_TABLES HOLDOUT_JSON [PART PARTS
        [VARIANT...]] > OUT
    python research/results/latent-gap/explore.py --summarise OUT...     # the table of explore.md

(PART of PARTS: every PARTS-th of the families from the PART-th, so that two processes share the work.)
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
import zlib
from collections import defaultdict
from pathlib import Path

import numpy as np
import torch

from frenbrdf.data.folders import list_materials
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io import read_material
from frenbrdf.io.merl import merl_above_horizon
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table, sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.losses import reconstruction_loss
from frenbrdf.models.nbrdf import mapped_samples, nbrdf_forward
from frenbrdf.models.reconstruct import _frozen, _loss_config, _optimise, _Record, _sample_loss, _Samples, refine_config
from frenbrdf.numerics.coords import directions_to_rusinkiewicz
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics


@dataclasses.dataclass(frozen=True)
class Variant:
    prior: float = 1.0  # times the model's λ2 (the penalty towards 0)
    anchor: float = 0.0  # μ of μ·mean((z − z_start)²)
    bank_starts: int = 0  # training materials' latents to start from besides the encoder's z
    density: int = 0  # k of a k-NN density estimate: each sample's loss weighted by 1 / its density (0: off)
    clip: float = 10.0  # no weight above this many times the mean
    relative: bool = False  # the density relative to random bins' own (edges of the domain cancel)


VARIANTS = {
    "latent": Variant(),
    "prior x10": Variant(prior=10),
    "prior x100": Variant(prior=100),
    "anchor 0.01": Variant(anchor=0.01),
    "anchor 0.1": Variant(anchor=0.1),
    "bank starts 2": Variant(bank_starts=2),
    "density k8": Variant(density=8),
    "density k8 clip 3": Variant(density=8, clip=3),
    "density k32": Variant(density=32),
    "relative k8": Variant(density=8, relative=True),
    "relative k32": Variant(density=32, relative=True),
}
CONDITIONS = ("merl-bins", "uniform", "in-plane", "image-based", "specular")
COUNT = 1500


def tensors(model, drawn, variant: Variant = Variant()) -> _Samples:
    mapped, coords, cos_in = mapped_samples(model.mapping, *drawn)
    if variant.density:  # the weights enter as a factor of cos θ_i, which multiplies each sample's error
        cos_in = cos_in * density_weights(*drawn[1], variant.density, variant.clip, variant.relative)
    return _Samples(*(torch.from_numpy(np.asarray(a, dtype=np.float32))[None] for a in (coords, mapped, cos_in)))


def density_weights(wi: np.ndarray, wo: np.ndarray, k: int, clip: float, relative: bool) -> np.ndarray:
    """1 / each pair's sample density in the MERL table's index space, where random bins are uniform: (√(θ_h /
    (π/2)), θ_d / (π/2), φ_d folded into [0, π) / π), from the distance to its k-th nearest neighbour; ``relative``:
    times the density of random valid bins there (:func:`random_bins`), so that the domain's edges, where every
    k-NN estimate runs low, cancel. Mean 1, none above ``clip`` times the mean."""
    from scipy.spatial import cKDTree

    points = index_space(wi, wo)
    distance = cKDTree(points).query(points, k=min(k + 1, len(points)))[0][:, -1]
    weights = distance ** 3
    if relative:
        weights /= cKDTree(random_bins()).query(points, k=k)[0][:, -1] ** 3
    weights /= weights.mean()
    weights = np.minimum(weights, clip)
    return weights / weights.mean()


def index_space(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    theta_h, _, theta_d, phi_d = directions_to_rusinkiewicz(wi, wo).T
    return np.stack([np.sqrt(np.clip(theta_h / (np.pi / 2), 0, 1)), theta_d / (np.pi / 2),
                     np.mod(phi_d, np.pi) / np.pi], axis=1)


_RANDOM_BINS: list[np.ndarray] = []


def random_bins(count: int = 20000) -> np.ndarray:
    """``count`` random valid MERL bins' centres in the index space of :func:`index_space` (drawn once)."""
    if not _RANDOM_BINS:
        valid = np.argwhere(merl_above_horizon())
        chosen = valid[np.random.default_rng(7).choice(len(valid), count, replace=False)]
        _RANDOM_BINS.append((chosen + 0.5) / np.array([90, 90, 180]))
    return _RANDOM_BINS[0]


def loss_at(model, z: torch.Tensor, samples: _Samples) -> float:
    with torch.no_grad():
        return _sample_loss(model.network.decoder(z), samples, _loss_config(model).kind)


def refine(model, start: torch.Tensor, samples: _Samples, variant: Variant) -> torch.Tensor:
    """Stage 1 of the shipped `latent` budget from ``start``, with the variant's penalties."""
    config, loss = refine_config("latent"), _loss_config(model)
    z, anchor = start.clone().requires_grad_(True), start.clone()

    def objective(batch: _Samples) -> torch.Tensor:
        predicted = nbrdf_forward(model.network.decoder(z), batch.coords)
        value = reconstruction_loss(predicted, batch.values, batch.cos_in, loss.kind)
        return value + variant.anchor * torch.mean((z - anchor) ** 2) if variant.anchor else value

    def step(rows) -> float:  # _optimise's step: the loss on the rows, its gradient left in z.grad
        value = objective(samples if rows is None else
                          _Samples(samples.coords[:, rows], samples.values[:, rows], samples.cos_in[:, rows]))
        value.backward()
        return float(value.detach())

    with _frozen(model.network):
        decay = variant.prior * 2 * loss.lambda_latent / z.numel()
        _optimise("latent", [z], [decay], step, config.latent_steps, config.latent_lr, len(samples), config,
                  _Record())
    return z.detach()


def reconstruct(model, drawn, variant: Variant, bank: torch.Tensor | None) -> torch.Tensor:
    samples = tensors(model, drawn, variant)
    starts = [torch.from_numpy(model.encode(*drawn).astype(np.float32))[None]]
    if variant.bank_starts:
        fits = [loss_at(model, latent[None], samples) for latent in bank]
        starts += [bank[index][None] for index in np.argsort(fits)[:variant.bank_starts]]
    results = [refine(model, start, samples, variant) for start in starts]
    return min(results, key=lambda z: loss_at(model, z, samples))


def training_latents(model, tables: Path, holdout: set[str]) -> torch.Tensor:
    """Each training table's latent from 4,000 of its own random bins."""
    rng, latents = np.random.default_rng(123), []
    for path in list_materials(tables):
        if path.stem not in holdout:
            table = read_material(path)
            latents.append(model.encode(*truth_samples(table, sample_bins(table, rng, 4000), rng)))
    return torch.from_numpy(np.stack(latents).astype(np.float32))


def main(folder: str, tables: str, holdout_json: str, part: int = 0, parts: int = 1, *names: str) -> None:
    model, scene = load_model("pretrained"), Scene(resolution=128)
    mask = material_mask(scene)
    variants = {name: VARIANTS[name] for name in ("latent", *names)} if names else VARIANTS
    bank = (training_latents(model, Path(tables), set(json.loads(Path(holdout_json).read_text())["holdout"]))
            if any(variant.bank_starts for variant in variants.values()) else None)
    psnr, seconds = defaultdict(list), defaultdict(list)
    for path in sorted(Path(folder).glob("*.binary"))[::3][part::parts]:
        truth = read_material(path)
        table, truth_image = as_table(truth), tonemap(render_linear(truth, scene))
        for pattern in CONDITIONS:
            rng = np.random.default_rng([0, zlib.crc32(pattern.encode())])
            drawn = pattern_samples(truth, pattern, COUNT, rng, table=table)
            for name, variant in variants.items():
                start = time.perf_counter()
                z = reconstruct(model, drawn, variant, bank)
                seconds[name].append(time.perf_counter() - start)
                image = tonemap(render_linear(model.decode(z[0].numpy().astype(np.float64))[0], scene))
                psnr[pattern, name].append(image_metrics(truth_image, image, mask)["psnr"])
        print(path.stem, flush=True)
    print(json.dumps({"psnr": {f"{p}|{n}": v for (p, n), v in psnr.items()}, "seconds": seconds}))


def summarise(outputs: list[str]) -> None:
    """Per pattern: `latent`'s mean PSNR and each variant's difference from it (95 % interval over the families)."""
    psnr, seconds = defaultdict(list), defaultdict(list)
    for output in outputs:
        found = json.loads(Path(output).read_text().strip().splitlines()[-1])
        for key, values in found["psnr"].items():
            psnr[tuple(key.split("|"))] += values
        for name, values in found["seconds"].items():
            seconds[name] += values
    names = [name for name in VARIANTS if name in seconds]
    print("| pattern | " + " | ".join(names) + " |\n" + "|---" * (len(names) + 1) + "|")
    for pattern in CONDITIONS:
        base = np.array(psnr[pattern, "latent"])
        cells = [f"{base.mean():.2f}"]
        for name in names[1:]:
            change = paired_interval(np.array(psnr[pattern, name]) - base)
            cells.append(f"{change['mean']:+.2f} [{change['low']:+.2f}, {change['high']:+.2f}]")
        print(f"| {pattern} | " + " | ".join(cells) + " |")
    print("| seconds a material | " + " | ".join(f"{np.mean(seconds[name]):.1f}" for name in names) + " |")
    print(f"\n{len(base)} families.")


if __name__ == "__main__":
    if sys.argv[1] == "--summarise":
        summarise(sys.argv[2:])
    else:
        main(*sys.argv[1:4], *map(int, sys.argv[4:6]), *sys.argv[6:])
