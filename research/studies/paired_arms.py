"""Two training arms run on the same seeds, read and paired per test material: the input-variant studies' runs
(:func:`train_and_read`) and rule (:func:`decide`).

Each run of an arm writes ``WORK/ARM-SEED.json`` with its test-split rows (``test``: per material ``psnr``,
``delta_e`` and ``refined_*``, as ``evaluate_runs`` reports them) and its seam steps on the measurements (``seam``:
per measurement and budget, the median and 90th percentile; research/studies/seam.py).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy import stats

#: The readings of a test row: the encoder's columns, and `latent`'s under a prefix.
READINGS = (("encoder", ""), ("latent", "refined_"))


def interval(values) -> tuple[float, float, float]:
    """The mean and its 95 % t-interval."""
    values = np.asarray(values)
    half = stats.t.ppf(0.975, len(values) - 1) * values.std(ddof=1) / np.sqrt(len(values))
    return float(values.mean()), float(values.mean() - half), float(values.mean() + half)


def load_arms(work: Path, arms: tuple[str, ...]) -> dict[str, dict[int, dict]]:
    """Each arm's runs by seed."""
    runs: dict[str, dict[int, dict]] = {}
    for arm in arms:
        for path in work.glob(f"{arm}-*.json"):
            run = json.loads(path.read_text())
            runs.setdefault(arm, {})[run["seed"]] = run
    return runs


def paired_differences(runs: dict, base: str, arm: str) -> dict:
    """``arm`` − ``base`` per material and seed, for the encoder and `latent`: pairs, PSNR and ΔE (mean, interval),
    and whether the arm is harmless (PSNR's lower end above −0.5 dB, mean ΔE below +0.5)."""
    seeds = sorted(set(runs[base]) & set(runs[arm]))
    result: dict = {"seeds": seeds}
    for reading, prefix in READINGS:
        differences: dict[str, list[float]] = {"psnr": [], "delta_e": []}
        for seed in seeds:
            base_rows = {row["material"]: row for row in runs[base][seed]["test"]}
            for row in runs[arm][seed]["test"]:
                for key in differences:
                    differences[key].append(row[prefix + key] - base_rows[row["material"]][prefix + key])
        psnr, delta_e = interval(differences["psnr"]), interval(differences["delta_e"])
        result[reading] = {"pairs": len(differences["psnr"]), "psnr": psnr, "delta_e": delta_e,
                           "harmless": psnr[1] > -0.5 and delta_e[0] < 0.5}
        print(f"{reading}: {arm} − {base} over {len(differences['psnr'])} pairs: PSNR {psnr[0]:+.2f} dB "
              f"[{psnr[1]:+.2f}, {psnr[2]:+.2f}], ΔE {delta_e[0]:+.2f} [{delta_e[1]:+.2f}, {delta_e[2]:+.2f}]")
    return result


def seam_steps(runs: dict, arm: str, budgets: tuple[str, ...]) -> dict:
    """Per budget, the median over the seeds every arm ran of the measurements' median step and of their 90th
    percentile."""
    seeds = sorted(set.intersection(*(set(by_seed) for by_seed in runs.values())))
    steps = {}
    for budget in budgets:
        median = np.median([np.median([row[budget]["median"] for row in runs[arm][seed]["seam"].values()])
                            for seed in seeds])
        p90 = np.median([np.median([row[budget]["p90"] for row in runs[arm][seed]["seam"].values()])
                         for seed in seeds])
        steps[budget] = {"median": float(median), "p90": float(p90)}
        print(f"seam, {arm}, {budget}: median step {median:.4f}, p90 {p90:.4f}")
    return steps


def decide(description: str, default_arm: str, budgets: tuple[str, ...],
           removes_seam: Callable[[dict, str], bool]) -> None:
    """A study's ``decide.py WORK [--arm ARM] [--json FILE]``: ARM against ``fold``, paired, and the seam steps of
    ``budgets``; ``removes_seam(seam, arm)`` is the study's seam rule on those steps (``seam[arm][budget]``)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("work", type=Path)
    parser.add_argument("--arm", default=default_arm, help="the arm read against fold")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    runs = load_arms(args.work, ("fold", args.arm))
    result = paired_differences(runs, "fold", args.arm)
    result["seam"] = {arm: seam_steps(runs, arm, budgets) for arm in ("fold", args.arm)}
    result["removes_seam"] = removes_seam(result["seam"], args.arm)
    print("harmless (encoder, latent):", result["encoder"]["harmless"], result["latent"]["harmless"],
          "; removes the seam:", result["removes_seam"])
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")


def train_and_read(arm: str, seed: int, data: str, work: Path, measured: Path, budgets: tuple[str, ...]) -> None:
    """One run of an arm: the NBRDF baseline trained at the demo's length on ``data`` with ``seed`` (whatever this
    process patched), its test split read (4,000 random bins, encoder and `latent`) and its seam step on the
    ``.bsdf`` measurements in ``measured`` under each of ``budgets``, written to ``WORK/ARM-SEED.json``."""
    import seam

    import frenbrdf
    from frenbrdf.evaluation.evaluate import EvaluateConfig, evaluate_runs
    from frenbrdf.io.atomic import save_json
    from frenbrdf.training import config_for, train

    name = f"{arm}-{seed}"
    cfg = config_for("nbrdf", training="demo", data=data, out=str(work / "runs" / name), seed=seed,
                     cache_dir=str(work / "cache"), progress=False)
    run = train(cfg, overwrite=True)
    settings = EvaluateConfig(samples=4000, edits=30, edit_resolution=64, refine="latent", progress=False)
    report = evaluate_runs([run.path], work / "evaluation" / name, config=settings, overwrite=True)
    model = frenbrdf.Model.load(run.path)
    side, other = seam.seam_pairs()
    steps = {}
    for path in sorted(measured.glob("*.bsdf")):
        samples = frenbrdf.read_samples(path, samples=4000, seed=0)
        steps[path.stem] = {budget: seam.jumps(model.reconstruct(samples.values, (samples.wi, samples.wo),
                                                                 refine=budget).nbrdf, side, other)
                            for budget in budgets}
    save_json(work / f"{name}.json", {"arm": arm, "seed": seed, "test": report["reconstruction"]["nbrdf"],
                                      "summary": report["summary"]["nbrdf"], "seam": steps})
    print(name, "done")
