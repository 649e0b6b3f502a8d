"""Chart 9: does any L_fre variant beat η = 0? Variants × η × seeds, in and out of distribution (issue 29).

Three phases, each resumable (finished work is skipped), so that training and measuring can run on another
machine in time-limited chunks and the report anywhere: ``report`` needs only ``WORK/measured/*.json`` (bring
that folder back; without ``--data`` it measures nothing itself). ``all`` trains and measures each run in one
process (a run measured already is skipped, so a fresh machine given ``WORK/measured`` carries on), then reports:

    # 1. train every run (variants × η > 0 × seeds, and η = 0 once per seed); --jobs parallel processes
    python research/charts/chart_frequency_variants.py train --data DIR --work WORK --jobs 8 --threads 2 \\
        [--variants paper no-floor tone highlights] [--etas 0 5e-4 5e-3 0.05] [--seeds 0 1 2 3 4] \\
        [--training demo] [--epochs N] [--device cpu|cuda] [--time-limit 540]
    # 2. measure every trained run (optional here: `report` measures what is not measured yet)
    python research/charts/chart_frequency_variants.py evaluate --data DIR --work WORK --ood OOD --jobs 2
    # 3. the table, with paired 95 % intervals against η = 0 of the same seed
    python research/charts/chart_frequency_variants.py report --data DIR --work WORK --ood OOD \\
        --out research/figures --name chart9_frequency_variants

Every run is the ``frenbrdf`` preset with the ``--training`` length and default augmentation, its L_fre
variant (:data:`frenbrdf.presets.FREQUENCY_VARIANTS`) and η; η = 0 trains no L_fre, so one η = 0 run per
seed is every variant's baseline. Each run trains in its own process with ``--threads`` torch, OpenMP and
rayon threads; ``--time-limit`` stops the phase after that many seconds (the runs still training are
stopped and resume from their last epoch next time). Run folders: ``WORK/runs/<variant>/eta-<η>/seed-<s>``
(η = 0: ``WORK/runs/eta-0/seed-<s>``); the truth cache ``WORK/cache``; measurements ``WORK/measured/*.json``.

Measured per run, as ``frenbrdf evaluate`` measures: each seed's **test** materials (in distribution) and,
with ``--ood``, every material of that folder whose name is not in ``--data`` (the same for every run), each
encoded from 4000 samples, decoded, rendered at ``--resolution``: PSNR, ΔE, the highlights' PSNR and ΔE (the
truth's 5 % brightest lit pixels, :func:`frenbrdf.render.scoring.highlight_mask`), L_fre at the paper's
settings; editing over up to ``--edits`` (pair, t) of those materials (PSNR, ΔE, highlight PSNR).

Writes ``<out>/<name>.{png,csv,json}`` and prints the Markdown table.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import pyplot, run_metadata, save_chart, save_figure  # noqa: E402

VARIANTS = ("paper", "no-floor", "tone", "highlights")
ETAS = (0.0, 5e-4, 5e-3, 0.05)
SEEDS = (0, 1, 2, 3, 4)
EDIT_WEIGHTS = (0.25, 0.5, 0.75)
#: What each run is measured on (``id``: the seed's test split; ``ood``: the --ood folder), and the metrics.
RECONSTRUCTION = ("psnr", "delta_e", "highlight_psnr", "highlight_delta_e", "lfre")
EDITING = ("psnr", "delta_e", "highlight_psnr")
#: The table's columns: (set, metric), the first ones what the issue's goal is judged on.
COLUMNS = [(s, m) for s in ("id", "ood") for m in ("highlight_psnr", "edit_psnr", "psnr", "delta_e",
                                                    "highlight_delta_e", "edit_highlight_psnr", "lfre")]
THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "RAYON_NUM_THREADS")


# --------------------------------------------------------------------------- the runs


def plan(variants, etas, seeds) -> list[dict]:
    """The runs: η = 0 once per seed (no L_fre: the same for every variant), every variant at every η > 0."""
    runs = [{"variant": "paper", "eta": 0.0, "seed": s, "id": f"eta-0/seed-{s}"} for s in seeds if 0.0 in etas]
    runs += [{"variant": v, "eta": float(e), "seed": s, "id": f"{v}/eta-{e:g}/seed-{s}"}
             for v in variants for e in etas if e != 0 for s in seeds]
    return runs


def run_config(spec: dict, settings: dict):
    """The training config of one run: the frenbrdf preset, its variant and η, the sweep's settings."""
    from frenbrdf.training import config_for

    work = Path(settings["work"])
    cfg = config_for("frenbrdf", training=settings["training"], frequency=spec["variant"], data=settings["data"],
                     seed=spec["seed"], out=str(work / "runs" / spec["id"]), cache_dir=str(work / "cache"),
                     progress=False, device=settings["device"], **settings.get("overrides", {}),
                     **({"epochs": settings["epochs"]} if settings.get("epochs") else {}))
    cfg.loss.eta = spec["eta"]
    return cfg


def trained(spec: dict, settings: dict) -> bool:
    """Whether the run finished its epochs."""
    from frenbrdf.training import Run

    cfg = run_config(spec, settings)
    if not (Path(cfg.out) / "last.pt").exists():
        return False
    return len(Run(cfg.out).history) - 1 >= cfg.epochs


def train_one(spec: dict, settings: dict) -> None:
    """Trains a run, resumes it, or leaves it when finished."""
    from frenbrdf.training import train

    cfg = run_config(spec, settings)
    if trained(spec, settings):
        return
    train(cfg, resume=(Path(cfg.out) / "last.pt").exists(), overwrite=not (Path(cfg.out) / "last.pt").exists())


# --------------------------------------------------------------------------- measuring


def materials(settings: dict, run) -> dict[str, list[Path]]:
    """What a run is measured on: its seed's test split, and the --ood folder's materials not in --data."""
    from frenbrdf.data.folders import list_materials

    files = {path.stem: path for path in list_materials(settings["data"])}
    sets = {"id": [files[name] for name in sorted(run.split.test)]}
    if settings.get("ood"):
        sets["ood"] = [p for p in sorted(list_materials(settings["ood"]), key=lambda p: p.stem) if p.stem not in files]
    return sets


def measure_key(settings: dict) -> str:
    """A hash of what a measurement depends on beyond the run: a changed setting measures again."""
    described = {k: settings.get(k) for k in ("resolution", "edits", "samples")} | {"version": 1}
    described["ood"] = Path(settings["ood"]).name if settings.get("ood") else None  # the same folder elsewhere
    return hashlib.sha256(json.dumps(described, sort_keys=True).encode()).hexdigest()[:16]


def measure_one(spec: dict, settings: dict) -> dict:
    """The run's metrics on each set (means over materials and edits), cached in ``WORK/measured``."""
    from frenbrdf.io import read_material
    from frenbrdf.io.atomic import save_json
    from frenbrdf.render.renderer import Scene, material_mask, render_linear
    from frenbrdf.render.scoring import edit_metrics, reconstruction_rows
    from frenbrdf.training import Run

    cached = measured(spec, settings)
    if cached is not None:
        return cached
    path = Path(settings["work"]) / "measured" / f"{spec['id'].replace('/', '__')}.json"
    key = measure_key(settings)
    run = Run(run_config(spec, settings).out)
    model, scene = run.model(), Scene(resolution=settings["resolution"])
    mask = material_mask(scene)
    result = {"key": key, **spec, "best_epoch": run.best_epoch, "sets": {}}
    ratios = [e["train_gradient_ratio"] for e in run.history if "train_gradient_ratio" in e]
    seconds = [e["seconds"] for e in run.history if "seconds" in e]
    result.update(ratio_first=ratios[0] if ratios else 0.0, ratio_last=ratios[-1] if ratios else 0.0,
                  seconds_per_epoch=seconds[-1] / max(1, len(seconds)) if seconds else None)
    for name, files in materials(settings, run).items():
        if not files:
            continue
        latents: dict = {}
        rows = reconstruction_rows(model, files, samples=settings["samples"], resolution=settings["resolution"],
                                   progress=False, latents=latents)
        truth = {p.stem: render_linear(read_material(p), scene) for p in files}
        pairs = list(itertools.combinations(sorted(truth), 2))
        edits = list(itertools.product(pairs, EDIT_WEIGHTS))
        if len(edits) > settings["edits"]:
            chosen = np.random.default_rng(0).choice(len(edits), size=settings["edits"], replace=False)
            edits = [edits[i] for i in sorted(chosen)]
        edit_rows = [edit_metrics(model, latents[a], latents[b], truth[a], truth[b], t, scene, mask)
                     for (a, b), t in edits]
        means = {key: float(np.mean([r[key] for r in rows])) for key in RECONSTRUCTION}
        means |= {f"edit_{key}": float(np.mean([r[key] for r in edit_rows])) if edit_rows else float("nan")
                  for key in EDITING}
        result["sets"][name] = {**means, "materials": len(rows), "edits": len(edit_rows), "per_material": rows}
    path.parent.mkdir(parents=True, exist_ok=True)
    save_json(path, result)
    return result


# --------------------------------------------------------------------------- parallel processes


def run_parallel(phase: str, specs: list[dict], settings: dict, jobs: int, threads: int,
                 time_limit: float | None) -> dict[str, str]:
    """Runs ``phase`` (train or evaluate) of each spec in its own process, ``jobs`` at a time, each limited to
    ``threads`` threads. Returns each run's outcome: "done", "failed (rc)" or "stopped" (time limit)."""
    env = {**os.environ, **{name: str(threads) for name in THREAD_VARIABLES}, "PYTHONUNBUFFERED": "1"}
    deadline = time.monotonic() + time_limit if time_limit else None
    pending, running, outcome = list(specs), {}, {}
    log_dir = Path(settings["work"]) / "logs"
    log_dir.mkdir(parents=True, exist_ok=True)
    while pending or running:
        while pending and len(running) < jobs and (deadline is None or time.monotonic() < deadline):
            spec = pending.pop(0)
            log = open(log_dir / f"{phase}-{spec['id'].replace('/', '__')}.log", "w")
            command = [sys.executable, __file__, "worker", phase, json.dumps(spec), json.dumps(settings),
                       str(threads)]
            running[spec["id"]] = (subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT), log)
        for run_id, (process, log) in list(running.items()):
            if process.poll() is not None:
                log.close()
                outcome[run_id] = "done" if process.returncode == 0 else f"failed ({process.returncode})"
                print(f"{phase} {run_id}: {outcome[run_id]}", flush=True)
                del running[run_id]
        if deadline is not None and time.monotonic() >= deadline:
            for run_id, (process, log) in running.items():
                process.terminate()  # a run resumes from its last finished epoch next time
                process.wait()
                log.close()
                outcome[run_id] = "stopped"
            outcome.update({spec["id"]: "not started" for spec in pending})
            break
        time.sleep(0.2)
    return outcome


def worker(phase: str, spec: str, settings: str, threads: str) -> int:
    import torch

    torch.set_num_threads(int(threads))
    spec, settings = json.loads(spec), json.loads(settings)
    if phase in ("train", "all"):
        train_one(spec, settings)
    if phase in ("evaluate", "all"):
        measure_one(spec, settings)
    return 0


# --------------------------------------------------------------------------- the table


def summarise(measured: list[dict], variants, etas, seeds, sets=("id", "ood")) -> list[dict]:
    """One row per (variant, η): means over seeds and, against η = 0 of the same seed, the paired
    difference with its 95 % t-interval (:func:`frenbrdf.evaluation.statistics.paired_interval`)."""
    from frenbrdf.evaluation.statistics import paired_interval

    by = {(m["variant"] if m["eta"] else "baseline", m["eta"], m["seed"]): m for m in measured}
    rows = []
    for variant, eta in [("baseline", 0.0)] + [(v, e) for v in variants for e in etas if e != 0]:
        if not all((variant, eta, s) in by for s in seeds):
            continue
        row = {"variant": "η = 0 (no L_fre)" if variant == "baseline" else variant, "eta": eta}
        runs = [by[variant, eta, s] for s in seeds]
        row["ratio_first"] = float(np.mean([r["ratio_first"] for r in runs]))
        row["ratio_last"] = float(np.mean([r["ratio_last"] for r in runs]))
        for name, key in COLUMNS:
            if name not in sets or not all(name in r["sets"] for r in runs):
                continue
            values = [r["sets"][name][key] for r in runs]
            column = f"{name}_{key}"
            row[column] = float(np.mean(values))
            if variant != "baseline":
                base = [by["baseline", 0.0, s]["sets"][name][key] for s in seeds]
                d = paired_interval(np.subtract(values, base))
                row.update({f"{column}_vs_0": d["mean"], f"{column}_vs_0_low": d["low"],
                            f"{column}_vs_0_high": d["high"], f"{column}_vs_0_significant": d["significant"]})
        rows.append(row)
    return rows


def goal(rows: list[dict]) -> list[str]:
    """The rows that meet the issue's goal: highlight or editing PSNR above η = 0 with an interval excluding 0, in
    distribution, and no significant loss in any other column (step cost is measured apart: train_step.py)."""
    better = ("highlight_psnr", "edit_psnr")
    worse_if_up = ("delta_e", "highlight_delta_e")
    met = []
    for r in rows:
        if r["eta"] == 0:
            continue
        gains = [k for k in better if r.get(f"id_{k}_vs_0_significant") and r[f"id_{k}_vs_0"] > 0]
        losses = [c for c in (f"{s}_{k}" for s, k in COLUMNS if k != "lfre") if r.get(f"{c}_vs_0_significant")
                  and (r[f"{c}_vs_0"] > 0) == any(c.endswith(w) for w in worse_if_up)]
        if gains and not losses:
            met.append(f"{r['variant']} η={r['eta']:g}")
    return met


def markdown(rows: list[dict]) -> str:
    """Each column's mean over seeds and, for η > 0, its paired difference with η = 0 (bold: significant)."""
    columns = [f"{s}_{k}" for s, k in COLUMNS if any(f"{s}_{k}" in r for r in rows)]

    def cell(r, column):
        if column not in r:
            return "–"
        if r["eta"] == 0 or f"{column}_vs_0" not in r:
            return f"{r[column]:.3g}"
        low, high = r[f"{column}_vs_0_low"], r[f"{column}_vs_0_high"]
        text = (f"{r[f'{column}_vs_0']:+.2f} [{low:+.2f}, {high:+.2f}]" if low is not None
                else f"{r[f'{column}_vs_0']:+.2f}")
        return f"{r[column]:.3g} ({'**' + text + '**' if r[f'{column}_vs_0_significant'] else text})"

    names = {"highlight_psnr": "highlight PSNR", "edit_psnr": "edit PSNR", "psnr": "PSNR", "delta_e": "ΔE",
             "highlight_delta_e": "highlight ΔE", "edit_highlight_psnr": "edit highlight PSNR", "lfre": "L_fre"}
    header = ["variant", "η", "‖∇(η·L_fre)‖/‖∇L_rec‖"] + [
        f"{'in' if c.startswith('id_') else 'out of'} distr.: {names[c.split('_', 1)[1]]}" for c in columns]
    lines = ["| " + " | ".join(header) + " |", "|---" * len(header) + "|"]
    lines += [f"| {r['variant']} | {r['eta']:g} | {r['ratio_first']:.3g} → {r['ratio_last']:.3g} | "
              + " | ".join(cell(r, c) for c in columns) + " |" for r in rows]
    return "\n".join(lines)


def draw(rows: list[dict], path: Path, caption: str) -> None:
    plt = pyplot()
    panels = [c for c in ("id_highlight_psnr", "id_edit_psnr", "id_psnr", "ood_highlight_psnr", "ood_edit_psnr",
                          "ood_psnr") if any(f"{c}_vs_0" in r for r in rows)]
    figure, axes = plt.subplots(1, max(1, len(panels)), figsize=(4.2 * max(1, len(panels)), 4.2), squeeze=False)
    compared = [r for r in rows if r["eta"] != 0]
    x = np.arange(len(compared))
    variants = list(dict.fromkeys(r["variant"] for r in compared))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, column in zip(axes[0], panels, strict=False):  # one empty axis without panels
        for i, r in enumerate(compared):
            mean = r.get(f"{column}_vs_0", np.nan)
            low, high = r.get(f"{column}_vs_0_low"), r.get(f"{column}_vs_0_high")
            error = [[mean - low], [high - mean]] if low is not None else None
            ax.errorbar([i], [mean], yerr=error, fmt="o", capsize=3,
                        color=colours[variants.index(r["variant"]) % len(colours)])
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, [f"{r['variant']}\nη={r['eta']:g}" for r in compared], fontsize=6, rotation=90)
        ax.set_ylabel(f"{column.replace('_', ' ')} − η=0 (dB)")
        ax.grid(alpha=0.3)
    figure.suptitle("Chart 9 — L_fre variants against η = 0 of the same seed: paired mean and 95 % t-interval over "
                    f"seeds.\n{caption}", fontsize=9)
    figure.tight_layout()
    save_figure(figure, path, dpi=110)


# --------------------------------------------------------------------------- command line


def settings_of(args) -> dict:
    return {"data": str(args.data) if args.data else None, "work": str(args.work), "training": args.training, "epochs": args.epochs,
            "device": args.device, "ood": str(args.ood) if args.ood else None, "resolution": args.resolution,
            "edits": args.edits, "samples": 4000, "overrides": json.loads(args.overrides) if args.overrides else {}}


def main(argv=None) -> int:
    if (argv or sys.argv[1:])[:1] == ["worker"]:
        return worker(*(argv or sys.argv[1:])[1:])
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("phase", choices=("train", "evaluate", "report", "all"))
    parser.add_argument("--data", type=Path, help="folder of the training materials (train, evaluate)")
    parser.add_argument("--work", type=Path, default=Path("bench-results/frequency-variants"))
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS))
    parser.add_argument("--etas", type=float, nargs="+", default=list(ETAS))
    parser.add_argument("--seeds", type=int, nargs="+", default=list(SEEDS))
    parser.add_argument("--training", default="demo", help="training length of frenbrdf.presets (default demo)")
    parser.add_argument("--epochs", type=int, help="override the training length's epochs")
    parser.add_argument("--device", default="cpu", choices=("cpu", "cuda", "auto"))
    parser.add_argument("--overrides", help="JSON of further TrainConfig fields (nested), e.g. for tests")
    parser.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 2) // 2), help="parallel processes")
    parser.add_argument("--threads", type=int, default=2, help="torch/OpenMP/rayon threads per process")
    parser.add_argument("--time-limit", type=float, help="stop this phase after so many seconds (resume later)")
    parser.add_argument("--ood", type=Path, help="folder of out-of-distribution materials")
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--edits", type=int, default=120, help="at most this many (pair, t) edits per set")
    parser.add_argument("--out", type=Path, default=Path("research/figures"))
    parser.add_argument("--name", default="chart9_frequency_variants")
    args = parser.parse_args(argv)
    if 0.0 not in args.etas:
        raise SystemExit("--etas must include 0, the baseline every run is compared with")
    if args.data is None and args.phase != "report":
        raise SystemExit(f"{args.phase} needs --data, the folder of the training materials")
    from frenbrdf.presets import FREQUENCY_VARIANTS

    unknown = sorted(set(args.variants) - set(FREQUENCY_VARIANTS))
    if unknown:
        raise SystemExit(f"unknown variants {unknown}; choose from {sorted(FREQUENCY_VARIANTS)}")
    settings, specs = settings_of(args), plan(args.variants, args.etas, args.seeds)
    start = time.perf_counter()
    outcome = {}
    if args.phase in ("train", "all"):
        # A run measured already (WORK/measured, e.g. brought from an earlier machine) is not trained again.
        todo = [s for s in specs if measured(s, settings) is None and not (args.phase == "train" and trained(s, settings))]
        print(f"{args.phase}: {len(specs) - len(todo)} of {len(specs)} runs done, {len(todo)} to "
              + ("train" if args.phase == "train" else "train (or resume) and measure"), flush=True)
        outcome = run_parallel(args.phase, todo, settings, args.jobs, args.threads, args.time_limit)
        if any(v != "done" for v in outcome.values()):
            print(json.dumps(outcome, indent=1))
            return 0 if all(v in ("done", "stopped", "not started") for v in outcome.values()) else 1
    if args.phase == "evaluate" or (args.phase == "report" and args.data):
        todo = [s for s in specs if measured(s, settings) is None and trained(s, settings)]
        print(f"evaluate: {sum(measured(s, settings) is not None for s in specs)} of {len(specs)} runs measured, "
              f"{len(todo)} trained runs to measure", flush=True)
        remaining = None if args.time_limit is None else max(1.0, args.time_limit - (time.perf_counter() - start))
        outcome = run_parallel("evaluate", todo, settings, args.jobs, args.threads, remaining)
    if args.phase in ("report", "all"):
        # Without --data nothing is measured here: the report takes the measurements as they were made.
        results = [m for m in (measured(s, settings, any_settings=args.data is None) for s in specs) if m is not None]
        if len({m["key"] for m in results}) > 1:
            raise SystemExit("the runs were measured with different settings (--ood, --resolution, --edits); measure "
                             "them again with one set (evaluate --data …)")
        missing = len(specs) - len(results)
        if missing:
            print(f"report: {missing} of {len(specs)} runs not measured; their (variant, η) rows are left out")
        rows = summarise(results, args.variants, args.etas, args.seeds)
        caption = (f"{args.data.name if args.data else Path(settings['work']).name}, {args.training} training, seeds {', '.join(map(str, args.seeds))}; in "
                   f"distribution: each seed's test split" + (f"; out of distribution: {args.ood.name}" if args.ood
                                                              else "") + ".")
        report = {"chart": "frequency_variants", "settings": settings, "variants": args.variants, "etas": args.etas,
                  "seeds": args.seeds, "run": run_metadata(), "goal_met_by": goal(rows), "rows": rows,
                  "runs": results}
        save_chart(args.out, args.name, rows, report, lambda path: draw(rows, path, caption))
        print(markdown(rows))
        print(f"goal met by: {', '.join(report['goal_met_by']) or 'none'}")
        print(f"wrote {args.out / args.name}.{{png,csv,json}}")
    return 0


def measured(spec: dict, settings: dict, any_settings: bool = False) -> dict | None:
    """The run's measurement in ``WORK/measured`` when it was made with these settings (``any_settings``: with
    whatever settings), else None: the report needs only these files, not the run folders (bring
    ``WORK/measured`` back from the machine that trained)."""
    path = Path(settings["work"]) / "measured" / f"{spec['id'].replace('/', '__')}.json"
    if path.exists():
        cached = json.loads(path.read_text())
        if any_settings or cached.get("key") == measure_key(settings):
            return cached
    return None


if __name__ == "__main__":
    sys.exit(main())
