"""The training loop: FreNBRDF and its baselines (presets in :mod:`frenbrdf.presets`).

``train(cfg) -> Run`` is a plain function; ``frenbrdf train`` is a thin wrapper. A run
folder holds ``config.json``, ``split.json``, ``mapping.npz`` (f_ref, once per run),
``history.json``, ``last.pt`` (for ``--resume``) and ``best.pt`` (lowest validation
reconstruction loss, or highest validation render PSNR: ``TrainConfig.select``);
:class:`~frenbrdf.training.run.Run` opens one. Checkpoints
(:mod:`frenbrdf.io.checkpoints`) hold the weights, optimiser, config, split and RNG state,
written atomically. Under ``torchrun`` each step's batch of materials is sharded across
ranks (DDP: gloo on CPU, NCCL on GPU).
"""

from __future__ import annotations

import copy
import json
import math
import os
import time
from pathlib import Path

import torch
from tqdm.auto import tqdm

from ..configs import from_dict, to_dict
from ..data.folders import Split, list_materials, split_materials
from ..exceptions import TrainingDiverged
from ..io import checkpoints
from ..io.atomic import save_json
from ..io.outputs import OutputFolder
from ..models.autoencoder import AutoEncoder, Model, ModelConfig, load_model
from ..models.encoder import POOLING_FIELDS, pooling_fields_with_weights
from ..models.losses import FrequencyLoss
from ..presets import SELECTION_RULES
from ..render.scoring import ScoringSet
from .augment import BatchDrawer
from .config import TrainConfig, selection_score
from .prepared import Distributed, PreparedData, prepare, select_device
from .run import Run
from .step import loss_terms, optimisation_step

#: What a run folder holds: what :func:`train` writes there (``--overwrite`` replaces these).
RUN_FILES = ("config.json", "split.json", "mapping.npz", "history.json", "last.pt", "best.pt", "best-loss.pt",
             "best-psnr.pt")


def check_run_folder(cfg: TrainConfig, *, resume: bool = False, overwrite: bool = False) -> OutputFolder:
    """Where :func:`train` may write, checked before any work (the output rule of :mod:`frenbrdf.io.outputs`):
    without ``resume`` a new or empty folder; an earlier run's folder, or one holding other entries, only with
    ``overwrite`` (the earlier run's files are then removed before training, the user's entries kept); with
    ``resume`` a folder holding ``last.pt``. Never an input: the data folder, the run or checkpoint of
    ``decoder_from`` / ``init_from``, nor a folder holding one."""
    if not cfg.out:
        raise ValueError("config.out (the run folder) is empty")
    if not cfg.data:
        raise ValueError("config.data (the folder of MERL files) is empty")
    inputs = (cfg.data, *(source for source in (cfg.decoder_from, cfg.init_from) if source and source != "pretrained"))
    if resume:  # the run's own files are written again; nothing else in the folder is touched
        folder = OutputFolder.claim(cfg.out, command="train", inputs=inputs, overwrite=True)
        if not (folder.target / "last.pt").is_file():
            raise FileNotFoundError(f"{cfg.out} holds no last.pt to resume from")
        folder.check_names(RUN_FILES)  # a run's files that frenbrdf train did not write (no marker lists them)
        return folder
    folder = OutputFolder.claim(cfg.out, command="train", inputs=inputs, overwrite=overwrite)
    if folder.earlier and not overwrite:
        raise ValueError(f"{cfg.out} already holds a training run; continue it with --resume (resume=True), replace "
                         "it with --overwrite (overwrite=True), or choose another folder")
    folder.check_names(RUN_FILES)
    return folder


def train(cfg: TrainConfig, *, resume: bool = False, overwrite: bool = False, data_cache: dict | None = None) -> Run:
    """Trains one model; returns its run folder (see the module docstring for what it holds).

    Parameters
    ----------
    cfg
        The run's configuration; ``cfg.out`` is the run folder, ``cfg.data`` the folder of materials.
    resume
        Continue the run in ``cfg.out`` from its ``last.pt``. Otherwise ``cfg.out`` must be new or empty, unless
        ``overwrite``: then the files of an earlier run there are replaced (:func:`check_run_folder`).
    overwrite
        See ``resume``.
    data_cache
        An (initially empty) dict passed to successive calls lets runs on the same data, split and mapping read
        and map the materials once (sweeps of many runs).
    """
    start = time.perf_counter()
    folder = check_run_folder(cfg, resume=resume, overwrite=overwrite)
    files = {path.stem: path for path in list_materials(cfg.data)}
    device = select_device(cfg.device, int(os.environ.get("LOCAL_RANK", "0")))
    ranks = Distributed.start(device)
    checkpoint = checked_resume(folder.target, cfg) if resume else None  # a damaged last.pt fails here, before any write
    split = (_resumed_split(checkpoint, cfg, files, folder.target) if checkpoint
             else split_materials(files, cfg.seed, cfg.split, cfg.holdout))
    batch_size = _batch_size(cfg, split, ranks)
    # The model whose mapping and decoder the run keeps (decoder_from) or starts from (init_from), and, with both
    # given, the one its encoder starts from.
    source = load_model(cfg.decoder_from or cfg.init_from) if (cfg.decoder_from or cfg.init_from) else None
    encoder_source = (None if not (cfg.decoder_from and cfg.init_from) else
                      source if cfg.init_from == cfg.decoder_from else load_model(cfg.init_from))
    if source is not None:
        check_source(cfg, source, "decoder_from" if cfg.decoder_from else "init_from")
    if encoder_source is not None:
        check_source(cfg, encoder_source, "init_from")
    data = prepare(cfg, split, files, ranks, data_cache,
                   mapping=source.mapping if source is not None else None)  # bad data fails here
    if ranks.main:
        # Overwrite: an earlier run's files go (a best-psnr.pt of it must not look like this run's); resume keeps them.
        folder.begin(RUN_FILES, keep=RUN_FILES if resume else ())
        save_json(folder.target / "config.json", to_dict(cfg))
        save_json(folder.target / "split.json", split.to_json())
        checkpoints.save_mapping(folder.target, data.mapping.state())

    trainer = Trainer(cfg, folder.target, ranks, device, split, data, batch_size, source, checkpoint,
                      encoder_source=encoder_source)
    validation_renders = (ScoringSet([files[name] for name in split.val], resolution=cfg.render_resolution,
                                     seed=cfg.seed) if cfg.render_every else None)
    trainer.run(validation_renders)
    if ranks.main:
        folder.finish()
    ranks.barrier()
    return Run(folder.target, seconds=time.perf_counter() - start)


class Trainer:
    """One run's network, optimiser and record while it trains, and the steps of an epoch.

    Built from a fresh start or a resumed checkpoint; :meth:`run` then trains epoch by epoch: a pass over the
    training materials (:meth:`train_epoch`), the validation loss (and renders every ``render_every`` epochs),
    the checkpoints (:meth:`record`), and the schedule: the learning rate halved on a plateau, early stopping
    (:meth:`should_stop`).
    """

    def __init__(self, cfg: TrainConfig, run_dir: Path, ranks: Distributed, device: torch.device, split: Split,
                 data: PreparedData, batch_size: int, source: Model | None, checkpoint: dict | None, *,
                 encoder_source: Model | None = None):
        self.cfg, self.run_dir, self.ranks, self.device, self.split, self.data = cfg, run_dir, ranks, device, split, data
        self.batch_size, self.steps_per_epoch = batch_size, data.n_train // batch_size
        torch.manual_seed(cfg.seed)
        network = AutoEncoder(cfg.model)
        if source is not None and not cfg.decoder_from:  # fine-tuning: every weight starts where the source's ended
            network.load_state_dict(source.network.state_dict())
        elif source is not None:  # cfg.decoder_from: the trained decoder, frozen; only the encoder learns
            if encoder_source is not None:  # ... starting from another model's encoder (cfg.init_from)
                network.encoder.load_state_dict(encoder_source.network.encoder.state_dict())
            network.decoder.load_state_dict(source.network.decoder.state_dict())
            network.decoder.requires_grad_(False)
        self.network = network.to(device)
        self.frequency = FrequencyLoss(cfg.loss.frequency, data.mapping).to(device) if data.truth is not None else None
        self.optimizer = make_optimizer(self.network, cfg)
        self.drawer = BatchDrawer(cfg, data, with_truth=cfg.loss.eta > 0)
        self.generator = torch.Generator().manual_seed(cfg.seed)
        self.history: list[dict] = []
        # The best epoch by each rule measured (best.pt holds cfg.select's pick): score, lower is better.
        self.bests = {rule: {"epoch": -1, "val": math.inf}
                      for rule in (SELECTION_RULES if cfg.render_every else ("loss",))}
        #: The epoch training starts at: 0, or the one after a resumed checkpoint's.
        self.first_epoch = 0
        if checkpoint is not None:
            self.network.load_state_dict(checkpoint["model"])
            self.optimizer.load_state_dict(checkpoint["optimizer"])
            self.generator.set_state(checkpoint["generator"])
            self.history, self.first_epoch = checkpoint["history"], checkpoint["epoch"] + 1
            self.bests.update(checkpoint.get("bests", {cfg.select: checkpoint["best"]}))
        self.trained = torch.nn.parallel.DistributedDataParallel(self.network) if ranks.world > 1 else self.network

    def run(self, validation_renders: ScoringSet | None) -> None:
        """Trains from :attr:`first_epoch` to ``cfg.epochs`` or an early stop. ``validation_renders``: the
        validation materials read and rendered once (each ``render_every`` epochs then costs only the model's own
        renders), or None without ``render_every``."""
        cfg = self.cfg
        if self.first_epoch and self.stopped_early(self.first_epoch - 1):
            return  # a resumed run that patience had already stopped: nothing to add (a rerun of a script is safe)
        if not self.history:  # the untrained model's validation loss: the baseline every epoch improves on
            initial = self.validate()
            self.history.append({"epoch": -1, **{f"val_{k}": v for k, v in initial.items()}})
        # Training wall time, carried over a resume; the validation renders are measurement, not training.
        clock_start, render_seconds = time.perf_counter(), 0.0
        seconds_before = self.history[-1].get("seconds", 0.0)
        bar = tqdm(total=(cfg.epochs - self.first_epoch) * self.steps_per_epoch, desc=f"train {cfg.method}",
                   disable=not (cfg.progress and self.ranks.main))
        for epoch in range(self.first_epoch, cfg.epochs):
            entry = {"epoch": epoch, **self.train_epoch(epoch, bar),
                     **{f"val_{k}": v for k, v in self.validate().items()}}
            if validation_renders is not None and ((epoch + 1) % cfg.render_every == 0 or epoch == cfg.epochs - 1):
                render_start = time.perf_counter()
                entry.update(render_validation(self.network, self.data, cfg, validation_renders))
                render_seconds += time.perf_counter() - render_start
            entry["seconds"] = seconds_before + time.perf_counter() - clock_start - render_seconds
            entry["lr"] = self.optimizer.param_groups[0]["lr"]
            self.record(epoch, entry)
            if self.should_stop(epoch):
                break
        bar.close()

    def train_epoch(self, epoch: int, bar: tqdm) -> dict:
        """One pass over the training materials in a new random order; the mean of each logged term
        (``train_*``) and the gradient ratio of the epoch's first step."""
        self.network.train()
        sums: dict[str, float] = {}
        gradient_ratio = None
        order = torch.randperm(self.data.n_train, generator=self.generator)
        ranks, size = self.ranks, self.batch_size
        for step in range(self.steps_per_epoch):
            batch = order[step * size:(step + 1) * size].tolist()
            # Every rank draws the whole batch's samples (same generator), then keeps its share:
            # the run equals a single-process run on the same seed.
            share = slice(ranks.rank * len(batch) // ranks.world, (ranks.rank + 1) * len(batch) // ranks.world)
            mine = self.drawer.draw(batch, self.generator).take(share).to(self.device)
            terms = optimisation_step(self.trained, self.frequency, self.optimizer, self.cfg.loss, self.cfg.grad_clip,
                                      mine.context, mine.query, mine.truth, measure_gradients=step == 0,
                                      truth_mask=mine.truth_mask)
            if terms.gradient_ratio is not None:
                gradient_ratio = terms.gradient_ratio
            if terms.not_finite:
                kept = (f"the last good checkpoint is kept in {self.run_dir}" if (self.run_dir / "last.pt").is_file()
                        else "before any checkpoint was written")
                raise TrainingDiverged(
                    f"step {epoch * self.steps_per_epoch + step}: loss term(s) {terms.not_finite} became NaN/inf; "
                    f"training stopped, {kept} (lr {self.cfg.lr:g}, eta {self.cfg.loss.eta:g}: lower them, or set "
                    "grad_clip)")
            for name, value in terms.logged.items():
                sums[name] = sums.get(name, 0.0) + value / self.steps_per_epoch
            bar.update()
            bar.set_postfix({name: f"{value:.3g}" for name, value in terms.logged.items()}, refresh=False)
        return {**{f"train_{k}": v for k, v in sums.items()},
                **({"train_gradient_ratio": gradient_ratio} if gradient_ratio is not None else {})}

    def validate(self) -> dict:
        """The validation split's mean loss terms (:func:`evaluate_split`)."""
        return evaluate_split(self.network, self.frequency, self.cfg, self.data, self.data.validation, self.device,
                              drawer=self.drawer)

    def record(self, epoch: int, entry: dict) -> None:
        """Adds the epoch's entry to the history; writes the best checkpoint of each rule it improves,
        ``last.pt`` and ``history.json`` (the main rank only)."""
        self.history.append(entry)
        for rule, best in self.bests.items():
            score = selection_score(entry, rule)
            if score is not None and score < best["val"]:
                self.bests[rule] = {"epoch": epoch, "val": score}
                if self.ranks.main:
                    checkpoints.save(self.run_dir / best_checkpoint(rule, self.cfg), self.state(epoch))
        if self.ranks.main:
            checkpoints.save(self.run_dir / "last.pt", self.state(epoch))
            save_json(self.run_dir / "history.json", self.history)

    def should_stop(self, epoch: int) -> bool:
        """The schedule after ``epoch``: halves the learning rate every ``lr_plateau`` epochs without a better
        selection score (kept in last.pt for a resume); True once ``patience`` epochs passed without one."""
        since_best = epoch - self.bests[self.cfg.select]["epoch"]
        if self.cfg.lr_plateau and since_best and since_best % self.cfg.lr_plateau == 0:
            for group in self.optimizer.param_groups:
                group["lr"] *= 0.5
        return self.stopped_early(epoch)

    def stopped_early(self, epoch: int) -> bool:
        """Whether ``patience`` epochs had passed without a better selection score by the end of ``epoch``."""
        return bool(self.cfg.patience and epoch - self.bests[self.cfg.select]["epoch"] >= self.cfg.patience)

    def state(self, epoch: int) -> dict:
        """What a checkpoint holds after ``epoch`` (:mod:`frenbrdf.io.checkpoints`)."""
        cfg = self.cfg
        return {"method": cfg.method, "config": json.dumps(to_dict(cfg)), "split": self.split.to_json(),
                "model": self.network.state_dict(), "optimizer": self.optimizer.state_dict(),
                "generator": self.generator.get_state(), "epoch": epoch, "best": self.bests[cfg.select],
                "bests": self.bests, "history": self.history}


def _batch_size(cfg: TrainConfig, split: Split, ranks: Distributed) -> int:
    """Materials a step: full batches only (the last partial one is dropped; each epoch reshuffles), so that
    every step's batch splits evenly across ranks."""
    batch_size = min(cfg.batch_materials, len(split.train))
    if batch_size % ranks.world:
        raise ValueError(f"a batch of {batch_size} materials does not split evenly across {ranks.world} ranks; "
                         "choose batch_materials divisible by the number of ranks")
    return batch_size


def best_checkpoint(rule: str, cfg: TrainConfig) -> str:
    """The file name of the best checkpoint by ``rule``: ``best.pt`` for the run's own rule (``cfg.select``)."""
    return "best.pt" if rule == cfg.select else f"best-{rule}.pt"


def render_validation(network, data: PreparedData, cfg: TrainConfig, materials: ScoringSet) -> dict:
    """Mean render PSNR and ΔE of the validation materials as ``frenbrdf evaluate`` measures them
    (4000 samples each, drawn from the run's seed, the same every time)."""
    on_cpu = network if next(network.parameters()).device.type == "cpu" else copy.deepcopy(network).cpu()
    metrics = materials.mean_metrics(Model(on_cpu, data.mapping, cfg.model, cfg.method))  # eval mode
    return {"val_psnr": metrics["psnr"], "val_delta_e": metrics["delta_e"]}


def make_optimizer(network: torch.nn.Module, cfg: TrainConfig) -> torch.optim.Optimizer:
    """Adam, or AdamW (decoupled weight decay) with ``cfg.weight_decay > 0``, over the parameters that train
    (a frozen decoder's do not)."""
    trained = [p for p in network.parameters() if p.requires_grad]
    if cfg.weight_decay > 0:
        return torch.optim.AdamW(trained, lr=cfg.lr, weight_decay=cfg.weight_decay)
    return torch.optim.Adam(trained, lr=cfg.lr)


def check_source(cfg: TrainConfig, source: Model, field: str):
    """That the model ``cfg.decoder_from`` or ``cfg.init_from`` (``field``) names fits this run: for
    ``decoder_from`` the same decoder, NBRDF, latent size and mapping (the encoder may differ), for ``init_from``
    the same model config."""
    ours, theirs = to_dict(cfg.model), to_dict(source.config)
    if field == "init_from":  # the mean and density pooling have no weights: a model may be fine-tuned with another
        poolings = []
        for config in (ours, theirs):
            encoders = (config["encoder"], *config["extra_encoders"])
            poolings.append([pooling_fields_with_weights(encoder) for encoder in encoders])
            for encoder in encoders:
                for name in POOLING_FIELDS:
                    encoder.pop(name, None)
        differ = [name for name in ours if ours[name] != theirs[name]]
        if poolings[0] != poolings[1]:
            differ.append("the encoders' attention pooling (its score network has weights; mean and density have none)")
    else:
        differ = [name for name in ("decoder", "nbrdf", "mapping") if ours[name] != theirs[name]]
        if ours["encoder"]["latent"] != theirs["encoder"]["latent"]:
            differ.append("encoder.latent")
    if differ:
        rule = "the same model config" if field == "init_from" else "its model config; only the encoder may differ"
        raise ValueError(f"{field} {getattr(cfg, field)!r}: its model config differs from this run's in "
                         f"{', '.join(differ)}; give this run {rule}")


def checked_resume(run_dir: Path, cfg: TrainConfig) -> dict:
    """The run folder's ``last.pt``, every field a resume restores checked (:func:`checkpoints.load_for_resume`)
    against the network and optimiser ``cfg`` gives, built on the meta device (nothing allocated, no random
    numbers drawn)."""
    with torch.device("meta"):
        network = AutoEncoder(cfg.model)
    if cfg.decoder_from:
        network.decoder.requires_grad_(False)  # as train() freezes it: the optimiser holds the encoder's only
    path = run_dir / "last.pt"
    checkpoint = checkpoints.load_for_resume(path, network, make_optimizer(network, cfg), to_dict(cfg), model_as_read)
    try:
        Split.from_json(checkpoint["split"], "split")
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None
    return checkpoint


def model_as_read(model: dict) -> dict:
    """A saved model config (a dict) with the fields added since it was saved at their defaults, as a model loads
    it (a run from before ``encoder.pooling`` has the plain mean), so that it compares equal to the same config
    written today; as it is where it is no valid config."""
    try:
        return to_dict(from_dict(ModelConfig, model, "model"))
    except (ValueError, TypeError):
        return model


def _resumed_split(checkpoint: dict, cfg: TrainConfig, files: dict, run_dir: Path) -> Split:
    """The split of the checkpoint being resumed, checked against ``cfg`` and the data folder."""
    saved = json.loads(checkpoint["config"])
    if model_as_read(saved["model"]) != to_dict(cfg)["model"] or saved["seed"] != cfg.seed:
        raise ValueError(f"{run_dir / 'last.pt'} was trained with another model config or seed; "
                         "resume with the run's own config.json")
    split = Split.from_json(checkpoint["split"])
    missing = sorted(set(split.train + split.val) - set(files))
    if missing:
        raise ValueError(f"the run's materials {missing[:5]} are not in {cfg.data}")
    return split


@torch.no_grad()
def evaluate_split(network, frequency: FrequencyLoss | None, cfg: TrainConfig, data: PreparedData, materials,
                   device, *, drawer: BatchDrawer | None = None) -> dict:
    """Mean loss terms over materials, on samples drawn from a fixed seed (the same every epoch). With
    ``cfg.validate_through == "sampling"`` and a ``drawer`` of a pattern mixture, each material's context is read
    through a pattern the drawer's mixture picks."""
    network.eval()
    generator = torch.Generator().manual_seed(cfg.seed + 1)
    sampler = drawer.patterns if cfg.validate_through == "sampling" and drawer is not None else None
    materials = list(materials)
    sums: dict[str, float] = {}
    for start in range(0, len(materials), cfg.batch_materials):
        batch = materials[start:start + cfg.batch_materials]
        if sampler is not None and drawer is not None:
            patterns = list(sampler.choose(len(batch), generator))
            context = drawer.pattern_context(batch, patterns, cfg.context_samples, generator).to(device)
        else:
            context = data.bank.sample(batch, cfg.context_samples, generator).to(device)
        query = data.bank.sample(batch, cfg.query_samples, generator).to(device)
        true = data.truth[batch].to(device) if data.truth is not None else None
        terms = loss_terms(network, frequency, cfg.loss, context, query, true)
        for name, value in terms.logged.items():
            sums[name] = sums.get(name, 0.0) + value * len(batch) / len(materials)
    return sums

