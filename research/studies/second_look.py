"""A second look for the encoder: a network that reads what the first guess got wrong (issue 47; a prototype).

    python research/studies/second_look.py train CONFIG DATA --out DIR [--minutes 30] [--epochs N] [--seed 0]
        [--base pretrained] [--steps 1] [--init RUN]
    python research/studies/second_look.py score MATERIALS... --runs DIR... --out OUT [--patterns ...] [--count 1500]
        [--draws 0]
    python research/studies/second_look.py refine MATERIALS... --base MODEL --runs DIR... --out OUT
        [--budgets none latent full] [--patterns merl-bins] [--count 4000] [--draws 0]

Through a device the shipped encoders stay 2–6 dB below their random-bin figure, and no choice among them closes
it (research/results/encoder-choice), while `latent`, which reads the samples' errors step by step, comes within
about 1 dB through uniform pairs. The second look (:mod:`frenbrdf.models.second_look`) takes one learned step of that
kind from the base model's own guess z₁ (its encoders' `best-fit` choice); the decoder and the encoders stay frozen.

``train`` fits one for ``--base`` on CONFIG's data and split (a run config such as
research/results/folds-v8/config-v8.json) through the `mixed` pattern mixture of version 5's device encoders
(counts 300–4,000), L1 without L_fre, Adam at the config's rate, for a number of epochs or a time, keeping the
weights of the best validation loss (the validation tables read through the mixture).

``score`` renders the package model's first look and each run's second look for each material and pattern (128²)
and writes ``OUT/rows.json`` and ``OUT/summary.md``: PSNR / ΔE of each, and the difference per material (the second
look the mean of the runs'). ``refine`` reconstructs with and without each run's look by each refinement budget.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from frenbrdf import Model
from frenbrdf.configs import from_dict, to_dict
from frenbrdf.data.folders import SampleBatch, list_materials, split_materials
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.models.autoencoder import AutoEncoder, load_model
from frenbrdf.models.nbrdf import mapped_samples, nbrdf_forward
from frenbrdf.models.second_look import SecondLook, SecondLookConfig, look_weights
from frenbrdf.render import Scene, material_mask, render_linear, tonemap
from frenbrdf.training.augment import BatchDrawer
from frenbrdf.training.config import TrainConfig
from frenbrdf.training.prepared import prepare
from frenbrdf.training.step import decoding_terms

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "release")]
from pattern_readings import readings, reconstruction_rows  # noqa: E402

from pack_second_look import read_looks  # noqa: E402

MIXED = Path(__file__).resolve().parents[1] / "results" / "version-5" / "encoder-mixed.json"
PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


class FirstLook:
    """The model's `best-fit` guess for a batch: every encoder's latent, the one whose decoding fits the context
    best (the plain cos θ_i-weighted loss, as :meth:`frenbrdf.Model.encoding` chooses), without gradients."""

    def __init__(self, model: Model):
        encoder = model.network.encoder
        self.members = encoder.encoders() if hasattr(encoder, "encoders") else [encoder]
        self.decoder, self.kind = model.network.decoder, model.loss.get("kind", "l1")

    @torch.no_grad()
    def __call__(self, context: SampleBatch) -> torch.Tensor:
        latents = torch.stack([member(context.encoder_input()) for member in self.members], dim=1)  # (B, M, L)
        b, m, size = latents.shape
        params = self.decoder(latents.reshape(b * m, size))
        predicted = nbrdf_forward(params, context.coords.repeat_interleave(m, dim=0))
        error = (predicted - context.values.repeat_interleave(m, dim=0)) * context.cos_in.repeat_interleave(m, dim=0)[..., None]
        loss = (error.abs() if self.kind == "l1" else error.square()).mean(dim=(1, 2)).reshape(b, m)
        return latents[torch.arange(b), loss.argmin(dim=1)]


def run_config(path: Path, data: Path, seed: int) -> TrainConfig:
    config = json.loads(path.read_text())
    config.update(data=str(data), seed=seed, sampling=json.loads(MIXED.read_text())["sampling"], method="nbrdf",
                  validate_through="sampling", render_every=0, device="cpu")
    config["loss"] = {**config.get("loss", {}), "eta": 0.0}
    return from_dict(TrainConfig, config)


def looked(second: SecondLook, context: SampleBatch, z1: torch.Tensor, decoder, steps: int) -> list[torch.Tensor]:
    """z after each of ``steps`` looks, each from the z the last one gave."""
    out = [z1]
    for _ in range(steps):
        out.append(second(context.coords, context.values, context.cos_in, out[-1], decoder))
    return out[1:]


def validation_loss(model: Model, first: FirstLook, second: SecondLook, cfg, data, drawer,
                    steps: int = 1) -> tuple[float, float]:
    """The validation tables' reconstruction loss of the first look and after ``steps`` looks, read through the
    mixture (the same samples every time)."""
    generator = torch.Generator().manual_seed(cfg.seed + 1)
    materials = list(data.validation)
    sums = [0.0, 0.0]
    second.eval()
    with torch.no_grad():
        for start in range(0, len(materials), cfg.batch_materials):
            batch = materials[start:start + cfg.batch_materials]
            patterns = list(drawer.patterns.choose(len(batch), generator))
            context = drawer.pattern_context(batch, patterns, cfg.context_samples, generator)
            query = data.bank.sample(batch, cfg.query_samples, generator)
            z1 = first(context)
            for k, z in enumerate((z1, looked(second, context, z1, model.network.decoder, steps)[-1])):
                terms = decoding_terms(z, model.network.decoder(z), query, cfg.loss)
                sums[k] += float(terms["rec"]) * len(batch) / len(materials)
    second.train()
    return sums[0], sums[1]


def train(args) -> int:
    model = load_model(args.base)
    model.network.requires_grad_(False)
    cfg = run_config(args.config, args.data, args.seed)
    files = {path.stem: path for path in list_materials(cfg.data)}
    split = split_materials(files, cfg.seed, cfg.split, cfg.holdout)
    data = prepare(cfg, split, files, mapping=model.mapping)
    drawer = BatchDrawer(cfg, data, with_truth=False)
    torch.manual_seed(cfg.seed)
    look_config = SecondLookConfig(steps=args.steps)
    first, second = FirstLook(model), SecondLook(model.config.encoder.latent, look_config)
    if args.init is not None:  # go on from a trained look
        second.load_state_dict(torch.load(args.init / "second_look.pt", weights_only=True)["state"])
    optimizer = torch.optim.Adam(second.parameters(), lr=cfg.lr)
    generator = torch.Generator().manual_seed(cfg.seed)
    args.out.mkdir(parents=True, exist_ok=True)
    history, best = [], math.inf
    deadline = time.monotonic() + 60 * args.minutes
    epoch = 0
    while time.monotonic() < deadline and epoch < args.epochs:
        order = torch.randperm(data.n_train, generator=generator)
        losses = []
        for step in tqdm(range(data.n_train // cfg.batch_materials), desc=f"epoch {epoch}", leave=False,
                         disable=args.quiet):
            batch = order[step * cfg.batch_materials:(step + 1) * cfg.batch_materials].tolist()
            drawn = drawer.draw(batch, generator)
            context = drawn.context
            # each look's loss, averaged: the last look starts from the earlier ones' answers
            terms_by_look = [decoding_terms(z, model.network.decoder(z), drawn.query, cfg.loss)
                             for z in looked(second, context, first(context), model.network.decoder, args.steps)]
            terms = {key: sum(t[key] for t in terms_by_look) / args.steps for key in ("rec", "w", "z")}
            total = terms["rec"] + terms["w"] + terms["z"]
            optimizer.zero_grad(set_to_none=True)
            total.backward()
            optimizer.step()
            losses.append(float(terms["rec"].detach()))
        val_first, val_second = validation_loss(model, first, second, cfg, data, drawer, args.steps)
        history.append({"epoch": epoch, "train_rec": float(np.mean(losses)), "val_first": val_first,
                        "val_second": val_second})
        print(json.dumps(history[-1]), flush=True)
        if val_second < best:
            best = val_second
            torch.save({"state": second.state_dict(), "epoch": epoch, "config": to_dict(look_config)},
                       args.out / "second_look.pt")
        save_json(args.out / "history.json", history)
        epoch += 1
    return 0


def trained_look(run: Path, latent: int) -> SecondLook:
    """The look a run of :func:`train` saved (``run/second_look.pt``), at the sizes it was trained with, for eval."""
    config, (saved,) = read_looks([run])
    look = SecondLook(latent, config)
    look.load_state_dict(saved["state"])
    return look.eval()


def look_samples(model: Model, reading) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """A reading's samples as a look reads them: coordinates, mapped values and cos θ_i, float32, a batch of one."""
    mapped, coords, cos_in = (torch.from_numpy(a.astype(np.float32))[None]
                              for a in mapped_samples(model.mapping, reading.values, reading.directions))
    return coords, mapped, cos_in


def first_look(model: Model, values, directions) -> np.ndarray:
    """The z of ``model``'s encoders (its `best-fit` choice), float32: before its own second look where it has one
    (version 10's encoders are version 9's, so the package's model gives the first look these readings began from)."""
    encoding = model.encoding(values, directions)
    return (encoding.z if encoding.first_look is None else encoding.first_look).astype(np.float32)


def with_looks(model: Model, runs: list[Path], steps: int | None = None) -> Model:
    """``model`` with the second looks of the run folders ``runs`` (trained for it; several: their answers averaged,
    ``SecondLookConfig.members``), taking ``steps`` looks (None: as many as the first run was trained for)."""
    if model.config.second_look is not None:
        raise ValueError("the model has a second look already; give the model the looks were trained for")
    look, saved = read_looks(runs)
    config = dataclasses.replace(model.config, second_look=dataclasses.replace(
        look, members=len(runs), steps=look.steps if steps is None else steps))
    network = AutoEncoder(config)
    network.load_state_dict({**model.network.state_dict(), **look_weights([run["state"] for run in saved])})
    return Model(network, model.mapping, config, model.method, model.loss)


def refine(args) -> int:
    """Each material through the patterns, reconstructed by the base alone and with each run's look, by each budget
    (``none``: the encoder): the rows and a summary as :func:`score` writes them, one look label per budget."""
    base = load_model(args.base)
    models = {"first": base, **{run.name: with_looks(base, [run]) for run in args.runs}}
    rows = reconstruction_rows(models, "look", args.materials, args.patterns, args.draws, args.count, args.budgets)
    args.out.mkdir(parents=True, exist_ok=True)
    save_json(args.out / "rows.json", rows)
    text = "".join(f"\n{budget}\n\n" + summarise([r for r in rows if r["budget"] == budget], args.patterns)
                   for budget in args.budgets)
    write_text(args.out / "summary.md", text)
    print(text)
    return 0


def score(args) -> int:
    model = Model.pretrained()
    looks = [trained_look(run, model.config.encoder.latent) for run in args.runs]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    rows = []
    for reading in readings(args.materials, args.patterns, args.draws, args.count, scene, mask):
        z1 = first_look(model, reading.values, reading.directions)
        coords, mapped, cos_in = look_samples(model, reading)
        latents = {"first": z1}
        with torch.no_grad():
            for run, second in zip(args.runs, looks, strict=True):
                latents[run.name] = second(coords, mapped, cos_in, torch.from_numpy(z1)[None],
                                           model.network.decoder)[0].numpy()
        for look, z in latents.items():
            metrics = reading.metrics(tonemap(render_linear(model.decode(z)[0], scene)), mask)
            rows.append({"material": reading.material, "pattern": reading.pattern, "draw": reading.draw,
                         "look": look, "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]})
    args.out.mkdir(parents=True, exist_ok=True)
    save_json(args.out / "rows.json", rows)
    summary = summarise(rows, args.patterns)
    write_text(args.out / "summary.md", summary)
    print(summary)
    return 0


def per_material(rows: list[dict], pattern: str, key: str = "psnr") -> dict[str, tuple[float, float]]:
    """``{material: (first look, second look)}`` in ``key`` through ``pattern``, each the mean over the draws (the
    second look's also over its runs)."""
    out = {}
    for material in sorted({r["material"] for r in rows}):
        here = [r for r in rows if r["material"] == material and r["pattern"] == pattern]
        out[material] = (float(np.mean([r[key] for r in here if r["look"] == "first"])),
                         float(np.mean([r[key] for r in here if r["look"] != "first"])))
    return out


def summarise(rows: list[dict], patterns) -> str:
    runs = sorted({r["look"] for r in rows} - {"first"})
    lines = [f"second look: the mean of {len(runs)} run(s) ({', '.join(runs)}); PSNR dB / ΔE, means over the materials",
             "", "| pattern | first look | second look | second − first, per material |", "|---|---|---|---|"]
    for name in patterns:
        psnr, delta_e = per_material(rows, name), per_material(rows, name, "delta_e")
        interval = paired_interval([second - first for first, second in psnr.values()])
        span = "" if interval["low"] is None else f" [{interval['low']:+.2f}, {interval['high']:+.2f}]"
        cells = [f"{np.mean([v[k] for v in psnr.values()]):.2f} / {np.mean([v[k] for v in delta_e.values()]):.2f}"
                 for k in (0, 1)]
        lines.append(f"| {name} | {cells[0]} | {cells[1]} | {interval['mean']:+.2f}{span} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    t = commands.add_parser("train")
    t.add_argument("config", type=Path)
    t.add_argument("data", type=Path)
    t.add_argument("--out", type=Path, required=True)
    t.add_argument("--minutes", type=float, default=30, help="stop after this long ...")
    t.add_argument("--epochs", type=int, default=10**9, help="... or this many epochs, whichever comes first")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--quiet", action="store_true", help="no progress bars")
    t.add_argument("--base", default="pretrained", help="the model whose first look is corrected: 'pretrained' "
                   "(the package's), a packed model's folder or a run folder")
    t.add_argument("--steps", type=int, default=1, help="looks unrolled in training, each look's loss averaged; "
                   "the validation loss is the last one's (research/results/two-step-look)")
    t.add_argument("--init", type=Path, help="a look run to start from instead of zero (the same sizes)")
    s = commands.add_parser("score")
    s.add_argument("materials", nargs="+", type=Path)
    s.add_argument("--runs", nargs="+", type=Path, required=True)
    s.add_argument("--out", type=Path, required=True)
    s.add_argument("--patterns", nargs="+", default=list(PATTERNS))
    s.add_argument("--count", type=int, default=1500)
    s.add_argument("--draws", type=int, nargs="+", default=[0])
    r = commands.add_parser("refine")
    r.add_argument("materials", nargs="+", type=Path)
    r.add_argument("--base", default="pretrained", help="the model the looks were trained for")
    r.add_argument("--runs", nargs="+", type=Path, required=True)
    r.add_argument("--budgets", nargs="+", default=["none", "latent", "full"])
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--patterns", nargs="+", default=["merl-bins"])
    r.add_argument("--count", type=int, default=4000)
    r.add_argument("--draws", type=int, nargs="+", default=[0])
    args = parser.parse_args(argv)
    return {"train": train, "score": score, "refine": refine}[args.command](args)


if __name__ == "__main__":
    raise SystemExit(main())
