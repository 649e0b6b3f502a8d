"""A trained run's decoder fitted further as an auto-decoder: each training material's latent free.

Training fits the decoder through its encoder's z, and stops (by patience) with the decoded NBRDFs still
fitting the very materials it trained on at several times the per-material fit's error: training and validation
losses end equal, an under-fit. :func:`fit_decoder` takes such a run's training materials, starts each one's latent
at the encoder's z of the run's ``context_samples`` random bins, and fits those latents and the decoder's weights together (two
Adam rates) on L_rec plus the run's weight and latent penalties; no augmentation, no L_fre, and by default the
encoder untouched. `latent` refinement then reaches more of every material, unseen ones too
(research/results/decoder-finetune: +0.27 dB on 19 real measurements outside training, +1.85 dB on 40 held-out
tables, `full` +1.09 dB). The encoder's z no longer fits the new decoder: train its encoders again with
``frenbrdf train --decoder-from OUT`` before using it from the encoder alone (done so for the study, the encoder
read 0.9 dB below the run's own and `latent` +0.20 dB, within noise: the fit is not in the shipped model).
``encoder_weight`` keeps the decoding of the encoder's z in the loss, the encoder training along (``encoder_lr``) or
kept (``encoder_lr=0``); the study found both cost the encoder alone 0.9–1.7 dB on held-out tables all the same.
``encoder_augment`` draws that term's materials as the run's training drew them (mixes, gains, hue turns): with the
encoder kept, the one way found to keep its reading (held-out tables +0.04 dB, two seeds) while `latent` gains
(+1.4 dB on the tables, +0.25 dB on the measurements, within the fit's noise; on the shipped recipe's runs +1.1 and
+0.10: not shipped).

The result is a run folder (the source's config, split and mapping, its ``best.pt`` with the new decoder and,
where it trained, encoder), so everything that reads runs reads it, with ``decoder-fit.json`` (settings and the
loss by epoch) and ``latents.npz`` (each training material's latent at the end).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from ..data.folders import Split, list_materials, mapped_bank, max_directional_albedo, read_valid_table
from ..exceptions import TrainingDiverged
from ..io import checkpoints
from ..io.atomic import save_json
from ..io.outputs import OutputFolder
from ..models.autoencoder import Model
from .augment import BatchDrawer
from .config import TrainConfig
from .prepared import PreparedData, check_bank_memory
from .run import Run
from .step import decoding_terms, loss_terms

#: What :func:`fit_decoder` writes into its folder.
FIT_FILES = ("config.json", "split.json", "mapping.npz", "history.json", "best.pt", "decoder-fit.json", "latents.npz")
#: What it reads of the source run folder (``best.pt`` last: it is written anew).
RUN_INPUTS = ("config.json", "split.json", "mapping.npz", "best.pt")
#: The most epochs a fit takes (a day of a CPU core at ~200 materials).
MAX_EPOCHS = 100_000
#: Each number setting's range (low, high, whether low itself is excluded); larger Adam steps overflow.
RANGES = {"decoder_lr": (0, 1, True), "latent_lr": (0, 1, True), "encoder_weight": (0, 100, False),
          "encoder_lr": (0, 1, False)}


@dataclass
class DecoderFitConfig:
    """How long and how fast :func:`fit_decoder` fits (research/results/decoder-finetune chose these on one fold's
    validation tables)."""

    epochs: int = 300
    """Passes over the training materials."""
    decoder_lr: float = 1e-4
    """Adam rate of the decoder's weights (1e-5 gained the validation tables 0.3 dB where this gained 2.1)."""
    latent_lr: float = 1e-3
    """Adam rate of the materials' latents (1e-2 threw the training loss from 0.06 to 0.33 in one epoch)."""
    seed: int = 0
    """Seeds the initial latents' samples, the order of the materials and the query bins."""
    encoder_weight: float = 0.0
    """0: the encoder's z plays no part (it no longer fits the new decoder). Above 0: the loss adds this weight
    times the training loss (L_rec and penalties) of the decoding of the encoder's z from a fresh context of the
    run's ``context_samples`` random bins, on the same query, so the decoder stays one the encoder can read."""
    encoder_lr: float = 1e-4
    """With ``encoder_weight`` above 0: the encoder's Adam rate; 0 keeps the encoder as it is (the decoder then
    keeps fitting the z it gives)."""
    encoder_augment: bool = False
    """With ``encoder_weight`` above 0: draw the encoder term's materials as the run's training drew them (its
    mixes, gains, hue turns, procedural materials and sampling patterns, :class:`~.augment.BatchDrawer`), so that
    the decoder keeps decoding the z of materials between and beyond the training ones; the free latents' term stays
    on the training materials as they are."""

    @property
    def trains_encoder(self) -> bool:
        return self.encoder_weight > 0 and self.encoder_lr > 0

    def __post_init__(self):
        problems = []
        if not 1 <= int(self.epochs) <= MAX_EPOCHS:
            problems.append(f"epochs must lie in 1 … {MAX_EPOCHS}, got {self.epochs}")
        for name, (low, high, low_excluded) in RANGES.items():
            value = getattr(self, name)
            if not (math.isfinite(value) and (low < value if low_excluded else low <= value) and value <= high):
                problems.append(f"{name} must lie in {'(' if low_excluded else '['}{low}, {high}], got {value}")
        if self.encoder_augment and self.encoder_weight == 0:
            problems.append("encoder_augment needs encoder_weight above 0 (it changes the encoder term's materials)")
        if int(self.seed) < 0:
            problems.append(f"seed must be ≥ 0, got {self.seed}")
        if problems:
            raise ValueError("; ".join(problems))


def fit_decoder(run: str | Path, out: str | Path, config: DecoderFitConfig | None = None, *,
                overwrite: bool = False, progress: bool = False) -> Path:
    """Fits the decoder of the training run ``run`` further on its training materials (see the module docstring)
    and writes the result as a run folder ``out``; returns ``out``.

    The run's data folder must still hold its materials. ``config``: :class:`DecoderFitConfig` (None: its
    defaults). ``overwrite``: replace an earlier ``fit_decoder`` output in ``out`` (other files there are kept).
    Everything is checked before the work, and the folder appears whole at the end (:mod:`frenbrdf.io.outputs`).
    """
    config = config or DecoderFitConfig()
    source = Run(run)
    missing = [name for name in RUN_INPUTS if not (source.path / name).is_file()]
    if missing:
        raise ValueError(f"{run} is not a trained run folder (it lacks {', '.join(missing)}); give a folder "
                         "`frenbrdf train --out` wrote")
    cfg, split, run = source.config, source.split, source.path
    files = {path.stem: path for path in list_materials(cfg.data)}
    if missing := sorted(set(split.train) - set(files)):
        raise ValueError(f"the run's training materials {missing[:5]} are not in its data folder {cfg.data}")
    if config.encoder_augment and not cfg.augment.active and cfg.sampling.paper:
        raise ValueError(f"encoder_augment: {run} trained without augmentations or sampling patterns (its config's "
                         "`augment` and `sampling`), so its training drew nothing but the tables as they are")
    folder = OutputFolder.claim(out, command="fit-decoder", inputs=(run, cfg.data), overwrite=overwrite)
    if folder.earlier and not overwrite:  # as `train` does: a fit is long work, replaced only when asked
        raise ValueError(f"--out {out} already holds a fit-decoder output; replace it with --overwrite "
                         "(overwrite=True), or choose another folder")
    folder.check_names(FIT_FILES)
    checkpoint = checkpoints.load(run / "best.pt")
    model = Model.from_checkpoint(checkpoint, checkpoints.load_mapping(run / "best.pt", checkpoint), source=str(run))
    # Only the training materials' mapped bank is needed (no frequency truth), read one at a time.
    check_bank_memory(len(split.train))
    bank = mapped_bank(split.train, (read_valid_table(files[name]) for name in split.train), model.mapping)
    drawer = _augmented_drawer(cfg, split, bank, model.mapping) if config.encoder_augment else None
    network = model.network.train()
    network.encoder.requires_grad_(config.trains_encoder)
    generator = torch.Generator().manual_seed(config.seed)
    start = time.perf_counter()
    latents, history = _fit(network, bank, len(split.train), cfg, config, generator, progress, drawer)
    # The source's checkpoint with the new weights; its optimiser's state belonged to the old decoder.
    checkpoint = {key: value for key, value in checkpoint.items() if key != "optimizer"} | {"model": network.state_dict()}
    with folder.staged() as staging:
        for name in RUN_INPUTS[:-1] + ("history.json",):  # the source's record, so the folder reads as a run
            if (run / name).is_file():
                (staging / name).write_bytes((run / name).read_bytes())
        checkpoints.save(staging / "best.pt", checkpoint)
        np.savez(staging / "latents.npz", names=np.array(split.train), latents=latents)
        save_json(staging / "decoder-fit.json", {"source": str(run), **dataclasses.asdict(config),
                                                 "seconds": time.perf_counter() - start, "history": history})
    return folder.path


def _augmented_drawer(cfg: TrainConfig, split: Split, bank, mapping) -> BatchDrawer:
    """The run's own batch drawer over its training materials (no L_fre truth), for ``encoder_augment``."""
    training = dataclasses.replace(split, val=(), test=())  # the bank holds the training materials only
    albedo = max_directional_albedo(bank, mapping, range(len(training.train))) if cfg.augment.gain > 0 else None
    return BatchDrawer(cfg, PreparedData(training, mapping, bank, None, albedo), with_truth=False)


def _fit(network, bank, materials: int, cfg: TrainConfig, config: DecoderFitConfig, generator: torch.Generator,
         progress: bool, drawer: BatchDrawer | None = None) -> tuple[np.ndarray, list[dict]]:
    """The joint fit of the decoder's weights and one latent a material (and of the encoder with
    ``config.encoder_weight``, its materials drawn by ``drawer`` where given); returns the latents and the loss by
    epoch."""
    decoder, encoder = network.decoder, network.encoder
    with torch.no_grad():  # each material's start: the encoder's z of a context drawn as training draws one
        latents = torch.cat([encoder(bank.sample(list(range(i, min(i + 8, materials))), cfg.context_samples,
                                                 generator).encoder_input()) for i in range(0, materials, 8)])
    latents.requires_grad_(True)
    groups = [{"params": decoder.parameters(), "lr": config.decoder_lr}, {"params": [latents], "lr": config.latent_lr}]
    if config.trains_encoder:
        groups.append({"params": encoder.parameters(), "lr": config.encoder_lr})
    optimizer = torch.optim.Adam(groups)
    size, loss = min(cfg.batch_materials, materials), cfg.loss
    steps, history = materials // size, []
    for epoch in tqdm(range(config.epochs), desc="fit decoder", disable=not progress):
        order, totals = torch.randperm(materials, generator=generator).tolist(), {"train_rec": 0.0}
        for step in range(steps):
            batch = order[step * size:(step + 1) * size]
            query = bank.sample(batch, cfg.query_samples, generator)
            z = latents[batch]
            terms = decoding_terms(z, decoder(z), query, loss)
            rec = terms["rec"]
            value = rec + terms["w"] + terms["z"]
            if config.encoder_weight > 0:  # the loss training uses, of the encoder's z
                context, encoder_query = _encoder_samples(bank, batch, query, cfg, drawer, generator)
                encoded = loss_terms(network, None, loss, context, encoder_query, None)
                value = value + config.encoder_weight * encoded.total
                totals["train_rec_encoder"] = totals.get("train_rec_encoder", 0.0) + encoded.logged["rec"] / steps
            if not torch.isfinite(value):
                raise TrainingDiverged(f"fit-decoder: the loss became {float(value)} at epoch {epoch}, step {step}; "
                                       f"nothing was written (lower decoder_lr {config.decoder_lr:g} or latent_lr "
                                       f"{config.latent_lr:g})")
            optimizer.zero_grad()
            value.backward()
            optimizer.step()
            totals["train_rec"] += float(rec.detach()) / steps
        history.append({"epoch": epoch, **totals})
    return latents.detach().numpy(), history


def _encoder_samples(bank, batch: list[int], query, cfg: TrainConfig, drawer: BatchDrawer | None,
                     generator: torch.Generator):
    """The encoder term's context and query: fresh random bins of each material, read on the free latents' query;
    with ``drawer``, the batch the run's training would have drawn in its place."""
    if drawer is None:
        return bank.sample(batch, cfg.context_samples, generator), query
    drawn = drawer.draw(batch, generator)
    return drawn.context, drawn.query
