"""decoder-finetune (README.md): a trained run's decoder fitted further as an auto-decoder, each training
material's latent free.

The run's training materials (its split and data folder, read as training reads them); each material's latent
starts at the run's encoder's z of 2,000 of its random bins and is optimised with the decoder's weights (Adam, two
rates) on L_rec plus the run's weight and latent penalties, 2,000 query bins a material a step, batches of the
run's size, no augmentation and no L_fre. The encoder is not trained. Written as a run folder (the source's
config, split and mapping, its ``best.pt`` with the decoder replaced), so every script that reads runs reads it,
with ``finetune.json`` (the training loss by epoch) and ``latents.npz`` (each training material's latent at the end).

    python research/results/decoder-finetune/finetune.py RUN OUT [--epochs 300] [--decoder-lr 1e-4] [--latent-lr 1e-2]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
import time
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from frenbrdf.configs import from_dict
from frenbrdf.data.folders import Split, list_materials
from frenbrdf.io.atomic import save_json
from frenbrdf.io.checkpoints import save
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.losses import latent_penalty, reconstruction_loss, weight_penalty
from frenbrdf.models.nbrdf import nbrdf_forward
from frenbrdf.training.config import TrainConfig
from frenbrdf.training.prepared import prepare


def initial_latents(network, bank, materials: list[int], context: int, generator: torch.Generator) -> torch.Tensor:
    """The encoder's z of each material from ``context`` random valid bins (as training draws a context)."""
    with torch.no_grad():
        return torch.cat([network.encoder(bank.sample(materials[i:i + 8], context, generator).encoder_input())
                          for i in range(0, len(materials), 8)])


def finetune(run: Path, out: Path, epochs: int, decoder_lr: float, latent_lr: float, seed: int) -> dict:
    cfg = from_dict(TrainConfig, json.loads((run / "config.json").read_text()), "config")
    # Only the bank is needed: no frequency truth (eta 0), no gain albedos.
    reading = dataclasses.replace(cfg, method="nbrdf", loss=dataclasses.replace(cfg.loss, eta=0.0),
                                  augment=dataclasses.replace(cfg.augment, gain=0.0, hue_turn=0.0))
    split = Split.from_json(json.loads((run / "split.json").read_text()))
    model = load_model(run)
    files = {path.stem: path for path in list_materials(cfg.data)}
    data = prepare(reading, split, files, mapping=model.mapping)
    network = model.network.train()
    network.encoder.requires_grad_(False)
    generator = torch.Generator().manual_seed(seed)
    train = list(range(data.n_train))
    latents = initial_latents(network, data.bank, train, cfg.context_samples, generator).requires_grad_(True)
    optimizer = torch.optim.Adam([{"params": network.decoder.parameters(), "lr": decoder_lr},
                                  {"params": [latents], "lr": latent_lr}])
    size, loss = cfg.batch_materials, cfg.loss
    history, start = [], time.perf_counter()
    for epoch in tqdm(range(epochs), desc="fine-tune"):
        order, total = torch.randperm(len(train), generator=generator).tolist(), 0.0
        steps = len(order) // size
        for step in range(steps):
            batch = order[step * size:(step + 1) * size]
            query = data.bank.sample(batch, cfg.query_samples, generator)
            z = latents[batch]
            params = network.decoder(z)
            rec = reconstruction_loss(nbrdf_forward(params, query.coords), query.values, query.cos_in, loss.kind)
            value = (rec + loss.lambda_weights * weight_penalty(params, loss.weight_penalty)
                     + loss.lambda_latent * latent_penalty(z))
            optimizer.zero_grad()
            value.backward()
            optimizer.step()
            total += float(rec) / steps
        history.append({"epoch": epoch, "train_rec": total})
    checkpoint = torch.load(run / "best.pt", weights_only=False)
    checkpoint["model"] = network.state_dict()
    out.mkdir(parents=True, exist_ok=False)
    for name in ("config.json", "split.json", "mapping.npz"):
        shutil.copy2(run / name, out / name)
    save(out / "best.pt", checkpoint)
    names = list(split.train)  # the bank's first n_train materials, in split order
    np.savez(out / "latents.npz", names=np.array(names), latents=latents.detach().numpy())
    record = {"source": str(run), "epochs": epochs, "decoder_lr": decoder_lr, "latent_lr": latent_lr, "seed": seed,
              "seconds": time.perf_counter() - start, "history": history}
    save_json(out / "finetune.json", record)
    return record


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--epochs", type=int, default=300)
    parser.add_argument("--decoder-lr", type=float, default=1e-4)
    parser.add_argument("--latent-lr", type=float, default=1e-2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    result = finetune(args.run, args.out, args.epochs, args.decoder_lr, args.latent_lr, args.seed)
    print(f"{args.out}: train_rec {result['history'][0]['train_rec']:.4f} -> {result['history'][-1]['train_rec']:.4f} "
          f"in {result['seconds']:.0f} s")
