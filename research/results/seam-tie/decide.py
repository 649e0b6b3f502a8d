"""The seam-tie study's rule (README.md): paired PSNR and ΔE differences tied − fold, and the seam steps.

    python research/results/seam-tie/decide.py WORK [--arm tied|tied@0.3] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from paired_arms import load_arms, paired_differences, seam_steps  # noqa: E402

BUDGETS = ("none", "latent", "full")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("work", type=Path)
    parser.add_argument("--arm", default="tied", help="the arm read against fold (tied or tied@WEIGHT)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    runs = load_arms(args.work, ("fold", args.arm))
    result = paired_differences(runs, "fold", args.arm)
    result["seam"] = {arm: seam_steps(runs, arm, BUDGETS) for arm in ("fold", args.arm)}
    result["removes_seam"] = all(result["seam"][args.arm][b]["median"] <= result["seam"]["fold"][b]["median"] / 4
                                 for b in ("none", "latent"))
    print("harmless (encoder, latent):", result["encoder"]["harmless"], result["latent"]["harmless"],
          "; removes the seam:", result["removes_seam"])
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
