"""Measures the shipped model's held-out tables with `latent` again, after the budget changed, and rewrites its card
(``card.json`` in the package and ``docs/pretrained.md``); the model's files stay as they are.

    python release/remeasure_latent.py FOLDER...   # the card's source folders: merl, bank, rgl-fits (their names)

Each FOLDER's name is a source of the card (``held_out_refined_by_source``); the held-out tables are read from
them by the names the card's training config holds out, drawn as ``train_shipped_model.py`` draws them (seed 0).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frenbrdf import Model
from frenbrdf.data.folders import list_materials
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.jsonfile import read_json
from frenbrdf.models import pretrained
from frenbrdf.render.scoring import reconstruction_rows

sys.path.insert(0, str(Path(__file__).resolve().parent))
from train_shipped_model import by_source, card_markdown, source_names  # noqa: E402

CARD = Path(pretrained.__file__).parent / pretrained.CARD_FILE
DOC = Path(__file__).resolve().parents[1] / "docs" / "pretrained.md"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folders", nargs="+", type=Path)
    args = parser.parse_args(argv)
    card = read_json(CARD, "model card", max_bytes=1 << 20)
    files = {path.stem: path for folder in args.folders for path in list_materials(folder)}
    names = card["training_config"]["holdout"]
    missing = sorted(set(names) - files.keys())
    if missing:
        raise SystemExit(f"the folders lack the held-out tables {missing}")
    test = [files[name] for name in sorted(names)]
    rows = reconstruction_rows(Model.pretrained(), test, frequency_metric=False, refine="latent", progress=True)
    card["held_out_refined_by_source"] = by_source(rows, source_names(args.folders))
    save_json(CARD, card)
    write_text(DOC, card_markdown(card))
    print(card["held_out_refined_by_source"]["all"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
