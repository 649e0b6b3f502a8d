"""Timing of training steps and of decoded NBRDFs, for the benchmarks and the research sweeps.

Research tooling, not part of the installed package: the research scripts (``research/charts/sweeps.py``,
``research/studies/train_step.py``, ``research/studies/augment_step.py``) put ``benches/`` on ``sys.path`` and
import it as ``step_timing``.

- :func:`time_training_step`: one optimisation step of a config (the training code's own
  :func:`~frenbrdf.training.optimisation_step`), with and without the frequency term;
- :func:`time_frequency_variants`: the same step with each L_fre variant, timed side by side;
- :func:`nbrdf_throughput`: queries per second of decoded NBRDFs, timed in turn;
- :func:`timed_seconds`: the interleaved timer they all use.
"""

from __future__ import annotations

import dataclasses
import statistics
import time

import numpy as np
import torch

from frenbrdf.data.folders import list_materials, split_materials
from frenbrdf.models.autoencoder import AutoEncoder
from frenbrdf.models.losses import FrequencyLoss, FrequencyLossConfig
from frenbrdf.models.nbrdf import N_INPUTS, NBRDF
from frenbrdf.training import TrainConfig, optimisation_step, prepare
from frenbrdf.training.loop import make_optimizer


def timed_seconds(functions: dict, steps: int, device: torch.device, *, warmup: int = 3,
                  statistic=statistics.median) -> dict[str, float]:
    """Time of each function over ``steps`` calls (median by default; ``statistic=min`` resists load from other
    processes), calls interleaved so that drift affects all alike."""
    times: dict[str, list[float]] = {name: [] for name in functions}
    for i in range(steps + warmup):
        for name, function in functions.items():
            if device.type == "cuda":
                torch.cuda.synchronize()
            start = time.perf_counter()
            function()
            if device.type == "cuda":
                torch.cuda.synchronize()
            if i >= warmup:
                times[name].append(time.perf_counter() - start)
    return {name: statistic(values) for name, values in times.items()}


def time_training_step(cfg: TrainConfig, steps: int = 30, device: torch.device | str = "cpu", *,
                       data_cache: dict | None = None, statistic=statistics.median) -> dict:
    """Time (median of ``steps``, or ``statistic``) of one optimisation step of ``cfg`` on a batch of
    ``cfg.data``'s training materials.

    With L_fre (η > 0) it also times the same step without the frequency term (same model,
    same samples), so the difference is what L_fre adds, and the parts of L_fre alone.
    ``cfg.data`` needs only ``cfg.batch_materials`` training materials; ``data_cache`` as in
    :func:`frenbrdf.training.train`.
    """
    device = torch.device(device)
    files = {path.stem: path for path in list_materials(cfg.data)}
    split = split_materials(files, cfg.seed, cfg.split)
    data = prepare(cfg, split, files, data_cache=data_cache)
    bank, truth = data.bank, data.truth
    torch.manual_seed(0)
    network = AutoEncoder(cfg.model).to(device)
    frequency = FrequencyLoss(cfg.loss.frequency, data.mapping).to(device)
    optimizer = make_optimizer(network, cfg)  # Adam, or AdamW with weight decay: as training builds it
    generator = torch.Generator().manual_seed(0)
    batch = list(range(min(cfg.batch_materials, len(split.train))))
    context = bank.sample(batch, cfg.context_samples, generator).to(device)
    query = bank.sample(batch, cfg.query_samples, generator).to(device)
    true = truth[batch].to(device) if truth is not None else None

    def step(with_frequency: bool):
        optimisation_step(network, frequency if with_frequency else None, optimizer, cfg.loss, cfg.grad_clip, context,
                          query, true if with_frequency else None)

    result = {"method": cfg.method, "nbrdf_hidden": list(cfg.model.nbrdf.hidden), "batch_materials": len(batch),
              "samples": [cfg.context_samples, cfg.query_samples], "eta": cfg.loss.eta}
    if cfg.loss.eta == 0:
        result["step_s"] = timed_seconds({"step": lambda: step(False)}, steps, device, statistic=statistic)["step"]
        return result
    params = [p.detach().requires_grad_() for p in network(context.encoder_input())[1]]
    timed = timed_seconds({"step": lambda: step(True), "without": lambda: step(False),
                           "nbrdf_eval": lambda: frequency.predicted_maps(params),
                           "fre": lambda: frequency(params, true).backward()}, steps, device, statistic=statistic)
    result.update(step_s=timed["step"], step_without_fre_s=timed["without"],
                  fre_added_share=timed["step"] / timed["without"] - 1,
                  fre_nbrdf_eval_s=timed["nbrdf_eval"], fre_forward_backward_s=timed["fre"])
    return result


def time_frequency_variants(cfg: TrainConfig, variants: dict[str, FrequencyLossConfig], steps: int = 30,
                            device: torch.device | str = "cpu", *, statistic=min) -> dict[str, float]:
    """Seconds of one optimisation step of ``cfg`` with each L_fre setting of ``variants`` (name → settings) and
    without L_fre (``"without L_fre"``), timed interleaved (:func:`timed_seconds`; ``min`` by default, which
    resists load from other processes), so that their ratios come from the same minutes.

    Every variant starts from the same initialisation and steps on the same samples of the same training
    materials; only the frequency term (its truth, its transform) differs.
    """
    device = torch.device(device)
    files = {path.stem: path for path in list_materials(cfg.data)}
    split = split_materials(files, cfg.seed, cfg.split)
    data_cache: dict = {}
    functions = {}
    for name, frequency in variants.items():
        config = dataclasses.replace(cfg, loss=dataclasses.replace(cfg.loss, frequency=frequency))
        data = prepare(config, split, files, data_cache=data_cache)
        torch.manual_seed(0)
        network = AutoEncoder(cfg.model).to(device)
        loss = FrequencyLoss(frequency, data.mapping).to(device)
        optimizer = make_optimizer(network, config)
        generator = torch.Generator().manual_seed(0)
        batch = list(range(min(cfg.batch_materials, len(split.train))))
        context = data.bank.sample(batch, cfg.context_samples, generator).to(device)
        query = data.bank.sample(batch, cfg.query_samples, generator).to(device)
        true = data.truth[batch].to(device)
        functions[name] = (lambda network=network, loss=loss, optimizer=optimizer, config=config, context=context,
                           query=query, true=true: optimisation_step(network, loss, optimizer, config.loss,
                                                                     config.grad_clip, context, query, true))
        if "without L_fre" not in functions:
            functions["without L_fre"] = (lambda network=network, optimizer=optimizer, config=config, context=context,
                                          query=query: optimisation_step(network, None, optimizer, config.loss,
                                                                         config.grad_clip, context, query, None))
    return timed_seconds(functions, steps, device, statistic=statistic)


def nbrdf_throughput(nbrdfs: dict[str, NBRDF], queries: int = 1 << 18, repeats: int = 40,
                     threads: int = 1) -> dict[str, float]:
    """Queries per second of :meth:`NBRDF.mapped` (one material each, CPU) on ``threads`` torch threads.

    The NBRDFs are timed in turn, round after round, and each counts its fastest of
    ``repeats`` calls: the one least disturbed by other processes.
    """
    coords = np.random.default_rng(0).uniform(-1, 1, (queries, N_INPUTS)).astype(np.float32)
    previous = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        seconds = timed_seconds({name: (lambda nbrdf=nbrdf: nbrdf.mapped(coords)) for name, nbrdf in nbrdfs.items()},
                                repeats, torch.device("cpu"), warmup=2, statistic=min)
    finally:
        torch.set_num_threads(previous)
    return {name: queries / value for name, value in seconds.items()}

