"""Training: FreNBRDF and its baselines in one loop.

``train(cfg) -> TrainResult`` is a plain function; ``frenbrdf train`` is a thin wrapper.
Methods (DESIGN §6):

- ``frenbrdf``: L1 reconstruction + η · L_fre (η = 0.1);
- ``nbrdf``: the same autoencoder with η = 0;
- ``hyperbrdf``: HyperBRDF's settings: MSE, a 6→60×4→3 NBRDF, λ1 = λ2 = 0.1,
  learning rate 5e-5, gradient norm clipped at 1.

A run folder holds ``config.json``, ``split.json``, ``history.json``, ``last.pt`` (for
``--resume``) and ``best.pt`` (lowest validation reconstruction loss). Checkpoints hold
the weights, optimiser, config, split, mapping (f_ref) and RNG state, and are written
atomically. Under ``torchrun`` each step's batch of materials is sharded across ranks
(DDP: gloo on CPU, NCCL on GPU).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
import torch.distributed as dist
from tqdm.auto import tqdm

from .atomic import atomic_path, save_json
from .data import (MaterialBank, Split, list_materials, mapped_bank, read_tables,
                   split_materials)
from .losses import (FrequencyLoss, FrequencyLossConfig, FrequencyTruth, latent_penalty, reconstruction_loss,
                     weight_penalty)
from .models.autoencoder import AutoEncoder, ModelConfig
from .models.mapping import LogRelativeMapping
from .models.nbrdf import nbrdf_forward

METHODS = ("frenbrdf", "nbrdf", "hyperbrdf")
CHECKPOINT_FORMAT = 1


@dataclass
class LossConfig:
    """How the loss terms are weighted: L = L_rec + λ1 · weights + λ2 · latents + η · L_fre."""

    kind: str = "l1"
    """Reconstruction error: ``"l1"`` (paper Eq. 1) or ``"mse"`` (HyperBRDF)."""
    lambda_weights: float = 1e-3
    """λ1, on the mean squared NBRDF weight of each tensor."""
    lambda_latent: float = 1e-3
    """λ2, on the mean squared latent."""
    eta: float = 0.1
    """η, the weight of the frequency-rectified loss (0 switches it off)."""
    frequency: FrequencyLossConfig = field(default_factory=FrequencyLossConfig)

    def __post_init__(self):
        if self.kind not in ("l1", "mse"):
            raise ValueError(f"loss.kind must be 'l1' or 'mse', got {self.kind!r}")
        for name in ("lambda_weights", "lambda_latent", "eta"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"loss.{name} must be a finite number ≥ 0, got {value}")


@dataclass
class TrainConfig:
    """One training run. Saved as ``config.json`` in the run folder and in every checkpoint."""

    method: str = "frenbrdf"
    """``frenbrdf``, ``nbrdf`` or ``hyperbrdf``: which preset :func:`config_for` starts from."""
    data: str = ""
    """Folder of MERL files."""
    out: str = ""
    """Run folder (created)."""
    seed: int = 0
    """Seeds the split, the initialisation and the sampling."""
    split: tuple[float, float, float] = (0.7, 0.1, 0.2)
    """Train/validation/test fractions, by material."""
    epochs: int = 200
    """Passes over the training materials."""
    batch_materials: int = 8
    """Materials per optimisation step (sharded across ranks under DDP)."""
    context_samples: int = 4000
    """Samples per material given to the encoder."""
    query_samples: int = 4000
    """Samples per material at which the reconstruction is compared."""
    lr: float = 1e-3
    """Adam learning rate."""
    grad_clip: float = 0.0
    """Clip the gradient norm to this (0: no clipping)."""
    device: str = "cpu"
    """``"cpu"``, ``"cuda"`` or ``"auto"``."""
    cache_dir: str = ""
    """Cache of true SH coefficients (default: ``$FRENBRDF_CACHE`` or ``~/.cache/frenbrdf``)."""
    progress: bool = True
    """Show progress bars."""
    model: ModelConfig = field(default_factory=ModelConfig)
    loss: LossConfig = field(default_factory=LossConfig)

    def __post_init__(self):
        problems = []
        if self.method not in METHODS:
            problems.append(f"method must be one of {METHODS}, got {self.method!r}")
        for name in ("epochs", "batch_materials", "context_samples", "query_samples"):
            if int(getattr(self, name)) < 1:
                problems.append(f"{name} must be ≥ 1, got {getattr(self, name)}")
        if not (self.lr > 0 and math.isfinite(self.lr)):
            problems.append(f"lr must be a positive number, got {self.lr}")
        if not (self.grad_clip >= 0 and math.isfinite(self.grad_clip)):
            problems.append(f"grad_clip must be ≥ 0, got {self.grad_clip}")
        if self.device not in ("cpu", "cuda", "auto"):
            problems.append(f"device must be 'cpu', 'cuda' or 'auto', got {self.device!r}")
        if problems:
            raise ValueError("invalid training config: " + "; ".join(problems))
        self.split = tuple(self.split)


def config_for(method: str, **overrides) -> TrainConfig:
    """The preset of a method (DESIGN §6), with top-level fields overridden."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    cfg = TrainConfig(method=method, **overrides)
    if method == "nbrdf":
        cfg.loss.eta = 0.0
    elif method == "hyperbrdf":
        cfg.loss = LossConfig(kind="mse", lambda_weights=0.1, lambda_latent=0.1, eta=0.0)
        cfg.model.nbrdf.hidden = (60, 60, 60, 60)
        cfg.lr, cfg.grad_clip = 5e-5, 1.0
    return cfg


# --------------------------------------------------------------------------- config as JSON


def to_dict(config) -> dict:
    return json.loads(json.dumps(dataclasses.asdict(config)))


def from_dict(cls, data: dict, where: str = "config"):
    """Builds a (nested) dataclass from a dict, refusing unknown keys by name."""
    if not isinstance(data, dict):
        raise ValueError(f"{where} must be a JSON object, got {type(data).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} in {where}; valid keys: {sorted(fields)}")
    values = {}
    for name, value in data.items():
        default = fields[name].default_factory() if fields[name].default_factory is not dataclasses.MISSING else None
        if dataclasses.is_dataclass(default):
            values[name] = from_dict(type(default), value, f"{where}.{name}")
        else:
            values[name] = tuple(value) if isinstance(value, list) else value
    return cls(**values)


def load_config(path: str | os.PathLike, **overrides) -> TrainConfig:
    """A JSON config file (any subset of :class:`TrainConfig`'s keys) over its method's preset."""
    try:
        data = json.loads(Path(path).read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    data.update({key: value for key, value in overrides.items() if value is not None})
    base = to_dict(config_for(data.get("method", "frenbrdf")))
    return from_dict(TrainConfig, _merge(base, data), str(path))


def _merge(base: dict, update: dict) -> dict:
    merged = dict(base)
    for key, value in update.items():
        merged[key] = _merge(base[key], value) if isinstance(value, dict) and isinstance(base.get(key), dict) \
            else value
    return merged


# --------------------------------------------------------------------------- checkpoints


def save_checkpoint(path: Path, state: dict) -> None:
    """``torch.save`` to a temporary file in the same folder, then rename: never a half-written file."""
    with atomic_path(path) as temporary:
        torch.save(state, temporary)


def load_checkpoint(path: str | os.PathLike) -> dict:
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"checkpoint {path} does not exist")
    try:
        checkpoint = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises several types for damaged files
        raise ValueError(f"{path}: not a readable frenbrdf checkpoint ({error})") from None
    if not isinstance(checkpoint, dict) or checkpoint.get("format") != CHECKPOINT_FORMAT:
        raise ValueError(f"{path}: not a frenbrdf checkpoint (format {CHECKPOINT_FORMAT})")
    return checkpoint


def model_config_from_checkpoint(checkpoint: dict) -> ModelConfig:
    return from_dict(ModelConfig, json.loads(checkpoint["config"])["model"], "checkpoint model config")


# --------------------------------------------------------------------------- the loop


class TrainingDiverged(RuntimeError):
    """A loss term became NaN or infinite; the last good checkpoint is kept."""


@dataclass
class TrainResult:
    """What a run produced."""

    run_dir: Path
    best_epoch: int
    best_val: float
    """Validation reconstruction loss (L1, cosine-weighted, mapped space) of the best epoch."""
    history: list[dict]
    seconds: float


@dataclass
class _Distributed:
    rank: int = 0
    world: int = 1

    @classmethod
    def start(cls, device: torch.device) -> _Distributed:
        if int(os.environ.get("WORLD_SIZE", "1")) <= 1:
            return cls()
        if not dist.is_initialized():
            dist.init_process_group("nccl" if device.type == "cuda" else "gloo")
        return cls(dist.get_rank(), dist.get_world_size())

    @property
    def main(self) -> bool:
        return self.rank == 0

    def barrier(self):
        if self.world > 1:
            dist.barrier()


def _device(name: str, rank: int) -> torch.device:
    if name == "auto":
        name = "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda":
        if not torch.cuda.is_available():
            raise ValueError("device 'cuda' requested but torch sees no GPU; use device 'cpu'")
        return torch.device("cuda", rank % torch.cuda.device_count())
    return torch.device("cpu")


def _file_hash(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()[:32]


@dataclass
class _Terms:
    total: torch.Tensor
    logged: dict[str, float]


def loss_terms(network, frequency: FrequencyLoss | None, loss: LossConfig, context, query,
               true_coefficients: torch.Tensor | None) -> _Terms:
    """The one place where the loss is composed."""
    z, params = network(context.encoder_input())
    terms = {
        "rec": reconstruction_loss(nbrdf_forward(params, query.coords), query.values, query.cos_in, loss.kind),
        "w": loss.lambda_weights * weight_penalty(params),
        "z": loss.lambda_latent * latent_penalty(z),
    }
    if frequency is not None and true_coefficients is not None:
        terms["fre"] = frequency(params, true_coefficients)
    total = terms["rec"] + terms["w"] + terms["z"] + loss.eta * terms.get("fre", 0.0)
    return _Terms(total, {name: float(value.detach()) for name, value in terms.items()})


def _check_finite(terms: _Terms, step: int, run_dir: Path):
    bad = [name for name, value in terms.logged.items() if not math.isfinite(value)]
    if bad or not torch.isfinite(terms.total):
        raise TrainingDiverged(f"step {step}: loss term(s) {bad or ['total']} became NaN/inf; training stopped, "
                               f"the last good checkpoint is kept in {run_dir} (lower lr or eta, or set grad_clip)")


def _prepare(cfg: TrainConfig, split: Split, files: dict[str, Path], rank_info: _Distributed,
             data_cache: dict | None = None):
    """Reads the materials, builds the mapping from the training split, and the true coefficients.

    With ``data_cache`` (a dict the caller keeps), the mapping and the mapped bank are kept
    in it under the files, split and mapping settings, and later runs that share those
    reuse them instead of reading the materials again.
    """
    names = list(split.train) + list(split.val)
    key = json.dumps([[str(files[n]) for n in names], len(split.train), dataclasses.asdict(cfg.model.mapping)])
    if data_cache is not None and key in data_cache:
        mapping, bank = data_cache[key]
    else:
        tables = read_tables([files[n] for n in names], progress=cfg.progress and rank_info.main)
        mapping = LogRelativeMapping.from_tables(tables[:len(split.train)], cfg.model.mapping)
        bank = mapped_bank(names, tables, mapping)
        del tables
        if data_cache is not None:
            data_cache.clear()  # one data set at a time: a bank holds ~17 MB per material
            data_cache[key] = mapping, bank
    truth = None
    if cfg.loss.eta > 0 or cfg.method == "frenbrdf":
        cache = Path(cfg.cache_dir or os.environ.get("FRENBRDF_CACHE") or Path.home() / ".cache" / "frenbrdf")
        reference_hash = hashlib.sha256(mapping.reference.tobytes()).hexdigest()[:16]
        frequency_truth = FrequencyTruth(cfg.loss.frequency, cache / "frequency")
        coefficients = []
        # Every rank fills the cache for its share of the materials, then all read it.
        for phase in ("fill", "read"):
            mine = [i for i in range(len(names)) if phase == "read" or i % rank_info.world == rank_info.rank]
            for i in tqdm(mine, desc="true SH coefficients", disable=not (cfg.progress and rank_info.main),
                          leave=False):
                key = f"{_file_hash(files[names[i]])}-{reference_hash}"
                result = frequency_truth.coefficients(bank.mapped[i].numpy(), bank.valid[i].numpy(), key)
                if phase == "read":
                    coefficients.append(result)
            rank_info.barrier()
        truth = torch.from_numpy(np.stack(coefficients))
    return mapping, bank, truth


def train(cfg: TrainConfig, *, resume: bool = False, data_cache: dict | None = None) -> TrainResult:
    """Trains one model; see the module docstring for what the run folder holds.

    ``data_cache``: an (initially empty) dict passed to successive calls lets runs on the
    same data, split and mapping read and map the materials once (sweeps of many runs).
    """
    start = time.perf_counter()
    if not cfg.out:
        raise ValueError("config.out (the run folder) is empty")
    if not cfg.data:
        raise ValueError("config.data (the folder of MERL files) is empty")
    run_dir = Path(cfg.out)
    material_files = list_materials(cfg.data)
    files = {path.stem: path for path in material_files}
    device = _device(cfg.device, int(os.environ.get("LOCAL_RANK", "0")))
    rank_info = _Distributed.start(device)

    checkpoint = load_checkpoint(run_dir / "last.pt") if resume else None
    if checkpoint is not None:
        saved = json.loads(checkpoint["config"])
        if saved["model"] != to_dict(cfg)["model"] or saved["seed"] != cfg.seed:
            raise ValueError(f"{run_dir / 'last.pt'} was trained with another model config or seed; "
                             "resume with the run's own config.json")
        split = Split.from_json(checkpoint["split"])
        missing = sorted(set(split.train + split.val) - set(files))
        if missing:
            raise ValueError(f"the run's materials {missing[:5]} are not in {cfg.data}")
    else:
        split = split_materials(files, cfg.seed, cfg.split)
    n_train = len(split.train)
    # Full batches only (the last partial one is dropped; each epoch reshuffles), so that
    # every step's batch splits evenly across ranks.
    batch_size = min(cfg.batch_materials, n_train)
    if batch_size % rank_info.world:
        raise ValueError(f"a batch of {batch_size} materials does not split evenly across {rank_info.world} ranks; "
                         "choose batch_materials divisible by the number of ranks")
    mapping, bank, truth = _prepare(cfg, split, files, rank_info, data_cache)  # reads every file: bad data fails here
    if rank_info.main:
        run_dir.mkdir(parents=True, exist_ok=True)
        save_json(run_dir / "config.json", to_dict(cfg))
        save_json(run_dir / "split.json", split.to_json())

    torch.manual_seed(cfg.seed)
    network = AutoEncoder(cfg.model).to(device)
    frequency = FrequencyLoss(cfg.loss.frequency).to(device) if truth is not None else None
    optimizer = torch.optim.Adam(network.parameters(), lr=cfg.lr)
    generator = torch.Generator().manual_seed(cfg.seed)
    history: list[dict] = []
    best = {"epoch": -1, "val": math.inf}
    first_epoch = 0
    if checkpoint is not None:
        network.load_state_dict(checkpoint["model"])
        optimizer.load_state_dict(checkpoint["optimizer"])
        generator.set_state(checkpoint["generator"])
        history, best, first_epoch = checkpoint["history"], checkpoint["best"], checkpoint["epoch"] + 1
    trained = torch.nn.parallel.DistributedDataParallel(network) if rank_info.world > 1 else network

    def state(epoch: int) -> dict:
        return {"format": CHECKPOINT_FORMAT, "method": cfg.method, "config": json.dumps(to_dict(cfg)),
                "split": split.to_json(), "mapping": {"reference": torch.from_numpy(mapping.state()["reference"]),
                                                      "epsilon": mapping.epsilon},
                "model": network.state_dict(), "optimizer": optimizer.state_dict(),
                "generator": generator.get_state(), "epoch": epoch, "best": best, "history": history}

    if not history:  # the untrained model's validation loss: the baseline every epoch improves on
        initial = evaluate_split(network, frequency, cfg, bank, truth, range(n_train, len(bank)), device)
        history.append({"epoch": -1, **{f"val_{k}": v for k, v in initial.items()}})
    steps_per_epoch = n_train // batch_size
    bar = tqdm(total=(cfg.epochs - first_epoch) * steps_per_epoch, desc=f"train {cfg.method}",
               disable=not (cfg.progress and rank_info.main))
    for epoch in range(first_epoch, cfg.epochs):
        network.train()
        sums: dict[str, float] = {}
        order = torch.randperm(n_train, generator=generator)
        for step_in_epoch in range(steps_per_epoch):
            batch = order[step_in_epoch * batch_size:(step_in_epoch + 1) * batch_size].tolist()
            # Every rank draws the whole batch's samples (same generator), then keeps its share:
            # the run equals a single-process run on the same seed.
            context = bank.sample(batch, cfg.context_samples, generator)
            query = bank.sample(batch, cfg.query_samples, generator)
            share = slice(rank_info.rank * len(batch) // rank_info.world,
                          (rank_info.rank + 1) * len(batch) // rank_info.world)
            context, query = _take(context, share).to(device), _take(query, share).to(device)
            true = truth[batch][share].to(device) if truth is not None and cfg.loss.eta > 0 else None
            terms = loss_terms(trained, frequency, cfg.loss, context, query, true)
            _check_finite(terms, epoch * steps_per_epoch + step_in_epoch, run_dir)
            optimizer.zero_grad(set_to_none=True)
            terms.total.backward()
            if cfg.grad_clip > 0:
                torch.nn.utils.clip_grad_norm_(network.parameters(), cfg.grad_clip)
            optimizer.step()
            for name, value in terms.logged.items():
                sums[name] = sums.get(name, 0.0) + value / steps_per_epoch
            bar.update()
            bar.set_postfix({name: f"{value:.3g}" for name, value in terms.logged.items()}, refresh=False)
        validation = evaluate_split(network, frequency, cfg, bank, truth, range(n_train, len(bank)), device)
        history.append({"epoch": epoch, **{f"train_{k}": v for k, v in sums.items()},
                        **{f"val_{k}": v for k, v in validation.items()}})
        if validation["rec"] < best["val"]:
            best = {"epoch": epoch, "val": validation["rec"]}
            if rank_info.main:
                save_checkpoint(run_dir / "best.pt", state(epoch))
        if rank_info.main:
            save_checkpoint(run_dir / "last.pt", state(epoch))
            save_json(run_dir / "history.json", history)
    bar.close()
    rank_info.barrier()
    return TrainResult(run_dir, best["epoch"], best["val"], history, time.perf_counter() - start)


def _take(samples, share: slice):
    return type(samples)(samples.coords[share], samples.values[share], samples.cos_in[share])


@torch.no_grad()
def evaluate_split(network, frequency, cfg: TrainConfig, bank: MaterialBank, truth, materials, device) -> dict:
    """Mean loss terms over materials, on samples drawn from a fixed seed (the same every epoch)."""
    network.eval()
    generator = torch.Generator().manual_seed(cfg.seed + 1)
    materials = list(materials)
    sums: dict[str, float] = {}
    for start in range(0, len(materials), cfg.batch_materials):
        batch = materials[start:start + cfg.batch_materials]
        context = bank.sample(batch, cfg.context_samples, generator).to(device)
        query = bank.sample(batch, cfg.query_samples, generator).to(device)
        true = truth[batch].to(device) if truth is not None else None
        terms = loss_terms(network, frequency, cfg.loss, context, query, true)
        for name, value in terms.logged.items():
            sums[name] = sums.get(name, 0.0) + value * len(batch) / len(materials)
    return sums
