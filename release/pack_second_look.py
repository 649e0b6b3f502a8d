"""Packs a packed model with a second look (``frenbrdf.models.second_look``) as the shipped model.

    python release/pack_second_look.py --base WORK/v9 --looks WORK/looks/s1 WORK/looks/s2 WORK/looks/s3 \\
        --work WORK/base-work --version 12 --why "[look-ensemble](../research/results/look-ensemble/README.md)" \\
        --mean --steps 2 [--choice last]

The base (``--base``: ``pretrained`` or a packed model's folder) gives everything but the second look: its
decoder, encoders, mapping and card. Of the looks (run folders of ``research/studies/second_look.py train``, each
trained for that base's first look) the one with the lowest validation loss is added to the config and the weights
(research/results/second-look, amendment 1), or with ``--mean`` all of them, their answers averaged
(``SecondLookConfig.members``, research/results/look-ensemble); the model takes ``--steps`` looks
(research/results/repeated-look). The card is the base's with the version, the look and the held-out test materials
measured anew, encoder only and refined, and through the card's sampling patterns, as assembled (float32) and as
packed. The held-out materials and their sources are train_shipped_model.py's (``--work``), or
(``--held-out CONFIG DIR --sources FILE``) those a training config's ``holdout`` names, from a folder, with a JSON
of source folder name → material names.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import torch

from frenbrdf.configs import from_dict, to_dict
from frenbrdf.data.folders import list_materials
from frenbrdf.models import pretrained
from frenbrdf.models.second_look import SecondLookConfig, look_weights

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1] / "benches")]
from common import run_metadata  # noqa: E402
from train_shipped_model import ROOT, held_out_files, measure_and_pack, read_sources  # noqa: E402

#: The file a second-look run keeps its weights in (research/studies/second_look.py).
LOOK_FILE = "second_look.pt"


def best_look(runs: list[Path]) -> Path:
    """The run whose best validation loss (its ``history.json``) is lowest."""
    def best(run: Path) -> float:
        return min(entry["val_second"] for entry in json.loads((run / "history.json").read_text()))

    return min(runs, key=best)


def read_looks(look_runs: list[Path]) -> tuple[SecondLookConfig, list[dict]]:
    """The first look's config and every look run's saved look (``second_look.pt``: ``state``, ``epoch``,
    ``config``). Looks to be averaged must differ and share their sizes; a ValueError says which do not."""
    if len({run.resolve() for run in look_runs}) < len(look_runs):
        raise ValueError(f"a look is given twice in {[str(run) for run in look_runs]}; looks averaged must differ")
    saved = [torch.load(run / LOOK_FILE, weights_only=True) for run in look_runs]
    trained = [from_dict(SecondLookConfig, run.get("config", {}), f"{path / LOOK_FILE} config")
               for run, path in zip(saved, look_runs, strict=True)]
    sizes = {(look.hidden, look.after) for look in trained}
    if len(sizes) > 1:
        raise ValueError(f"the looks {[str(run) for run in look_runs]} have different sizes (hidden, after: "
                         f"{sorted(sizes)}); looks averaged must share them")
    return trained[0], saved


def assemble(base: str | None, look_runs: list[Path], steps: int = 1, choice: str = "last") -> tuple[dict, dict, dict]:
    """The base's checkpoint with the second looks of ``look_runs`` added (several: their answers averaged), taking
    ``steps`` looks and z from them by ``choice``; its mapping and its card."""
    packed, mapping, card = pretrained.load_packed(None if base in (None, "pretrained") else base)
    config = json.loads(packed["config"])
    if config["model"].get("second_look"):
        raise ValueError(f"{base}: the base has a second look already; give the model it was trained for")
    trained, saved = read_looks(look_runs)
    look = dataclasses.replace(trained, steps=steps, choice=choice, members=len(saved))
    config["model"]["second_look"] = to_dict(look)
    weights = {**packed["model"], **look_weights([run["state"] for run in saved])}
    checkpoint = {"method": packed["method"], "config": json.dumps(config),
                  "model": {name: value.float() for name, value in weights.items()}}
    return checkpoint, mapping, {**card, "look_epochs": [int(run["epoch"]) for run in saved]}


def held_out(config: Path, folder: Path) -> list[Path]:
    """The files of the materials ``config``'s ``holdout`` names, from ``folder``."""
    names = json.loads(config.read_text())["holdout"]
    files = {path.stem: path for path in list_materials(folder)}
    missing = sorted(set(names) - files.keys())
    if missing:
        raise FileNotFoundError(f"{folder} lacks the held-out materials {missing}")
    return [files[name] for name in sorted(names)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="pretrained", help="'pretrained' or a packed model's folder")
    parser.add_argument("--looks", type=Path, nargs="+", required=True,
                        help="second_look.py run folders, trained for the base; the lowest validation loss is packed, "
                        "or with --mean all of them")
    parser.add_argument("--steps", type=int, default=1, help="how many looks the model takes (research/results/"
                        "repeated-look)")
    parser.add_argument("--mean", action="store_true", help="pack every look, their answers averaged, instead of "
                        "the lowest validation loss's (research/results/look-ensemble)")
    parser.add_argument("--choice", default="last", help="how z is taken from the looks: 'last' or 'best-fit' "
                        "(research/results/look-choice)")
    parser.add_argument("--work", type=Path, help="train_shipped_model.py's --work (data/, run/split.json, sources.json)")
    parser.add_argument("--held-out", nargs=2, type=Path, metavar=("CONFIG", "DIR"), help="instead of --work")
    parser.add_argument("--sources", type=Path, help="with --held-out: JSON of source folder name → material names")
    parser.add_argument("--why", help="a Markdown link to the study whose rule chose the look, for the card")
    parser.add_argument("--version", required=True, help="the packed model's version, for its card")
    parser.add_argument("--dest", default=str(pretrained.PACKAGE_DIR))
    parser.add_argument("--card", default=str(ROOT / "docs" / "pretrained.md"))
    args = parser.parse_args(argv)
    if (args.work is None) == (args.held_out is None) or (args.held_out is not None) != (args.sources is not None):
        parser.error("give --work, or --held-out with --sources")
    pretrained.check_pack_destination(args.dest, inputs=[args.base, *args.looks])  # before any work
    looks = args.looks if args.mean else [best_look(args.looks)]
    checkpoint, mapping, card = assemble(args.base, looks, args.steps, args.choice)
    if args.work is not None:
        test = held_out_files(args.work, json.loads((args.work / "run" / "split.json").read_text())["test"])
        sources = read_sources(args.work)
    else:
        test, sources = held_out(*args.held_out), json.loads(args.sources.read_text())
    card.update({"version": args.version,
                 "second_look": {"runs": [str(run) for run in looks], "of": [str(run) for run in args.looks],
                                 "epochs": card.pop("look_epochs"), "why": args.why,
                                 "config": json.loads(checkpoint["config"])["model"]["second_look"],
                                 "command": run_metadata()["command"]}})
    measure_and_pack(checkpoint, mapping, test, sources, card, args.dest, args.card)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
