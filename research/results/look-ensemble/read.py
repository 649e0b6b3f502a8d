"""look-ensemble's judged readings (README.md): version 11 (its encoders' z, then the look `s1` twice) and the
candidate (the looks `s1`, `s2`, `s3` of local/sl/judge with their answers averaged, twice), encoder alone, random bins
and the five devices, 1,500 pairs; ``OUT/v11/rows.json`` and ``OUT/ensemble/rows.json``.

    python research/results/look-ensemble/read.py MATERIALS... --out OUT [--draws 0 1]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from pattern_readings import readings  # noqa: E402
from second_look import PATTERNS, first_look, look_samples, trained_look  # noqa: E402

from frenbrdf import Model  # noqa: E402
from frenbrdf.io.atomic import save_json  # noqa: E402
from frenbrdf.models.second_look import SecondLook  # noqa: E402
from frenbrdf.render import Scene, material_mask, render_linear, tonemap  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from explore import RUNS, averaged  # noqa: E402


def trained_looks(model: Model) -> list[SecondLook]:
    """second-look's three looks (local/sl/judge/s1 … s3), trained for version 11's encoders and decoder."""
    return [trained_look(RUNS / run, model.config.encoder.latent) for run in ("s1", "s2", "s3")]


@torch.no_grad()
def latents(model: Model, looks: list[SecondLook], reading) -> dict[str, torch.Tensor]:
    """Version 11's z (``s1`` twice) and the candidate's (the three averaged, twice) for one reading."""
    z1 = torch.from_numpy(first_look(model, reading.values, reading.directions))[None]
    samples, decoder = look_samples(model, reading), model.network.decoder
    return {name: averaged(chosen, averaged(chosen, z1, samples, decoder), samples, decoder)
            for name, chosen in (("v11", looks[:1]), ("ensemble", looks))}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("materials", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--draws", type=int, nargs="+", default=[0, 1])
    args = parser.parse_args(argv)
    model = Model.pretrained()
    looks = trained_looks(model)
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    rows: dict[str, list] = {"v11": [], "ensemble": []}
    for reading in readings(args.materials, PATTERNS, args.draws, 1500, scene, mask):
        for name, z in latents(model, looks, reading).items():
            metrics = reading.metrics(tonemap(render_linear(model.decode(z[0].numpy())[0], scene)), mask)
            rows[name].append({"material": reading.material, "pattern": reading.pattern, "draw": reading.draw,
                               "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]})
    for name, found in rows.items():
        (args.out / name).mkdir(parents=True, exist_ok=True)
        save_json(args.out / name / "rows.json", found)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
