"""Amendments 4 and 5's encoder configs (README.md): a config of encoders.sh with validation through the run's
sampling and at most EPOCHS epochs; with --devices-only, random MERL bins taken out of its sampling mixture.

    python research/results/capacity-v4/val_config.py CONFIG OUT --epochs 400 [--devices-only]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("config", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--epochs", type=int, required=True)
    parser.add_argument("--devices-only", action="store_true", help="no random MERL bins in the sampling mixture")
    args = parser.parse_args(argv)
    config = json.loads(args.config.read_text())
    config.update(validate_through="sampling", epochs=args.epochs)
    if args.devices_only:
        config["sampling"]["patterns"].pop("merl-bins")
    args.out.write_text(json.dumps(config, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
