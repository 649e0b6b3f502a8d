"""Helpers shared by the scripts of ``benches/``, and the conventions their charts follow.

The scripts live by kind: ``peers/`` (comparisons with other libraries), ``charts/`` (each
chart and its sweeps), ``studies/`` (one-off measurements behind a doc); ``pretrained.py``
packs the shipped model. They run as ``python benches/KIND/NAME.py`` and are also loaded by
path (``tests/test_charts.py``), so each puts its own folder and ``benches/`` on ``sys.path``
before ``import common``.

Nothing heavy is imported here at module level: the SHT peer workers import this module in
processes that time other libraries, so frenbrdf (and with it torch) and matplotlib are
imported only inside the functions that need them.

Timing
    :func:`time_calls` (warm-up, samples of back-to-back calls, :class:`Timing`),
    :func:`median_seconds`; :func:`time_interleaved` (two contenders in alternating rounds,
    for a ratio that the machine's drift does not bias); :class:`CpuMeter` (how much of the machine other processes
    used meanwhile), :func:`busy_cpu_seconds`, :func:`own_cpu_seconds`.
Inputs
    :func:`unit_vectors`, :func:`gaussian_weighting` (the numpy weighting that kNN peers
    need to compute what ``frenbrdf.KnnInterpolator`` computes).
Charts
    A chart is written as a trio beside each other: ``<name>.png``, ``<name>.csv`` (the
    plotted numbers) and ``<name>.json`` (those, the settings and the details), every file
    atomically (:func:`save_chart`, :func:`save_figure`); figures are drawn with the
    ``Agg`` backend (:func:`pyplot`); the JSON holds a ``run`` block (:func:`run_metadata`:
    the command, the CPU, the time).
"""

from __future__ import annotations

import math
import os
import platform
import shlex
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

#: Environment variables that set thread counts; :func:`run_metadata` records those set.
THREAD_ENV = ("RAYON_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


# ---------------------------------------------------------------------------------------
# Timing


@dataclass
class Timing:
    """What :func:`time_calls` measured."""

    samples_s: list[float]
    """Seconds per call, one entry per sample."""
    calls: int = 1
    """Back-to-back calls in each sample."""
    first_s: float | None = None
    """The warm-up call (None without one): compilation, caches, thread pools, allocator."""

    @property
    def median_s(self) -> float:
        return statistics.median(self.samples_s)

    @property
    def best_s(self) -> float:
        """The fastest sample: on a shared machine other work only slows calls down."""
        return min(self.samples_s)


def time_calls(function: Callable[[], object], repeats: int, *, warmup: bool = True, min_sample_s: float = 0.0,
               budget_s: float | None = None) -> Timing:
    """Times ``repeats`` samples of ``function()``, after one warm-up call.

    Parameters
    ----------
    function
        Called without arguments; what it returns is dropped at once.
    repeats
        Number of samples.
    warmup
        Call once first, timed apart (:attr:`Timing.first_s`). ``min_sample_s`` and
        ``budget_s`` scale from that call's time, so they need it.
    min_sample_s
        Each sample repeats the call back to back until it lasts at least this long: a
        sample of one sub-millisecond call is at the mercy of a single wake-up or
        preemption on a shared machine.
    budget_s
        Take fewer samples (but at least 3, or ``repeats`` if fewer) when ``repeats`` of
        them would last longer than this, judged from the warm-up call.
    """
    if not warmup and (min_sample_s > 0 or budget_s is not None):
        raise ValueError("min_sample_s and budget_s are judged from the warm-up call: they need warmup=True")
    first, calls, count = None, 1, repeats
    if warmup:
        start = time.perf_counter()
        function()
        first = time.perf_counter() - start
        elapsed = max(first, 1e-9)
        calls = max(1, math.ceil(min_sample_s / elapsed))
        if budget_s is not None:
            count = max(min(3, repeats), min(repeats, int(budget_s / (elapsed * calls))))
    samples = []
    for _ in range(count):
        start = time.perf_counter()
        for _ in range(calls):
            function()
        samples.append((time.perf_counter() - start) / calls)
    return Timing(samples, calls, first)


def median_seconds(function: Callable[[], object], repeats: int) -> float:
    """Median of ``repeats`` one-call samples after a warm-up call (see :func:`time_calls`)."""
    return time_calls(function, repeats).median_s


@dataclass
class Interleaved:
    """What :func:`time_interleaved` measured: seconds per call of two contenders, round by round."""

    first_s: list[float]
    second_s: list[float]

    @property
    def ratios(self) -> list[float]:
        """second / first per round: how many times faster the first was in that round."""
        return [b / a for a, b in zip(self.first_s, self.second_s, strict=True)]

    def ratio_summary(self) -> dict:
        """The median ratio, its quartiles and range, and each contender's median seconds."""
        # Inclusive: with few rounds the default method extrapolates beyond the range.
        quartiles = statistics.quantiles(self.ratios, n=4, method="inclusive") if len(self.ratios) > 1 else self.ratios * 3
        return {"median": statistics.median(self.ratios), "quartiles": [quartiles[0], quartiles[2]],
                "range": [min(self.ratios), max(self.ratios)], "rounds": len(self.ratios),
                "first_median_s": statistics.median(self.first_s), "second_median_s": statistics.median(self.second_s)}


def time_interleaved(first: Callable[[], object], second: Callable[[], object], rounds: int,
                     calls: int = 3, pause_s: float = 0.05) -> Interleaved:
    """Times two contenders in alternating rounds, each round the best of ``calls`` calls of each.

    On a shared or virtual machine the speed drifts by tens of percent within a minute; timing one
    contender after the other puts that drift into their ratio. Alternating them (and which goes
    first) gives both the same conditions round by round, so the per-round ratios are comparable
    even where the absolute times are not. Both are called once first as a warm-up. Each turn
    starts after ``pause_s`` of sleep, so that the other's worker threads, which spin a while
    after their work, have gone to sleep and take no core from it.
    """
    if rounds < 1 or calls < 1:
        raise ValueError(f"rounds and calls must be at least 1, got {rounds} and {calls}")
    first(), second()

    def best(function: Callable[[], object]) -> float:
        time.sleep(pause_s)
        times = []
        for _ in range(calls):
            start = time.perf_counter()
            function()
            times.append(time.perf_counter() - start)
        return min(times)

    first_s, second_s = [], []
    for round_ in range(rounds):
        if round_ % 2:
            second_s.append(best(second))
            first_s.append(best(first))
        else:
            first_s.append(best(first))
            second_s.append(best(second))
    return Interleaved(first_s, second_s)


def busy_cpu_seconds() -> float | None:
    """Machine-wide busy CPU time (all processes), from /proc/stat; None off Linux."""
    try:
        values = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    except (OSError, ValueError):
        return None
    idle = values[3] + values[4]  # idle + iowait
    return (sum(values) - idle) / os.sysconf("SC_CLK_TCK")


def own_cpu_seconds() -> float:
    """CPU time of this process and of its waited-for children, user and system."""
    import resource

    return sum(getattr(resource.getrusage(who), field) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)
               for field in ("ru_utime", "ru_stime"))


class CpuMeter:
    """How much of the machine's CPU other processes used while something was measured.

    >>> meter = CpuMeter()          # doctest: +SKIP
    >>> ...                         # the measurement, in this process or its children
    >>> wall_s, background = meter.read()

    ``background`` is the busy CPU time of the whole machine (/proc/stat), less this
    process's and its children's, as a share of every core over the wall time; None off
    Linux. Children count once they have been waited for.
    """

    def __init__(self):
        self.busy, self.own, self.start = busy_cpu_seconds(), own_cpu_seconds(), time.perf_counter()

    def read(self) -> tuple[float, float | None]:
        """Seconds since the meter was made, and the share of the machine other processes used in them."""
        wall, busy = time.perf_counter() - self.start, busy_cpu_seconds()
        if self.busy is None or busy is None:
            return wall, None
        other = busy - self.busy - (own_cpu_seconds() - self.own)
        return wall, max(0.0, other / (wall * (os.cpu_count() or 1)))


# ---------------------------------------------------------------------------------------
# Inputs


def material_folder(data: Path | None, scratch: str | os.PathLike, n: int = 16) -> Path:
    """``data``, or without it the first ``n`` materials of the default bank written into ``scratch``."""
    if data is not None:
        return Path(data)
    from frenbrdf.data.synth import write_bank

    write_bank(scratch, n=n, seed=0, progress=False)
    return Path(scratch)


def unit_vectors(rng: np.random.Generator, n: int, hemisphere: bool = False) -> np.ndarray:
    """``n`` random directions ``(n, 3)``, uniform on the sphere, or on the upper (z ≥ 0) hemisphere."""
    v = rng.normal(size=(n, 3))
    if hemisphere:
        v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def gaussian_weighting(squared: np.ndarray, indices: np.ndarray, values: np.ndarray, sigma: float) -> np.ndarray:
    """FreNBRDF Eq. 5–7 in numpy, weights relative to the nearest neighbour (as frenbrdf does).

    ``squared``: squared distances of the k nearest sources ``(m, k)``, nearest first;
    ``indices``: those sources ``(m, k)``; ``values``: every source's channels ``(n, C)``.
    Returns the weighted means ``(m, C)``.
    """
    w = np.exp(-(squared - squared[:, :1]) / (2 * sigma**2))
    w /= w.sum(axis=1, keepdims=True)
    return np.einsum("mk,mkc->mc", w, values[indices])


# ---------------------------------------------------------------------------------------
# Charts


def pyplot():
    """``matplotlib.pyplot`` on the non-interactive ``Agg`` backend (charts are files)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(figure, path: str | os.PathLike, dpi: int = 100) -> None:
    """Writes a figure as a PNG atomically (:func:`frenbrdf.render.save_figure`) and closes it."""
    from frenbrdf.render.renderer import save_figure as save

    save(figure, path, dpi=dpi)
    pyplot().close(figure)


def render_sheet(rows: dict[str, dict[str, np.ndarray]], path: str | os.PathLike, *, columns=None, title=None,
                 fontsize: int = 7) -> None:
    """A PNG of renders: one row per material (``rows``: name → column → display image), one column per name of
    ``columns`` (default: every column, in the order first met); a column a row lacks stays empty.
    ``title(name, column)`` labels each image (default: the column)."""
    plt = pyplot()
    columns = columns or list(dict.fromkeys(column for images in rows.values() for column in images))
    figure, axes = plt.subplots(len(rows), len(columns), figsize=(2 * len(columns), 2.1 * len(rows)), squeeze=False)
    for row, (name, images) in zip(axes, rows.items(), strict=True):
        for axis, column in zip(row, columns, strict=True):
            if column in images:
                axis.imshow(images[column])
            axis.set_xticks([]), axis.set_yticks([])
            axis.set_title(title(name, column) if title else column, fontsize=fontsize)
        row[0].set_ylabel(name, fontsize=7)
    save_figure(figure, path)


def cpu_model() -> str:
    """The CPU's model name (``lscpu``), else what :mod:`platform` knows."""
    try:
        output = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10,
                                env={**os.environ, "LC_ALL": "C"}).stdout
    except (OSError, subprocess.SubprocessError):
        output = ""
    for line in output.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "Model name" and value.strip():
            return value.strip()
    return platform.processor() or platform.machine()


def run_metadata() -> dict:
    """Where a result comes from: the command that ran (with the thread variables set in the
    environment), the CPU, its core count and when it started (UTC)."""
    threads = [f"{name}={os.environ[name]}" for name in THREAD_ENV if name in os.environ]
    return {"command": " ".join([*threads, "python", shlex.join(sys.argv)]), "cpu": cpu_model(),
            "cores": os.cpu_count(), "time": datetime.now(timezone.utc).isoformat(timespec="seconds")}


def save_chart(out_dir: str | os.PathLike, name: str, rows: list[dict], report: dict,
               draw: Callable[[Path], None]) -> dict[str, Path]:
    """Writes a chart: ``<name>.csv`` (``rows``), ``<name>.json`` (``report``), then ``<name>.png``.

    Parameters
    ----------
    out_dir
        Folder of the three files (made if missing).
    rows
        The plotted numbers, one dict per CSV row (:func:`frenbrdf.io.atomic.save_csv`).
    report
        Everything else worth keeping (settings, details, :func:`run_metadata`).
    draw
        Draws the figure and writes it to the path it is given (with :func:`save_figure`).

    Returns
    -------
    dict
        The paths written, under ``"csv"``, ``"json"`` and ``"png"``.
    """
    from frenbrdf.io.atomic import save_csv, save_json

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {suffix: out / f"{name}.{suffix}" for suffix in ("csv", "json", "png")}
    save_csv(paths["csv"], rows)
    save_json(paths["json"], report)
    draw(paths["png"])
    return paths
