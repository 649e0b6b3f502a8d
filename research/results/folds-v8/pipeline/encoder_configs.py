"""The four encoder configs of the pipeline amendment (../README.md): a fold run's own config (its recipe, its
held-out tables) made into version 8's device encoders for its packed decoder: the `mixed` sampling of version 5's
encoders or the nine device patterns alone, `mean` or attention pooling, validated through the run's own sampling,
at most 400 epochs (capacity-v4's amendments 4 and 5).

    python research/results/folds-v8/pipeline/encoder_configs.py RUN/config.json DECODER OUT_DIR

Writes OUT_DIR/{mixed,devices}-{mean,attention}.json; DECODER (a packed folder) is written as it is given, so give
it as the training command will see it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from frenbrdf.io.atomic import write_text

MIXED = Path(__file__).resolve().parents[2] / "version-5" / "encoder-mixed.json"


def encoder_config(run_config: dict, decoder: str, sampling: str, pooling: str) -> dict:
    config = {k: v for k, v in run_config.items() if k not in ("data", "out", "seed")}
    patterns = dict(json.loads(MIXED.read_text())["sampling"]["patterns"])
    if sampling == "devices":
        patterns.pop("merl-bins")
    config.update(sampling={"patterns": patterns, "counts": [300, 4000], "preset": "custom"},
                  validate_through="sampling", epochs=400, decoder_from=decoder, init_from="", device="auto")
    config["model"]["encoder"].update(pooling=pooling, attention_heads=4)
    return config


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run_config", type=Path)
    parser.add_argument("decoder")
    parser.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    run_config = json.loads(args.run_config.read_text())
    args.out.mkdir(parents=True, exist_ok=True)
    for sampling in ("mixed", "devices"):
        for pooling in ("mean", "attention"):
            config = encoder_config(json.loads(json.dumps(run_config)), args.decoder, sampling, pooling)
            write_text(args.out / f"{sampling}-{pooling}.json", json.dumps(config, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
