"""Packs several encoders of one decoder as the shipped model: z their mean (research/results/encoder-refit) or,
with ``--choice best-fit``, the latent whose decoding fits the samples best (research/results/version-5).

    python release/pack_encoder_mean.py --members local/refit/plain-s0 local/refit/plain-s1 ... \\
        --work local/v2 --version 3

The base (``--base``: ``pretrained`` or a packed model's folder) gives the decoder, the mapping, the
training config and the first encoder; each member (a run trained with ``--decoder-from`` the base)
adds its encoder, after a check that its decoder and mapping are exactly the base's; with
``--without-base-encoder`` z is the members' mean alone (version 5: encoders trained on other sampling
patterns than the base's). The card is the
base's with the members named, the version given, and the held-out test split (``WORK/run/split.json``'s
``test``, files in ``WORK/data``; by source: ``WORK/sources.json``; WORK is train_shipped_model.py's) measured
anew, encoder only and refined, as assembled (float32) and as packed.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

from frenbrdf.configs import to_dict
from frenbrdf.models import pretrained
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.encoder import ENCODER_CHOICES

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1] / "benches")]  # its folder, benches/
from common import run_metadata  # noqa: E402
from train_shipped_model import ROOT, held_out_files, measure_and_pack, read_sources  # noqa: E402


def assemble(base: str | None, members: list[str], *, base_encoder: bool = True,
             choice: str = "mean") -> tuple[dict, dict, dict]:
    """The checkpoint of the base's decoder with every encoder (the base's first, unless ``base_encoder`` is
    false: then the members' only) and ``choice`` (``ModelConfig.encoder_choice``), its mapping and its card."""
    packed, mapping, card = pretrained.load_packed(None if base in (None, "pretrained") else base)
    base_decoder = {name: value.float() for name, value in packed["model"].items() if name.startswith("decoder.")}
    config = json.loads(packed["config"])
    if config["model"].get("second_look"):  # trained for the base's encoders, not for new ones
        raise ValueError(f"{base}: the base has a second look; give the model without one that it was trained for")
    if base_encoder and config["model"].get("extra_encoders"):
        raise ValueError(f"{base}: the base has several encoders; give its single-encoder base and its members instead")
    encoders = []  # (state dict, encoder config) of each encoder, in order
    if base_encoder:
        encoders.append(({name[len("encoder."):]: value.float() for name, value in packed["model"].items()
                          if name.startswith("encoder.")}, config["model"]["encoder"]))
    for spec in members:
        member = load_model(spec)
        decoder = member.network.decoder.state_dict()
        if any(not torch.equal(decoder[name[len("decoder."):]], value) for name, value in base_decoder.items()) or \
                not np.array_equal(member.mapping.state()["reference"], mapping["reference"].astype(np.float32)):
            raise ValueError(f"{spec}: its decoder or mapping is not the base's (train it with --decoder-from)")
        encoders.append((member.network.encoder.state_dict(), to_dict(member.config.encoder)))
    if not encoders:
        raise ValueError("no encoder: give --members, or keep the base's encoder")
    config["model"]["encoder"] = encoders[0][1]
    config["model"]["extra_encoders"] = [encoder_config for _, encoder_config in encoders[1:]]
    config["model"]["encoder_choice"] = choice
    # One encoder is a plain SetEncoder (keys encoder.*); several an EncoderMean (encoder.members.K.*).
    prefixes = ["encoder."] if len(encoders) == 1 else [f"encoder.members.{k}." for k in range(len(encoders))]
    weights = dict(base_decoder)
    for prefix, (state, _) in zip(prefixes, encoders, strict=True):
        weights.update({prefix + name: value for name, value in state.items()})
    return {"method": packed["method"], "config": json.dumps(config), "model": weights}, mapping, card


def poolings(checkpoint: dict) -> list[str]:
    """How each packed encoder pools its codes, in order (``EncoderConfig.pooling``)."""
    model = json.loads(checkpoint["config"])["model"]
    return [encoder.get("pooling", "mean") for encoder in (model["encoder"], *model.get("extra_encoders", []))]


def member_sampling(run: str) -> dict | None:
    """The sampling a member's run trained with (its ``config.json``), for the card."""
    return json.loads((Path(run) / "config.json").read_text()).get("sampling")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="pretrained", help="'pretrained' or a packed model's folder")
    parser.add_argument("--members", nargs="+", required=True, help="run folders of encoders for the base's decoder")
    parser.add_argument("--work", required=True, help="train_shipped_model.py's --work (data/, run/split.json, sources.json)")
    parser.add_argument("--without-base-encoder", action="store_true",
                        help="z is the mean of the members' encoders only (the base gives the decoder and mapping)")
    parser.add_argument("--choice", choices=ENCODER_CHOICES, default="mean",
                        help="how the encoders' latents give z (ModelConfig.encoder_choice)")
    parser.add_argument("--why", help="a Markdown link to the study whose rule chose these encoders, for the card")
    parser.add_argument("--version", required=True, help="the packed model's version, for its card")
    parser.add_argument("--dest", default=str(pretrained.PACKAGE_DIR))
    parser.add_argument("--card", default=str(ROOT / "docs" / "pretrained.md"))
    args = parser.parse_args(argv)
    pretrained.check_pack_destination(args.dest, inputs=[args.base, *args.members])  # before any work
    checkpoint, mapping, card = assemble(args.base, args.members, base_encoder=not args.without_base_encoder,
                                      choice=args.choice)
    work = Path(args.work)
    test = held_out_files(work, json.loads((work / "run" / "split.json").read_text())["test"])
    sources = read_sources(work)
    card.update({"version": args.version,  # "command" stays the one that trained and packed the base
                 "encoders": {"base": args.base, "members": args.members, "base_encoder": not args.without_base_encoder,
                              "choice": args.choice, "poolings": poolings(checkpoint),
                              "samplings": [member_sampling(member) for member in args.members], "why": args.why,
                              "command": run_metadata()["command"]}})
    measure_and_pack(checkpoint, mapping, test, sources, card, args.dest, args.card)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
