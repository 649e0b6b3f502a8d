"""The doubled-φ_d study's rule (README.md): paired PSNR and ΔE differences arm − fold, and the seam steps.

    python research/results/doubled-phi-d/decide.py WORK [--arm doubled|scaled] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy import stats


def interval(values: list[float]) -> tuple[float, float, float]:
    values = np.asarray(values)
    half = stats.t.ppf(0.975, len(values) - 1) * values.std(ddof=1) / np.sqrt(len(values))
    return float(values.mean()), float(values.mean() - half), float(values.mean() + half)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("work", type=Path)
    parser.add_argument("--arm", default="doubled", help="the arm read against fold (doubled or scaled)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    arms = {arm: {json.loads(p.read_text())["seed"]: json.loads(p.read_text()) for p in args.work.glob(f"{arm}-*.json")}
            for arm in ("fold", args.arm)}
    seeds = sorted(set(arms["fold"]) & set(arms[args.arm]))
    result: dict = {"seeds": seeds}
    for reading, prefix in (("encoder", ""), ("latent", "refined_")):
        differences: dict[str, list[float]] = {"psnr": [], "delta_e": []}
        for seed in seeds:
            fold = {row["material"]: row for row in arms["fold"][seed]["test"]}
            for row in arms[args.arm][seed]["test"]:
                for key in differences:
                    differences[key].append(row[prefix + key] - fold[row["material"]][prefix + key])
        psnr, delta_e = interval(differences["psnr"]), interval(differences["delta_e"])
        result[reading] = {"pairs": len(differences["psnr"]), "psnr": psnr, "delta_e": delta_e,
                           "harmless": psnr[1] > -0.5 and delta_e[0] < 0.5}
        print(f"{reading}: {args.arm} − fold over {len(differences['psnr'])} pairs: PSNR {psnr[0]:+.2f} dB "
              f"[{psnr[1]:+.2f}, {psnr[2]:+.2f}], ΔE {delta_e[0]:+.2f} [{delta_e[1]:+.2f}, {delta_e[2]:+.2f}]")
    for arm in ("fold", args.arm):
        for budget in ("none", "latent"):
            steps = [np.median([row[budget]["median"] for row in arms[arm][seed]["seam"].values()]) for seed in seeds]
            p90 = [np.median([row[budget]["p90"] for row in arms[arm][seed]["seam"].values()]) for seed in seeds]
            result.setdefault("seam", {}).setdefault(arm, {})[budget] = {"median": float(np.median(steps)),
                                                                        "p90": float(np.median(p90))}
            print(f"seam, {arm}, {budget}: median step {np.median(steps):.4f}, p90 {np.median(p90):.4f}")
    result["removes_seam"] = all(result["seam"][args.arm][b]["median"] < 0.001 for b in ("none", "latent"))
    print("harmless (encoder, latent):", result["encoder"]["harmless"], result["latent"]["harmless"],
          "; removes the seam:", result["removes_seam"])
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
