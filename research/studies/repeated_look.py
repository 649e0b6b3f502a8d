"""The second look taken more than once: z_{k+1} = look(z_k), each look reading the samples again (issue 47).

    python research/studies/repeated_look.py MATERIALS... --out OUT [--base pretrained] [--look RUN] [--steps 1 2]
        [--choice last] [--budgets none] [--patterns ...] [--count 1500] [--draws 0]

A look is trained for one step from the encoders' guess (research/studies/second_look.py), yet from its own answer it
can read what is still wrong and step again, as `latent` refinement does 600 times. Each material is reconstructed
by the model with each number of looks (``SecondLookConfig.steps``) and each budget (``none``: the encoder alone),
its renders (128²) scored against the truth's; ``OUT/rows.json`` and ``OUT/summary.md`` hold the readings and, per
pattern and budget, the difference of the most looks and the fewest, per material with a 95 % interval.

``--base`` is the model (``pretrained``: the package's, which carries its look), ``--look`` a look run trained for
a base without one (the fold runs').
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from frenbrdf import Model
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.models.autoencoder import load_model

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pattern_readings import reconstruction_rows  # noqa: E402
from second_look import PATTERNS, with_looks  # noqa: E402


def with_steps(model: Model, steps: int, choice: str = "last") -> Model:
    """``model``, whose config has a second look, taking ``steps`` looks, z chosen from them by ``choice``
    (``SecondLookConfig.choice``)."""
    if model.config.second_look is None:
        raise ValueError("the model has no second look: pass --look with a look run trained for it")
    config = dataclasses.replace(model.config,
                                 second_look=dataclasses.replace(model.config.second_look, steps=steps,
                                                                 choice=choice))
    return Model(model.network, model.mapping, config, model.method, model.loss)


def per_material(rows: list[dict], key: str) -> dict[int, dict[str, float]]:
    """``{looks: {material: key}}``, each the mean over the draws."""
    return {k: {m: float(np.mean([r[key] for r in rows if r["looks"] == k and r["material"] == m]))
                for m in sorted({r["material"] for r in rows})}
            for k in sorted({r["looks"] for r in rows})}


def summarise(rows: list[dict]) -> str:
    steps = sorted({r["looks"] for r in rows})
    lines = [f"PSNR dB / ΔE, means over the materials; difference: {steps[-1]} looks − {steps[0]}, per material, "
             "95 % interval", "", f"| budget | pattern | {' | '.join(f'{k} looks' for k in steps)} | difference |",
             f"|---|---|{'---|' * len(steps)}---|"]
    for budget in dict.fromkeys(r["budget"] for r in rows):
        for pattern in dict.fromkeys(r["pattern"] for r in rows):
            here = [r for r in rows if r["budget"] == budget and r["pattern"] == pattern]
            psnr, delta_e = per_material(here, "psnr"), per_material(here, "delta_e")
            cells = [f"{np.mean(list(psnr[k].values())):.2f} / {np.mean(list(delta_e[k].values())):.2f}"
                     for k in steps]
            interval = paired_interval([psnr[steps[-1]][m] - psnr[steps[0]][m] for m in psnr[steps[0]]])
            span = "" if interval["low"] is None else f" [{interval['low']:+.2f}, {interval['high']:+.2f}]"
            lines.append(f"| {budget} | {pattern} | {' | '.join(cells)} | {interval['mean']:+.2f}{span} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("materials", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--base", default="pretrained", help="'pretrained' (the package's model), a packed model's "
                        "folder or a run folder")
    parser.add_argument("--look", type=Path, help="a look run trained for --base, which has none of its own")
    parser.add_argument("--steps", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--choice", default="last", help="how z is taken from the looks: 'last' or 'best-fit'")
    parser.add_argument("--budgets", nargs="+", default=["none"])
    parser.add_argument("--patterns", nargs="+", default=list(PATTERNS))
    parser.add_argument("--count", type=int, default=1500)
    parser.add_argument("--draws", type=int, nargs="+", default=[0])
    args = parser.parse_args(argv)
    base = load_model(args.base)
    if args.look is not None:
        base = with_looks(base, [args.look])
    models = {k: with_steps(base, k, args.choice) for k in args.steps}
    rows = reconstruction_rows(models, "looks", args.materials, args.patterns, args.draws, args.count, args.budgets)
    args.out.mkdir(parents=True, exist_ok=True)
    save_json(args.out / "rows.json", rows)
    summary = summarise(rows)
    write_text(args.out / "summary.md", summary)
    print(summary)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
