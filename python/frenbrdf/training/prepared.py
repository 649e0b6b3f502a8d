"""What a run trains on: the split's materials read and mapped, and the true SH coefficients.

:func:`prepare` is shared by training and by the step timing of ``benches/step_timing.py``;
:class:`Distributed` and :func:`select_device` say where a process runs (DDP under
``torchrun``: gloo on CPU, NCCL on GPU).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import torch.distributed as dist
from tqdm.auto import tqdm

from ..data.folders import MaterialBank, Split, files_mapping, mapped_bank, max_directional_albedo, read_valid_table
from ..io.merl import N_BINS
from ..models.losses import FrequencyTruth
from ..models.mapping import LogRelativeMapping
from .config import TrainConfig


@dataclass(frozen=True)  # immutable: ``Distributed()`` is a default argument (pyproject.toml, extend-immutable-calls)
class Distributed:
    """This process's rank among ``world`` (1 without ``torchrun``)."""

    rank: int = 0
    world: int = 1

    @classmethod
    def start(cls, device: torch.device) -> Distributed:
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


def select_device(name: str, rank: int = 0) -> torch.device:
    """``"cpu"``, ``"cuda"`` (one GPU per rank) or ``"auto"`` as a torch device."""
    if name == "auto":
        name = "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda":
        if not torch.cuda.is_available():
            raise ValueError("device 'cuda' requested but torch sees no GPU; use device 'cpu'")
        return torch.device("cuda", rank % torch.cuda.device_count())
    return torch.device("cpu")


@dataclass
class PreparedData:
    """The training and validation materials of a split, ready to sample."""

    split: Split
    mapping: LogRelativeMapping
    """Built from the training materials."""
    bank: MaterialBank
    """Training materials first, then validation, in split order."""
    truth: torch.Tensor | None
    """True SH coefficients ``(M, S, 3, ncoeff)`` in bank order, or None without L_fre."""
    albedo: torch.Tensor | None = None
    """The training materials' largest directional albedo per channel ``(n_train, 3)``
    (:func:`frenbrdf.data.folders.max_directional_albedo`), computed for gain augmentation only."""

    @property
    def n_train(self) -> int:
        return len(self.split.train)

    @property
    def validation(self) -> range:
        """Bank indices of the validation materials."""
        return range(self.n_train, len(self.bank))


def file_hash(path: Path) -> str:
    """A content hash of a file (the cache key of what is computed from it)."""
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()[:32]


#: Bytes the mapped bank holds per material: float32 values and a validity flag at every MERL bin.
BANK_BYTES_PER_MATERIAL = N_BINS * 3 * 4 + N_BINS
#: The share of this machine's memory the bank may take (the rest: the model, the batches, the truth).
BANK_MEMORY_SHARE = 0.5


def check_bank_memory(n_materials: int) -> None:
    """Refuses, before any table is read, a training set whose mapped bank would not fit in memory."""
    needed = n_materials * BANK_BYTES_PER_MATERIAL
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    if needed > BANK_MEMORY_SHARE * total:
        most = int(BANK_MEMORY_SHARE * total // BANK_BYTES_PER_MATERIAL)
        raise ValueError(f"training and validation hold {n_materials:,} materials: {needed / 1e9:.1f} GB in memory "
                         f"({BANK_BYTES_PER_MATERIAL / 1e6:.1f} MB each); this machine ({total / 1e9:.0f} GB) takes "
                         f"at most {most:,}: train on fewer (a subfolder, or --holdout)")


def prepare(cfg: TrainConfig, split: Split, files: dict[str, Path], ranks: Distributed = Distributed(),
            data_cache: dict | None = None, mapping: LogRelativeMapping | None = None) -> PreparedData:
    """Reads the materials, builds the mapping from the training split (unless ``mapping`` is given: a
    trained decoder's), and the true coefficients.

    With ``data_cache`` (a dict the caller keeps), the mapping and the mapped bank are kept
    in it under the files, split and mapping settings, and later runs that share those
    reuse them instead of reading the materials again.
    """
    names = list(split.train) + list(split.val)
    check_bank_memory(len(names))
    key = json.dumps([[str(files[n]) for n in names], len(split.train), dataclasses.asdict(cfg.model.mapping),
                      cfg.decoder_from, cfg.init_from])
    if data_cache is not None and key in data_cache:
        mapping, bank = data_cache[key]
    else:
        # Read as needed, never all tables at once (~35 MB a material in float64): only the bank stays.
        progress = cfg.progress and ranks.main
        mapping = mapping or files_mapping([files[n] for n in split.train], cfg.model.mapping, progress)
        tables = (read_valid_table(files[n]) for n in tqdm(names, desc="reading materials", disable=not progress,
                                                            leave=False))
        bank = mapped_bank(names, tables, mapping)
        if data_cache is not None:
            data_cache.clear()  # one data set at a time: a bank holds ~17 MB per material
            data_cache[key] = mapping, bank
    truth = None
    if cfg.loss.eta > 0 or cfg.method == "frenbrdf":
        truth = _true_coefficients(cfg, names, files, mapping, bank, ranks)
    albedo = max_directional_albedo(bank, mapping, range(len(split.train))) if cfg.augment.gain > 0 else None
    return PreparedData(split, mapping, bank, truth, albedo)


def _true_coefficients(cfg: TrainConfig, names, files, mapping, bank, ranks: Distributed) -> torch.Tensor:
    frequency_truth = FrequencyTruth(cfg.loss.frequency, cfg.cache_folder / "frequency", mapping)
    coefficients = []
    # Every rank fills the cache for its share of the materials, then all read it.
    for phase in ("fill", "read"):
        mine = [i for i in range(len(names)) if phase == "read" or i % ranks.world == ranks.rank]
        for i in tqdm(mine, desc="true SH coefficients", disable=not (cfg.progress and ranks.main), leave=False):
            key = frequency_truth.cache_key(file_hash(files[names[i]]), mapping)
            result = frequency_truth.coefficients(bank.mapped[i].numpy(), bank.valid[i].numpy(), key)
            if phase == "read":
                coefficients.append(result)
        ranks.barrier()
    return torch.from_numpy(np.stack(coefficients))
