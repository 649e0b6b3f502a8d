"""A run's config with the larger model's sizes (research/results/capacity/config-big.json), for this study's scripts.

    python research/results/capacity-v4/sized_config.py BASE_CONFIG OUT [--pooling mean|attention] [--patience N]

BASE_CONFIG's own fields, less those the command line gives (data, out, seed, decoder_from), with only the
decoded NBRDF's widths, the latent and the decoder's heads set to the larger model's; with --pooling the encoder's
pooling too (attention with 4 heads), with --patience the training's patience.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

BIG = Path(__file__).resolve().parents[1] / "capacity" / "config-big.json"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("base", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--pooling", choices=("mean", "attention"))
    parser.add_argument("--patience", type=int)
    args = parser.parse_args(argv)
    config, big = (json.loads(path.read_text()) for path in (args.base, BIG))
    for field in ("data", "out", "seed", "decoder_from"):
        config.pop(field, None)
    model = config["model"]
    model["nbrdf"]["hidden"] = big["model"]["nbrdf"]["hidden"]
    model["encoder"]["latent"] = big["model"]["encoder"]["latent"]
    model["decoder"]["hidden"] = big["model"]["decoder"]["hidden"]
    if args.pooling:
        model["encoder"]["pooling"] = args.pooling
        if args.pooling == "attention":
            model["encoder"]["attention_heads"] = 4
    if args.patience:
        config["patience"] = args.patience
    args.out.write_text(json.dumps(config, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
