"""full-tie's exploration after its decision (decides nothing): the tie kept to pairs whose two directions lie at
least MARGIN degrees above the horizon, on the exploration's bank materials; render PSNR and the seam step's 90th
percentile of `full`, untied, tied at 0.1, and tied at 0.1 and 0.3 with a 15° margin.

    python research/results/full-tie/explore_margin.py BANK/*.binary > research/results/full-tie/explore/margin.txt
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
import seam  # noqa: E402
from compare_models import condition_rng  # noqa: E402

import frenbrdf  # noqa: E402
from frenbrdf.io import read_material  # noqa: E402
from frenbrdf.io.patterns import pattern_samples  # noqa: E402
from frenbrdf.models import reconstruct  # noqa: E402
from frenbrdf.models.nbrdf import fold_edge_pairs  # noqa: E402
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap  # noqa: E402
from frenbrdf.render.scoring import image_metrics, refined_reconstruction  # noqa: E402

#: Arm: (tie, margin in degrees or None).
ARMS = {"full": (0.0, None), "tie 0.1": (0.1, None), "tie 0.1, margin 15°": (0.1, 15.0),
        "tie 0.3, margin 15°": (0.3, 15.0)}


def with_margin(margin: float):
    """fold_edge_pairs keeping the pairs whose lower direction (zenith θ_h + θ_d on the edge) lies ``margin``° up."""
    def pairs(count: int, seed: int, ordered: bool = False) -> np.ndarray:
        many = fold_edge_pairs(4 * count, seed, ordered)
        theta_h = np.arctan2(many[:, 0, 0], many[:, 0, 2])
        theta_d = np.arctan2(np.abs(many[:, 0, 3]), many[:, 0, 5])
        return many[np.cos(theta_h + theta_d) > np.sin(np.radians(margin))][:count]
    return pairs


def main() -> None:
    model, scene = frenbrdf.Model.pretrained(), Scene(resolution=128)
    mask, (side, other) = material_mask(scene), seam.seam_pairs()
    readings: dict[str, list[tuple[float, float]]] = {arm: [] for arm in ARMS}
    for path in sys.argv[1:]:
        truth = read_material(path)
        drawn = pattern_samples(truth, "merl-bins", 4000, condition_rng(0, "merl-bins"))
        shown = tonemap(render_linear(truth, scene))
        for arm, (tie, margin) in ARMS.items():
            reconstruct.fold_edge_pairs = with_margin(margin) if margin else fold_edge_pairs
            config = dataclasses.replace(reconstruct.refine_config("full"), tie=tie)
            result, image, _ = refined_reconstruction(model, drawn, scene, config)
            readings[arm].append((image_metrics(shown, image, mask)["psnr"],
                                  seam.jumps(result.nbrdf, side, other)["p90"]))
    base = np.mean([psnr for psnr, _ in readings["full"]])
    for arm, rows in readings.items():
        psnr = np.mean([p for p, _ in rows])
        print(f"{arm}: PSNR {psnr:.2f} ({psnr - base:+.2f}), seam step p90 (median over materials) "
              f"{np.median([s for _, s in rows]):.4f}")


if __name__ == "__main__":
    main()
