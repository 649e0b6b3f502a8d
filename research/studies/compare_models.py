"""Models compared on the same samples of materials no training saw: measurements and tables.

    python research/studies/compare_models.py --models pretrained local/refit/rho-s0 local/refit/rho-s1 \\
        --labels v2 rho/0 rho/1 --measurements ../shared/data/rgl-measured/*.bsdf \\
        --tables local/v2/test/*.binary --draws 0 1 2 --out research/results/encoder-refit

Every model encodes every material from ``--samples`` random valid MERL bins of each draw (the same
bins for every model), then refines the latent on them (``latent``: today's budget); each result is
rendered and compared with the render of the truth (a ``.bsdf`` measurement itself, or a table). A
label ``NAME/RUN`` puts runs of one variant together: the report gives each variant's mean over its
runs, the spread between its runs, and the difference from the first model (the baseline) per
material, with a 95 % t-interval over the materials. ``--trained-on LABEL=MATERIAL`` leaves out a
material that model trained on (a fold of a cross-validation is then judged on its held-out materials
only); ``--group NAME=MATERIAL,...`` summarises some of the scored materials apart as well. Writes
``compare.json``, ``compare.md`` and ``compare.png`` (the measurements, draw 0: truth, then each variant's
first run that was scored on it, under the first of ``--budgets``).

``--patterns`` and several ``--samples`` counts read every material through each sampling pattern of
:mod:`frenbrdf.io.patterns` at each count (a condition ``PATTERN × COUNT``): every condition is summarised apart
(its groups named ``GROUP @ PATTERN × COUNT``) and ``compare.md`` adds one table per group and budget with a row
per condition. ``--refine-counts`` runs the budgets other than ``none`` only at those counts (refining costs
about a second a material). A budget ``NAME@FIELD=VALUE,...`` is the named budget with those
:class:`~frenbrdf.models.reconstruct.RefineConfig` fields changed (e.g. ``latent@latent_steps=600``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import zlib
from collections import defaultdict
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.bsdf import MeasuredBSDF
from frenbrdf.io.patterns import DEFAULT as DEFAULT_PATTERN
from frenbrdf.io.patterns import PATTERNS, pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.autoencoder import Model, load_model
from frenbrdf.models.reconstruct import RefineConfig, refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import render_sheet, run_metadata  # noqa: E402

BUDGETS = ("none", "latent")
"""The refinement budgets measured unless ``--budgets`` says others."""
METRICS = ("psnr", "delta_e")


def budget_config(budget: str) -> RefineConfig:
    """A budget of ``--budgets``: a name of ``frenbrdf.models.reconstruct.BUDGETS``, or ``NAME@FIELD=VALUE,...``."""
    name, _, changes = budget.partition("@")
    config = refine_config(name)
    fields = {}
    for change in filter(None, changes.split(",")):
        key, _, value = change.partition("=")
        if key not in {f.name for f in dataclasses.fields(RefineConfig)} or not value:
            raise ValueError(f"budget {budget!r}: {change!r} is not FIELD=VALUE of a RefineConfig field")
        fields[key] = _value(value)
    return dataclasses.replace(config, **fields)  # RefineConfig checks each value


def _value(text: str):
    """A budget field's value: true/false, none, an integer, a number, or the text itself."""
    named = {"true": True, "false": False, "none": None}
    if text.lower() in named:
        return named[text.lower()]
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def condition_rng(draw: int, pattern: str) -> np.random.Generator:
    """The generator of a draw's samples of one pattern: ``draw`` itself for ``merl-bins`` (the draws of every
    earlier comparison), else seeded by the draw and the pattern's name (the same whatever else runs)."""
    return np.random.default_rng(draw if pattern == DEFAULT_PATTERN else [draw, zlib.crc32(pattern.encode())])


def score(models: dict[str, Model], paths: list[Path], draws: list[int], conditions: list[tuple[str, int]],
          scene: Scene, trained_on: set[tuple[str, str]], budgets=BUDGETS, refine_counts=None):
    """Rows ``{model, material, group, draw, pattern, count, budget, psnr, delta_e}`` and the draw-0 images of the
    first condition; no row for a ``(label, material)`` pair of ``trained_on``, none of a budget other than
    ``none`` at a count outside ``refine_counts`` (None: every count)."""
    mask, rows, images = material_mask(scene), [], defaultdict(dict)
    for path in tqdm(paths, desc="materials"):
        truth = read_material(path)
        table, truth_image = as_table(truth), tonemap(render_linear(truth, scene))
        group = "measured" if isinstance(truth, MeasuredBSDF) else "tables"
        images[path.stem]["truth"] = truth_image
        for draw in draws:
            for pattern, count in conditions:
                drawn = pattern_samples(truth, pattern, count, condition_rng(draw, pattern), table=table)
                for label, model in models.items():
                    if (label, path.stem) in trained_on:
                        continue
                    for budget in budgets:
                        if budget != "none" and refine_counts is not None and count not in refine_counts:
                            continue
                        config = dataclasses.replace(budget_config(budget), seed=draw, progress=False)
                        _, image, _ = refined_reconstruction(model, drawn, scene, config)
                        metrics = image_metrics(truth_image, image, mask)
                        rows.append({"model": label, "material": path.stem, "group": group, "draw": draw,
                                     "pattern": pattern, "count": count, "budget": budget,
                                     **{key: metrics[key] for key in METRICS}})
                        first = draw == draws[0] and (pattern, count) == conditions[0] and budget == budgets[0]
                        if first and group == "measured":
                            images[path.stem][label] = image
    return rows, images


def variant(label: str) -> str:
    return label.split("/")[0]


def per_material_psnr(rows: list[dict], name: str, patterns, *, group: str = "tables", budget: str = "none",
                      count: int | None = None, metric: str = "psnr") -> dict[str, float]:
    """Material → variant ``name``'s PSNR (or another ``metric`` of the rows) averaged over ``patterns`` (at ``count``
    samples; None: any) and its runs, for the rules of the studies that read these rows."""
    mine = [r for r in rows if variant(r["model"]) == name and r["group"] == group and r["budget"] == budget
            and r["pattern"] in patterns and (count is None or r["count"] == count)]
    return {m: float(np.mean([r[metric] for r in mine if r["material"] == m]))
            for m in sorted({r["material"] for r in mine})}


# The five device patterns the studies' rules average over (every pattern but random MERL bins).
DEVICE_PATTERNS = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


def paired_difference(rows: list[dict], candidate: str, baseline: str, patterns, budget: str = "none",
                      group: str = "tables", metric: str = "psnr") -> dict:
    """The per-material difference ``candidate − baseline`` in PSNR (or ``metric``) on ``group`` (each the mean over
    its runs and ``patterns``), its mean and 95 % interval: the test of the studies' rules."""
    new = per_material_psnr(rows, candidate, patterns, group=group, budget=budget, metric=metric)
    old = per_material_psnr(rows, baseline, patterns, group=group, budget=budget, metric=metric)
    if not new or not old:
        raise SystemExit(f"no {budget!r} rows of {candidate!r} or {baseline!r} on the {group}")
    return paired_interval([new[m] - old[m] for m in sorted(new.keys() & old.keys())])


def print_intervals(tests: dict[str, dict]) -> None:
    """One line per rule test: its name, mean difference and 95 % interval, and over how many materials."""
    for name, test in tests.items():
        print(f"{name}: {test['mean']:+.2f} [{test['low']:+.2f}, {test['high']:+.2f}] over {test['n']} materials")


def summarise(rows: list[dict], baseline: str, groups: dict[str, list[str]], budgets=BUDGETS) -> dict:
    """Per group of materials, budget and variant: the mean and the spread over its runs, and the per-material
    difference from the baseline with its interval."""
    def mean_of(selected, key):
        return float(np.mean([r[key] for r in selected]))

    out = {}
    for group, materials in groups.items():
        for budget in budgets:
            # A table and a measurement may share a name (an RGL fit and its .bsdf): "tables" and "measured" take
            # their own rows only.
            chosen = [r for r in rows if r["budget"] == budget and r["material"] in materials
                      and r["group"] in ((group,) if group in ("measured", "tables") else ("measured", "tables"))]
            for name in dict.fromkeys(variant(r["model"]) for r in chosen):
                mine = [r for r in chosen if variant(r["model"]) == name]
                runs = sorted({r["model"] for r in mine})
                scored = [m for m in materials if any(r["material"] == m for r in mine)]
                entry = {"runs": runs}
                # Runs judged on other materials (folds) have no spread between them.
                same_materials = len({frozenset(r["material"] for r in mine if r["model"] == run) for run in runs}) == 1
                for key in METRICS:
                    per_run = [mean_of([r for r in mine if r["model"] == run], key) for run in runs]
                    entry[key] = float(np.mean(per_run))
                    spread = len(per_run) > 1 and same_materials
                    entry[f"{key}_run_sd"] = float(np.std(per_run, ddof=1)) if spread else None
                    if name != baseline:
                        base = [r for r in chosen if variant(r["model"]) == baseline]  # its runs' mean
                        differences = [mean_of([r for r in mine if r["material"] == m], key)
                                       - mean_of([r for r in base if r["material"] == m], key) for m in scored]
                        entry[f"{key}_change"] = paired_interval(differences)
                per_material = {m: mean_of([r for r in mine if r["material"] == m], "psnr") for m in scored}
                entry["materials"] = len(scored)
                entry["worst_material"] = min(per_material, key=per_material.get)
                entry["max_delta_e"] = max(mean_of([r for r in mine if r["material"] == m], "delta_e")
                                           for m in scored)
                out.setdefault(group, {}).setdefault(budget, {})[name] = entry
    return out


def condition_name(group: str, pattern: str, count: int) -> str:
    return f"{group} @ {pattern} × {count}"


def summarise_conditions(rows: list[dict], baseline: str, groups: dict[str, list[str]], budgets,
                         conditions: list[tuple[str, int]]) -> dict:
    """:func:`summarise` of each condition's rows apart: its groups named :func:`condition_name` (plainly
    ``GROUP`` when there is one condition)."""
    if len(conditions) == 1:
        return summarise(rows, baseline, groups, budgets)
    out = {}
    for pattern, count in conditions:
        mine = [r for r in rows if r["pattern"] == pattern and r["count"] == count]
        summary = summarise(mine, baseline, groups, budgets)
        out |= {condition_name(group, pattern, count): value for group, value in summary.items()}
    return out


def conditions_markdown(summary: dict, groups: dict, budgets, conditions: list[tuple[str, int]]) -> str:
    """Per group and budget, a row per condition: each variant's PSNR (sd between runs) / ΔE, and beside every
    variant but the baseline its PSNR change from it, mean [95 % interval over the materials]."""
    lines = ["PSNR dB (sd between runs) / ΔE per variant; Δ: per-material PSNR difference from the first variant, "
             "mean [95 % interval over the materials].", ""]
    for group in groups:
        for budget in budgets:
            found = [(c, summary[condition_name(group, *c)][budget]) for c in conditions
                     if budget in summary.get(condition_name(group, *c), {})]
            if not found:
                continue
            names = list(dict.fromkeys(name for _, variants in found for name in variants))
            names.sort(key=lambda name: any("psnr_change" in v[name] for _, v in found if name in v))  # baseline 1st
            header = [names[0], *(f"{name} | Δ" for name in names[1:])]
            lines += [f"**{group}, {'encoder only' if budget == 'none' else budget}**", "",
                      "| pattern × count | " + " | ".join(header) + " |",
                      "|---|" + "---|" * (2 * len(names) - 1)]
            for (pattern, count), variants in found:
                cells = []
                for name in names:
                    e = variants.get(name)
                    cells.append("–" if e is None else f"{e['psnr']:.2f}{_spread(e, 'psnr')} / {e['delta_e']:.2f}")
                    if name != names[0]:
                        cells.append("–" if e is None else _change(e, "psnr"))
                lines.append(f"| {pattern} × {count} | " + " | ".join(cells) + " |")
            lines.append("")
    return "\n".join(lines)


def _spread(entry: dict, key: str) -> str:
    """`` (sd)`` between a variant's runs, empty with one run."""
    return f" ({entry[f'{key}_run_sd']:.2f})" if entry[f"{key}_run_sd"] is not None else ""


def _change(entry: dict, key: str) -> str:
    """A variant's mean change from the baseline and its interval, ``–`` for the baseline."""
    c = entry.get(f"{key}_change")
    if c is None:
        return "–"
    interval = f" [{c['low']:+.2f}, {c['high']:+.2f}]" if c["low"] is not None else ""
    return f"{c['mean']:+.2f}{interval}"


def markdown(summary: dict) -> str:
    lines = ["PSNR dB / ΔE: each variant's mean over its runs (sd between runs); change: per-material difference from "
             "the baseline, mean [95 % interval over the materials].", ""]
    for group, budgets in summary.items():
        for budget, variants in budgets.items():
            lines += [f"**{group}, {'encoder only' if budget == 'none' else budget}**", "",
                      "| variant | runs | materials | PSNR | ΔE | ΔE max | PSNR change | ΔE change |",
                      "|---|---|---|---|---|---|---|---|"]
            for name, e in variants.items():
                lines.append(f"| {name} | {len(e['runs'])} | {e['materials']} | {e['psnr']:.2f}{_spread(e, 'psnr')} | "
                             f"{e['delta_e']:.2f}{_spread(e, 'delta_e')} | {e['max_delta_e']:.2f} | "
                             f"{_change(e, 'psnr')} | {_change(e, 'delta_e')} |")
            lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", nargs="+", required=True, help="the baseline first")
    parser.add_argument("--labels", nargs="+", required=True, help="one per model; NAME/SEED groups runs")
    parser.add_argument("--measurements", nargs="*", default=[], help=".bsdf files")
    parser.add_argument("--tables", nargs="*", default=[], help="MERL files (e.g. a test split)")
    parser.add_argument("--held-out", nargs=2, metavar=("CONFIG", "DIR"),
                        help="also the tables a training config holds out (its `holdout`), as DIR/NAME.binary")
    parser.add_argument("--draws", type=int, nargs="+", default=[0])
    parser.add_argument("--budgets", nargs="+", default=list(BUDGETS), metavar="BUDGET",
                        help="none, latent, full, or NAME@FIELD=VALUE,... (a RefineConfig field changed)")
    parser.add_argument("--samples", type=int, nargs="+", default=[4000], help="samples per material: one or more counts")
    parser.add_argument("--patterns", nargs="+", default=[DEFAULT_PATTERN], choices=tuple(PATTERNS), metavar="NAME",
                        help=f"sampling patterns the materials are read through (default {DEFAULT_PATTERN})")
    parser.add_argument("--refine-counts", type=int, nargs="+", metavar="N",
                        help="run the budgets other than none only at these of --samples (default: at every one)")
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--trained-on", nargs="*", default=[], metavar="LABEL=MATERIAL",
                        help="a material that model trained on: not scored for it")
    parser.add_argument("--group", nargs="*", default=[], metavar="NAME=MATERIAL,...",
                        help="also summarise these of the scored materials apart (e.g. the real ones of a test split); "
                             "a name both a table and a measurement have takes the rows of both")
    parser.add_argument("--out", required=True, help="folder for compare.json, compare.md, compare.png")
    args = parser.parse_args(argv)
    if len(args.models) != len(args.labels):
        parser.error("give one label per model")
    trained_on = {tuple(pair.split("=", 1)) for pair in args.trained_on}
    if any(len(pair) != 2 or pair[0] not in args.labels for pair in trained_on):
        parser.error("--trained-on takes LABEL=MATERIAL pairs with a LABEL of --labels")
    extra_groups = {name: members.split(",") for name, _, members in (g.partition("=") for g in args.group)}
    if any(not name or not all(members) for name, members in extra_groups.items()):
        parser.error("--group takes NAME=MATERIAL,MATERIAL,... with no empty name")
    if reserved := set(extra_groups) & {"measured", "tables"}:
        parser.error(f"--group: {sorted(reserved)} name the built-in groups; give the group another name")
    try:
        [budget_config(budget) for budget in args.budgets]
    except ValueError as error:
        parser.error(f"--budgets: {error}")
    models = {label: load_model(spec) for label, spec in zip(args.labels, args.models, strict=True)}
    measured, tables = [Path(p) for p in args.measurements], [Path(p) for p in args.tables]
    if args.held_out:
        config, folder = map(Path, args.held_out)
        tables += [folder / f"{name}.binary" for name in json.loads(config.read_text())["holdout"]]
    scored = {p.stem for p in measured + tables}
    for name, members in extra_groups.items():
        if missing := set(members) - scored:
            parser.error(f"--group {name}: not among the scored materials: {sorted(missing)}")
    conditions = [(pattern, count) for pattern in args.patterns for count in args.samples]
    rows, images = score(models, measured + tables, args.draws, conditions, Scene(resolution=args.resolution),
                         trained_on, args.budgets, args.refine_counts)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {"run": run_metadata(), "models": dict(zip(args.labels, args.models, strict=True)),
              "trained_on": sorted(args.trained_on),
              "draws": args.draws, "samples": args.samples, "patterns": args.patterns, "rows": rows}
    save_json(out / "compare.json", report)  # the scores are kept whatever the summary does
    groups = {name: [p.stem for p in paths] for name, paths in (("measured", measured), ("tables", tables)) if paths}
    groups |= extra_groups
    summary = summarise_conditions(rows, variant(args.labels[0]), groups, args.budgets, conditions)
    save_json(out / "compare.json", report | {"summary": summary})
    text = markdown(summary) if len(conditions) == 1 else conditions_markdown(summary, groups, args.budgets, conditions)
    write_text(out / "compare.md", text)
    if measured:
        names = list(dict.fromkeys(map(variant, models)))
        sheet, labels = {}, {}
        for path in measured:  # the truth, then each variant's first run scored on the material
            shown = images[path.stem]
            sheet[path.stem] = {"truth": shown["truth"]}
            for name in names:
                if label := next((label for label in shown if variant(label) == name), None):
                    sheet[path.stem][name], labels[path.stem, name] = shown[label], label
        render_sheet(sheet, out / "compare.png", columns=["truth", *names],
                     title=lambda m, name: f"{labels[m, name]}, {args.budgets[0]}" if (m, name) in labels else name)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
