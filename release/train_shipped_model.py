"""Regenerates the model shipped in the package (python/frenbrdf/models/pretrained/) and its card (docs/pretrained.md).

    frenbrdf import-nbrdf ../shared/data/merl-nbrdf/*.h5 merl/
    frenbrdf synth bank/
    python release/train_shipped_model.py --merl merl/ --bank bank/ --config pretrained.json --work pretrained-work/

Trains one model (``frenbrdf train`` with ``--config``: any TrainConfig keys over the
method's preset; ``data``, ``out`` and ``seed`` are set here) on the MERL files and the
bank together (a folder of links to both), evaluates its held-out test split
(:func:`frenbrdf.render.scoring.reconstruction_rows`: render RMSE/PSNR/SSIM/ΔE over the lit
material pixels, encoder only), packs it (:func:`frenbrdf.models.pretrained.pack_pretrained`:
float16 weights, compact f_ref), measures what float16 costs (the same test split through
the packed model), and writes the card (``card.json`` beside the files, ``docs/pretrained.md``).
``--dest`` and ``--card`` default to the package folder and docs/pretrained.md.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

import numpy as np

from frenbrdf import Model, Run
from frenbrdf.data.folders import list_materials
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.models import pretrained
from frenbrdf.render.scoring import reconstruction_rows
from frenbrdf.training import load_config, train

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1] / "benches")]  # its folder, benches/ (`import common`), also when loaded by path
from common import run_metadata  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
METRICS = ("rmse", "psnr", "ssim", "delta_e")
#: The sampling patterns the card reports the held-out split through (encoder only, ``PATTERN_SAMPLES`` pairs
#: each): the devices of research/results/sampling-patterns.
CARD_PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
PATTERN_SAMPLES = 1500


def linked_data(folders: list[Path], data: Path) -> None:
    """A folder of links to every material file of ``folders``; a link there already to the same file is kept,
    anything else under a name it needs (a user's file, a link elsewhere: a name in two folders) is refused."""
    data.mkdir(parents=True, exist_ok=True)
    for folder in folders:
        for path in list_materials(folder):
            link = data / path.name
            if link.is_symlink() and link.exists() and link.samefile(path):
                continue
            if link.is_symlink() or link.exists():
                raise ValueError(f"{link} is in the way (not a link to {path}): a name in two of the folders "
                                 f"{[str(f) for f in folders]}, or a file of its own; move it or choose another --work")
            link.symlink_to(path.resolve())


def held_out_files(work: Path, names) -> list[Path]:
    """The files in ``WORK/data`` of the held-out materials ``names`` (MERL tables or measurements)."""
    files = {path.stem: path for path in list_materials(work / "data")}
    missing = sorted(set(names) - files.keys())
    if missing:
        raise FileNotFoundError(f"{work / 'data'} lacks the held-out materials {missing}")
    return [files[name] for name in sorted(names)]


def read_sources(work: Path) -> dict[str, list[str]]:
    """``WORK/sources.json`` (:func:`source_names` of the training's folders), which :func:`build` writes."""
    path = work / "sources.json"
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: train_shipped_model.py writes it (since version 9); run it "
                                "again with --reuse on this WORK to write it without training")
    return json.loads(path.read_text())


def summary(rows: list[dict]) -> dict[str, float]:
    return {key: float(np.mean([row[key] for row in rows])) for key in METRICS}


def by_pattern(model: Model, test: list[Path], *, seed: int = 0, progress: bool = False) -> dict[str, dict]:
    """:func:`summary` of the held-out materials read through each of :data:`CARD_PATTERNS`, encoder only."""
    return {pattern: summary(reconstruction_rows(model, test, samples=PATTERN_SAMPLES, seed=seed,
                                                 frequency_metric=False, progress=progress, pattern=pattern))
            for pattern in CARD_PATTERNS}


def source_names(folders: list[Path]) -> dict[str, list[str]]:
    """The material names of each source folder, by the folder's name (the card's sources)."""
    return {folder.name: [path.stem for path in list_materials(folder)] for folder in folders}


def by_source(rows: list[dict], sources: dict[str, list[str]]) -> dict[str, dict]:
    """:func:`summary` of the rows of each source (:func:`source_names`), and of all."""
    members = {name: set(names) for name, names in sources.items()}
    groups = {name: [row for row in rows if row["material"] in names] for name, names in members.items()}
    return {"all": summary(rows), **{name: {**summary(group), "n": len(group)} for name, group in groups.items()
                                     if group}}


def build(config_path: str, folders: list[Path], work: Path, dest: Path, card_path: Path, *, seed: int = 0,
          progress: bool = True, reuse: bool = False, resume: bool = False, trained_on: str | None = None) -> dict:
    """Trains, evaluates, packs and documents the shipped model; returns the card.

    ``reuse``: a finished run in ``work`` (its ``best.pt``) is evaluated, packed and documented
    again instead of trained anew. ``resume``: a run stopped midway continues from its ``last.pt``."""
    sources = source_names(folders)
    linked_data(folders, work / "data")
    save_json(work / "sources.json", sources)  # for release/pack_encoder_mean.py's card
    cfg = load_config(config_path, data=str(work / "data"), out=str(work / "run"), seed=seed)
    cfg.progress = progress
    if reuse and (Path(cfg.out) / "best.pt").exists():
        run = Run(cfg.out)
    else:  # a fresh run replaces an earlier one of this script's in WORK/run
        run = train(cfg, resume=resume, overwrite=not resume)
    test = held_out_files(work, run.split.test)
    held_out = reconstruction_rows(run.model(), test, seed=seed, frequency_metric=False, progress=progress)
    refined = reconstruction_rows(run.model(), test, seed=seed, frequency_metric=False, refine="latent",
                                  progress=progress)
    card = {"version": pretrained.VERSION, "command": run_metadata()["command"],
            "training_config": json.loads(Path(config_path).read_text()), "data": list(sources),
            "materials": {"train": len(run.split.train), "validation": len(run.split.val), "test": len(test)},
            "seed": seed, "best_epoch": run.best_epoch, "epochs": run.history[-1]["epoch"] + 1,
            # Training time without the validation renders, as the run logged it (a reused run's own).
            "training_seconds": round(run.history[-1].get("seconds", run.seconds or 0.0), 1),
            "trained_on": trained_on or run_metadata()["cpu"],
            "held_out": {"float32": summary(held_out)}, "held_out_by_source": by_source(held_out, sources),
            "held_out_refined_by_source": by_source(refined, sources),
            "held_out_by_pattern": by_pattern(run.model(), test, seed=seed, progress=progress)}
    sizes = pretrained.pack_pretrained(run.path, dest, card=card)
    packed = Model.pretrained(dest)
    card["held_out"]["packed"] = summary(reconstruction_rows(packed, test, seed=seed, frequency_metric=False,
                                                             progress=progress))
    card["bytes"] = sizes
    sizes = pretrained.pack_pretrained(run.path, dest, card=card)  # the card now says what packing cost
    write_text(card_path, card_markdown({**card, "bytes": sizes}))
    return card


def measure_and_pack(checkpoint: dict, mapping: dict, test: list[Path], sources: dict[str, list[str]], card: dict,
                     dest: str | Path, card_path: str | Path) -> dict:
    """A model assembled from packed parts (``release/pack_*.py``): its held-out materials ``test`` measured (encoder
    only by source, with `latent` by source, through the card's patterns) into ``card``, packed into ``dest``,
    measured again as packed, and ``card_path`` (Markdown) written; returns the card."""
    model = Model.from_checkpoint(checkpoint, mapping)
    rows = reconstruction_rows(model, test, frequency_metric=False)
    refined = reconstruction_rows(model, test, frequency_metric=False, refine="latent")
    card.update({"held_out": {"float32": summary(rows)}, "held_out_by_source": by_source(rows, sources),
                 "held_out_refined_by_source": by_source(refined, sources),
                 "held_out_by_pattern": by_pattern(model, test)})
    card.pop("bytes", None)
    pretrained.pack_checkpoint(checkpoint, mapping, dest, card=card)
    card["held_out"]["packed"] = summary(reconstruction_rows(Model.pretrained(dest), test, frequency_metric=False))
    card["bytes"] = pretrained.pack_checkpoint(checkpoint, mapping, dest, card=card)
    card["bytes"] = pretrained.pack_checkpoint(checkpoint, mapping, dest, card=card)  # the card says its sizes
    write_text(card_path, card_markdown(card))
    print(json.dumps(card["held_out"], indent=2))
    return card


def card_markdown(card: dict) -> str:
    """docs/pretrained.md: what the shipped model is, how it was made, how well it reconstructs."""
    table = "\n".join(f"| {name} | {card['held_out']['float32'][key]:.4g} | {card['held_out']['packed'][key]:.4g} |"
                      for key, name in zip(METRICS, ("RMSE", "PSNR (dB)", "SSIM", "ΔE"), strict=True))
    return f"""# The pretrained model (version {card['version']})

`frenbrdf reconstruct INPUT --out DIR` and `frenbrdf.Model.pretrained()` load the model
packed in `python/frenbrdf/models/pretrained/` ({sum(card['bytes'].values()) / 1e6:.2f} MB:
{', '.join(f'`{k}` {v / 1e6:.2f} MB' for k, v in card['bytes'].items())}).

- **Data**: {', '.join(f'`{d}`' for d in card['data'])}: {card['materials']['train']} training,
  {card['materials']['validation']} validation and {card['materials']['test']} held-out test materials
  (split from seed {card['seed']}).
- **Training**: `{json.dumps(card['training_config'])}` over its method's preset; best epoch
  {card['best_epoch']} of {card['epochs']}, {card['training_seconds']} s on {card['trained_on']}.{encoders_text(card)}{second_look_text(card)}
- **Regenerate**: `bash release/train_shipped_model.sh` (the data, the decoder's training, its device encoders and
  packing: [release/README.md](../release/README.md)). These files
  were packed by `{card['command']}`.
- **Packing**: weights in float16; f_ref as ln(f_ref + ε) in 16 bits, differences along φ_d,
  compressed (relative error of f_ref + ε below 1e-4).

Held-out test materials, encoder only (4000 random valid bins each), render metrics over the lit
material pixels, as trained (float32) and as shipped (packed):

| metric | float32 | packed |
|---|---|---|
{table}

By source (float32), encoder only: {by_source_text(card['held_out_by_source'])}.
With the latent refined on the same samples (`--refine latent`; `frenbrdf reconstruct` defaults to `full`):
{by_source_text(card['held_out_refined_by_source'])}.

{patterns_text(card)}
Real gonio-photometer measurements: [research/measurements.md](../research/measurements.md); this recipe on measurements
outside its training, judged by folds: [results.md](results.md#with-real-measurements-in-the-training-data).
"""


def patterns_text(card: dict) -> str:
    """The card's table of the held-out split read through each sampling pattern (cards before version 5 have
    none)."""
    if "held_out_by_pattern" not in card:
        return ""
    rows = "\n".join(f"| {pattern} | {m['psnr']:.2f} | {m['delta_e']:.2f} |"
                     for pattern, m in card["held_out_by_pattern"].items())
    return f"""
The same held-out materials read through the sampling patterns of real devices (`frenbrdf.io.patterns`,
[docs/usage.md](usage.md#sampling-patterns)), {PATTERN_SAMPLES} pairs each, encoder only (float32):

| pattern | PSNR (dB) | ΔE |
|---|---|---|
{rows}
"""


def encoders_text(card: dict) -> str:
    """The card's line on the encoders of release/pack_encoder_mean.py, if the model's were packed by it."""
    if "encoders" not in card:
        return ""
    encoders = card["encoders"]
    members = ", ".join(f"`{m}`" for m in encoders["members"])
    with_base = encoders.get("base_encoder", True)  # cards before version 5 always kept the base's encoder
    count = len(encoders["members"]) + with_base
    who = f"the training run's and {members}" if with_base else members
    # what the members' training changed: each member's sampling (cards before version 8 gave one config for all)
    samplings = encoders.get("samplings") or [(encoders.get("training_config") or {}).get("sampling")]
    counted = Counter(json.dumps(sampling) for sampling in samplings if sampling)
    config = ("" if not counted else f" with the sampling `{next(iter(counted))}`" if len(counted) == 1 else
              " with the samplings " + "; ".join(f"`{sampling}` ({n})" for sampling, n in counted.items()))
    why = encoders.get("why") or "[encoder-refit](../research/results/encoder-refit/README.md)"  # None: not given
    how = ("the latent, of one of them, whose decoding fits the given samples best" if encoders.get("choice") == "best-fit"
           else "the mean of their latents")
    pooled = Counter(encoders.get("poolings", []))  # cards before version 6 do not say: every encoder took the mean
    pooling = (f"; pooled by {', '.join(f'{kind} ({n})' for kind, n in pooled.items())}" if set(pooled) - {"mean"}
               else "")
    return (f"\n- **Encoders**: {count} encoder{'s' * (count > 1)} of this decoder, z {how}: {who}, each "
            f"trained for the frozen decoder (`frenbrdf train --decoder-from`){config}{pooling}; why and the rule "
            f"that chose it: {why}. Packed by `{encoders['command']}`.")


def second_look_text(card: dict) -> str:
    """The card's line on the second look of release/pack_second_look.py, if the model has one."""
    look = card.get("second_look")
    if not look:
        return ""
    steps = look["config"].get("steps", 1)
    times = {1: "once", 2: "twice"}.get(steps, f"{steps} times, each look from the z the last gave")
    if look["config"].get("choice", "last") == "best-fit":
        times += ", keeping of the encoders' z and the looks' the one whose decoding fits the samples best"
    runs, of = look["runs"], len(look["of"])
    if len(runs) > 1:
        which = f"{len(runs)} runs, their answers averaged: " + ", ".join(
            f"`{run}` at its epoch {epoch}" for run, epoch in zip(runs, look["epochs"], strict=True))
    else:
        chosen = f"the lowest validation loss of {of} runs, " if of > 1 else ""
        which = f"`{runs[0]}`, {chosen}at its epoch {look['epochs'][0]}"
    return (f"\n- **Second look**: z from the encoders is corrected {times} from the samples' errors under it "
            f"(`frenbrdf.models.second_look`, `{json.dumps(look['config'])}`), trained for these frozen encoders "
            f"and decoder by `research/studies/second_look.py` ({which}); why and the rule that chose it: "
            f"{look['why']}. Packed by `{look['command']}`.")


def by_source_text(groups: dict) -> str:
    return "; ".join(f"{name} ({s['n']}): PSNR {s['psnr']:.2f} dB, ΔE {s['delta_e']:.2f}"
                     for name, s in groups.items() if name != "all")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--merl", help="folder of MERL files (frenbrdf import-nbrdf)")
    parser.add_argument("--bank", help="folder of bank MERL files (frenbrdf synth)")
    parser.add_argument("--data", action="append", default=[], metavar="DIR",
                        help="another folder of material files (repeatable), e.g. the RGL fits")
    parser.add_argument("--config", required=True, help="training config JSON (any TrainConfig keys)")
    parser.add_argument("--work", default="pretrained-work", help="folder of the linked data and the run")
    parser.add_argument("--dest", default=str(pretrained.PACKAGE_DIR), help="where the packed files go")
    parser.add_argument("--card", default=str(ROOT / "docs" / "pretrained.md"), help="the model card (Markdown)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--reuse", action="store_true", help="evaluate, pack and document WORK/run again, untrained")
    parser.add_argument("--resume", action="store_true", help="continue WORK/run from its last.pt")
    parser.add_argument("--trained-on", help="the machine the run was trained on, for the card (default: this CPU)")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    pretrained.check_pack_destination(args.dest, inputs=[args.work])  # before any work
    folders = [Path(f) for f in (args.merl, args.bank, *args.data) if f]
    if not folders:
        parser.error("give --merl, --bank, --data or several")
    card = build(args.config, folders, Path(args.work), Path(args.dest), Path(args.card), seed=args.seed,
                 progress=not args.quiet, reuse=args.reuse, resume=args.resume, trained_on=args.trained_on)
    print(json.dumps(card["held_out"], indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
