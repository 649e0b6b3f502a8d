"""Packs the study's candidate (README.md): the base's encoders and the members', ``best-fit``, into a folder that
every ``--model`` takes. No card is measured: the study's comparisons are the measurement.

    python research/results/device-specialists/pack.py OUT MEMBER ... --base local/v4-packed
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frenbrdf.models import pretrained

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "release"))
from pack_encoder_mean import assemble, poolings  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("members", nargs="+", help="run folders of encoders trained for the base's decoder")
    parser.add_argument("--base", required=True, help="a packed single-encoder model's folder (version 6: version 4's)")
    args = parser.parse_args(argv)
    checkpoint, mapping, card = assemble(args.base, args.members, choice="best-fit")
    card.update({"encoders": {"base": args.base, "members": args.members, "poolings": poolings(checkpoint)}})
    pretrained.pack_checkpoint(checkpoint, mapping, args.out, card=card)
    print(f"{args.out}: {len(poolings(checkpoint))} encoders ({', '.join(poolings(checkpoint))}), best-fit")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
