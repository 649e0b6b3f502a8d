"""What each command of the CLI runs: one function per command, taking the parsed arguments, returning the exit
status. Bad input raises ValueError or OSError, which :func:`frenbrdf.cli.main` reports in one line."""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path


def _print_json(data) -> None:
    """``--json``: what the command reports, as its files hold JSON (:func:`frenbrdf.io.atomic.json_text`)."""
    from ..io.atomic import json_text

    print(json_text(data), end="")


def info(args: argparse.Namespace) -> int:
    """Reports the installation and checks that the native core works."""
    import numpy as np

    import frenbrdf
    from frenbrdf import _native

    # A tiny end-to-end check of the native core: a specular pair has θ_h = 0.
    angles = frenbrdf.directions_to_rusinkiewicz(np.array([0.0, 0.6, 0.8]), np.array([0.0, -0.6, 0.8]))
    report = {
        "frenbrdf": frenbrdf.__version__,
        "native_module": _native.__file__,
        "native_threads": _native.num_threads(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "torch": _torch_version(),
        "pretrained_model": _pretrained_version(),
        "self_check": "ok" if abs(angles[0]) < 1e-12 else f"FAILED: θ_h = {angles[0]}",
    }
    if args.json:
        _print_json(report)
    else:
        width = max(map(len, report))
        for key, value in report.items():
            print(f"{key:<{width}}  {value}")
    return 0 if report["self_check"] == "ok" else 1


def _pretrained_version() -> str:
    """The shipped model's version, from its card (docs/pretrained.md), or why there is none."""
    from frenbrdf.io.jsonfile import read_json
    from frenbrdf.models.pretrained import CARD_FILE, PACKAGE_DIR

    try:
        card = read_json(PACKAGE_DIR / CARD_FILE, "model card", max_bytes=1 << 20)
    except FileNotFoundError:
        return "none shipped with this installation"
    except (OSError, ValueError) as error:
        return f"unreadable: {error}"
    return f"version {card.get('version', 'unknown')}"


def _torch_version() -> str:
    try:
        import torch
    except ImportError:
        return "not installed"
    return torch.__version__


def synth(args: argparse.Namespace) -> int:
    from ..data.synth import write_bank

    paths = write_bank(args.out_dir, n=args.n, seed=args.seed, mix=args.mix, overwrite=args.overwrite,
                       progress=not args.quiet)
    print(f"wrote {len(paths)} MERL files to {args.out_dir}")
    return 0


def import_nbrdf(args: argparse.Namespace) -> int:
    from ..data.nbrdf_import import import_nbrdf

    paths = import_nbrdf(args.weights, args.out_dir, overwrite=args.overwrite, progress=not args.quiet)
    print(f"wrote {len(paths)} MERL files to {args.out_dir}")
    return 0


def train(args: argparse.Namespace) -> int:
    from ..training import config_for, load_config, train
    from ..training.loop import check_run_folder

    if args.config and (args.training or args.augmentation or args.sampling):
        raise ValueError("--training, --augmentation and --sampling set presets; with --config the file says "
                         "everything")
    if args.seeds is not None and args.seed is not None:
        raise ValueError("give --seed or --seeds, not both")
    if args.seeds is not None and not args.out:
        raise ValueError("--seeds needs --out: each seed trains into OUT/seed-S")
    if args.seeds is not None and len(set(args.seeds)) < len(args.seeds):
        raise ValueError(f"--seeds repeats a seed ({' '.join(map(str, args.seeds))}): each seed trains one run")
    configs = []  # every seed's config and run folder checked before any trains
    for seed in args.seeds if args.seeds is not None else [args.seed]:
        out = str(Path(args.out) / f"seed-{seed}") if args.seeds is not None else args.out
        overrides = {"method": args.method, "data": args.data, "out": out, "epochs": args.epochs, "seed": seed,
                     "device": args.device, "holdout": args.holdout, "render_every": args.render_every,
                     "select": args.select, "decoder_from": args.decoder_from, "init_from": args.init_from}
        own = Path(out) / "config.json" if out else None
        if args.config:
            cfg = load_config(args.config, **overrides)
        elif args.resume and own is not None and own.is_file():  # the run's own config, changed only where asked
            if args.training or args.augmentation or args.sampling:
                raise ValueError("--training, --augmentation and --sampling set presets; a resume continues the "
                                 f"run's own config ({own}): give --epochs to train longer")
            cfg = load_config(own, **overrides)
        else:
            cfg = config_for(args.method or "frenbrdf", training=args.training, augmentation=args.augmentation,
                             sampling=args.sampling,
                             **{k: v for k, v in overrides.items() if v is not None and k != "method"})
        cfg.progress = not args.quiet
        check_run_folder(cfg, resume=args.resume, overwrite=args.overwrite)
        configs.append(cfg)
    for cfg in configs:
        run = train(cfg, resume=args.resume, overwrite=args.overwrite)
        assert run.seconds is not None  # train times what it trains
        best = run.best  # the history entry of the selected epoch
        summary = {"run_dir": str(run.path), "method": cfg.method, "seed": cfg.seed, "best_epoch": best["epoch"],
                   "selected_by": cfg.select, "best_val_rec": best["val_rec"], "seconds": round(run.seconds, 1)}
        if "val_psnr" in best:
            summary["best_val_psnr"] = best["val_psnr"]
        if os.environ.get("RANK", "0") == "0":  # under torchrun, one summary
            psnr = f", validation render PSNR {best['val_psnr']:.2f} dB" if "val_psnr" in best else ""
            if args.json:
                _print_json(summary)
            else:
                print(f"{cfg.method} (seed {cfg.seed}): best epoch {best['epoch']} by validation {cfg.select}: "
                      f"L_rec {best['val_rec']:.4g}{psnr}; {run.seconds:.0f} s; run folder {run.path}")
    return 0


def fit_nbrdf(args: argparse.Namespace) -> int:
    from ..data.fitting import FitConfig, fit_nbrdf
    from ..io.formats import format_of, read_table, write_material
    from ..io.outputs import OutputFolder
    from ..io.paths import input_file, naming

    try:
        hidden = tuple(int(h) for h in args.hidden.split(","))
    except ValueError:
        raise ValueError(f"--hidden takes hidden widths separated by commas, e.g. 21,21; got {args.hidden!r}") from None
    config = FitConfig(hidden=hidden, epochs=args.epochs, seed=args.seed)
    # Every input and output checked before any work: no fit is lost to a later clash, no file replaced unasked.
    materials = [input_file(path, "material file") for path in args.materials]
    for path in materials:
        format_of(path, ("measurement",), "fit-nbrdf")
    stems = [path.stem for path in materials]
    if len(set(stems)) < len(stems):
        raise ValueError(f"two inputs share a name and would write the same {args.out}/<name>.pt: "
                         f"{sorted({stem for stem in stems if stems.count(stem) > 1})}")
    suffixes = (".pt", ".binary") if args.merl else (".pt",)
    out = OutputFolder.claim(args.out, command="fit-nbrdf", inputs=materials, overwrite=args.overwrite,
                             additive=True)
    out.check_names(stem + suffix for stem in stems for suffix in suffixes)
    for path in materials:  # each fit moved in as soon as it is done: a long run keeps what it finished
        with naming(path):
            nbrdf = fit_nbrdf(read_table(path), config, progress=not args.quiet)
        with out.staged() as staging:
            write_material(staging / f"{path.stem}.pt", nbrdf.weights())
            if args.merl:
                nbrdf.to_merl(staging / f"{path.stem}.binary")
        print(f"fitted {path.name} -> {out.path / (path.stem + '.pt')}")
    return 0


def fit_decoder(args: argparse.Namespace) -> int:
    from ..training.decoder_fit import DecoderFitConfig, fit_decoder

    config = DecoderFitConfig(epochs=args.epochs, decoder_lr=args.decoder_lr, latent_lr=args.latent_lr, seed=args.seed,
                              encoder_weight=args.encoder_weight, encoder_lr=args.encoder_lr,
                              encoder_augment=args.encoder_augment)
    out = fit_decoder(args.source, args.out, config, overwrite=args.overwrite, progress=not args.quiet)
    if config.encoder_weight == 0:
        print(f"fitted the decoder of {args.source} -> {out} (its encoders no longer fit it: train them again with "
              f"`frenbrdf train --decoder-from {out}`)")
    else:
        fitted = "decoder and its encoder" if config.trains_encoder else "decoder to its encoder's z"
        print(f"fitted the {fitted} of {args.source} -> {out} (other encoders of the decoder: train them again "
              f"with `frenbrdf train --decoder-from {out}`)")
    return 0


def evaluate(args: argparse.Namespace) -> int:
    from ..evaluation.evaluate import EvaluateConfig, evaluate_seeds, report_markdown, seeds_markdown

    config = EvaluateConfig(samples=args.samples, edits=args.edits, resolution=args.resolution,
                            max_materials=args.max_materials, all_materials=args.all_materials,
                            refine=args.refine, patterns=tuple(args.patterns), progress=not args.quiet)
    if args.quick:
        config.edits, config.edit_resolution = min(args.edits, 120), 96
    report = evaluate_seeds(args.runs, args.out, data=args.data, config=config, overwrite=args.overwrite)
    print(seeds_markdown(report) if "comparison" in report else report_markdown(report))
    if args.json:
        _print_json(report.get("comparison", report.get("summary")))
    return 0


def render(args: argparse.Namespace) -> int:
    from ..io.formats import format_of, read_material
    from ..io.outputs import check_output_file
    from ..io.paths import input_file

    if args.spp is not None and not args.mitsuba:
        raise ValueError("--spp sets a --mitsuba render's samples per pixel; the metric renderer has none")
    format_of(input_file(args.material, "material file"), ("measurement", "nbrdf"), "render")
    check_output_file(args.out, (".png",), overwrite=args.overwrite, inputs=(args.material,))
    if args.mitsuba:  # the plugin reads the file with the same reader, frenbrdf.io.read_material
        from ..render.mitsuba import render_material

        render_material(args.material, out_path=args.out, spp=64 if args.spp is None else args.spp,
                        resolution=args.resolution)
    else:
        from ..models.nbrdf import as_brdf
        from ..render.renderer import Scene, render, save_png

        save_png(args.out, render(as_brdf(read_material(args.material)), Scene(resolution=args.resolution),
                                  progress=not args.quiet))
    print(f"wrote {args.out}")
    return 0


def spectrum(args: argparse.Namespace) -> int:
    from ..evaluation.spectrum import spectrum_report, summary_text

    report = spectrum_report(args.materials, args.out, truth=args.truth, variant=args.variant, lmax=args.lmax,
                             overwrite=args.overwrite)
    if args.json:
        _print_json(report["errors"] or report["materials"])
    else:
        print(summary_text(report))
    print(f"wrote {args.out}/spectrum.{{png,csv,json}}")
    return 0


def select(args: argparse.Namespace) -> int:
    from ..evaluation.select import select_config
    from ..evaluation.variants import base_config
    from ..training import load_config

    if args.front and (args.config or args.epochs is not None):
        raise ValueError("--config and --epochs set the training of candidates; with --front nothing is trained")
    base = None
    if args.config:
        base = load_config(args.config, data=args.data, epochs=args.epochs)
    elif args.epochs is not None:
        base = base_config(args.data, epochs=args.epochs)
    selection = select_config(args.data, args.target_psnr, args.out, front=args.front, base=base,
                              progress=not args.quiet, overwrite=args.overwrite)
    if args.json:
        _print_json(selection.summary)
    elif selection.chosen is not None:  # reached
        chosen = selection.chosen
        print(f"{chosen['name']}: NBRDF 6→{'→'.join(map(str, chosen['hidden']))}→3 "
              f"({chosen['bytes_per_material']} bytes per material), latent {chosen['latent']}, validation PSNR "
              f"{chosen['psnr']:.2f} dB ≥ {selection.target_psnr:g} dB; config {selection.config_path}; "
              f"report {selection.report_path}")
    if not selection.reached:
        best = selection.best
        print(f"frenbrdf select: no configuration reaches {selection.target_psnr:g} dB validation PSNR"
              + (f"; the best is {best['name']} at {best['psnr']:.2f} dB" if best else "")
              + f" (report {selection.report_path})", file=sys.stderr)
        return 1
    return 0


def demo(args: argparse.Namespace) -> int:
    from ..demo import run_demo

    out = run_demo(args.out, args.data, epochs=args.epochs, augmentation=args.augmentation, progress=not args.quiet,
                   overwrite=args.overwrite)
    print(f"report: {out / 'README.md'}")
    return 0


def reconstruct(args: argparse.Namespace) -> int:
    from ..material.outputs import reconstruct_file

    given = _sampling_options(args, args.input)
    if (args.width is not None or args.reciprocal) and args.refine != "full":
        raise ValueError(f"{'--width' if args.width is not None else '--reciprocal'} sets the NBRDF that "
                         f"--refine full fits; with --refine {args.refine} there is none")
    if args.coverage is not None and args.refine == "none":
        raise ValueError("--coverage weighs the samples of the latent stage; with --refine none there is none")
    report = reconstruct_file(args.input, args.out, model=args.model, refine=args.refine, seed=args.seed,
                              progress=not args.quiet, overwrite=args.overwrite, width=args.width,
                              reciprocal=args.reciprocal, coverage_k=args.coverage, **given)
    for warning in report["coverage"]["warnings"]:
        print(f"warning: {warning}", file=sys.stderr)
    if args.json:
        _print_json(report)
    else:
        metrics = report.get("metrics")
        quality = f"; render PSNR {metrics['psnr']:.2f} dB, ΔE {metrics['delta_e']:.2f}" if metrics else ""
        print(f"reconstructed {args.input} from {report['input']['samples']} samples "
              f"({sum(report['timings_s'].values()):.1f} s){quality}; wrote {os.path.join(args.out, '')}")
    return 0


def edit(args: argparse.Namespace) -> int:
    from ..material.edit import DEFAULT_T, edit_files

    given = _sampling_options(args, args.input_a, args.input_b)
    report = edit_files(args.input_a, args.input_b, args.out, DEFAULT_T if args.t is None else args.t,
                        model=args.model, latent=args.latent, refine=args.refine, seed=args.seed,
                        resolution=args.resolution, progress=not args.quiet, overwrite=args.overwrite, **given)
    if args.json:
        _print_json(report)
    else:
        ends = "; ".join(f"{side} PSNR {m['psnr']:.2f} dB against its render" for side, m in report["ends"].items())
        what = "latent interpolation" if report["mode"] == "latent" else "edit keeping each material"
        print(f"{what} between {args.input_a} and {args.input_b} at t = "
              f"{', '.join(f'{t:g}' for t in report['t'])}{f' (ends: {ends})' if ends else ''}; wrote "
              f"{os.path.join(args.out, '')}")
    return 0


def convert(args: argparse.Namespace) -> int:
    from ..material.convert import convert

    given = _sampling_options(args, args.input)
    if given and Path(args.output).suffix.lower() == ".binary":
        raise ValueError(f"--{next(iter(given))} picks the samples a .csv, .npz or .astm output holds; a .binary "
                         "output is the whole table")
    print(f"wrote {convert(args.input, args.output, seed=args.seed, overwrite=args.overwrite, **given)}")
    return 0


def view(args: argparse.Namespace) -> int:
    from ..render.viewer import write_view

    inputs = [args.input] + ([args.input_b] if args.input_b else [])
    path, page = write_view(inputs, args.out, overwrite=args.overwrite, model=args.model, title=args.title,
                            progress=not args.quiet)
    modes = f"; edit: {', '.join(page.edit.modes)}" if page.edit else ""
    print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB{modes}); open it in a browser")
    return 0


def _sampling_options(args: argparse.Namespace, *inputs: str) -> dict:
    """``--samples`` and ``--pattern`` as given, checked against the inputs: they pick samples from a whole material
    (a MERL file, a ``.bsdf``), and a pattern other than random bins draws a number of pairs, not all bins."""
    given = given_options(args, "samples", "pattern")
    if given and all(_holds_samples(path) for path in inputs):
        files = f"{inputs[0]} is a file" if len(inputs) == 1 else "both inputs are files"
        raise ValueError(f"--{next(iter(given))} picks samples from a MERL file or a .bsdf; {files} of samples, "
                         "read whole")
    if given.get("samples", 1) is None and given.get("pattern", "merl-bins") != "merl-bins":
        raise ValueError(f"--samples all draws every MERL bin; --pattern {given['pattern']} draws N pairs: give a "
                         "number")
    return given


def _holds_samples(path: str) -> bool:
    """Whether ``path``'s suffix is that of a file of samples (``.csv``, ``.npz``, ``.astm``: frenbrdf.io.formats)."""
    from ..io.formats import FORMATS

    entry = FORMATS.get(Path(path).suffix.lower())
    return entry is not None and entry.role == "samples"


def given_options(args: argparse.Namespace, *options: str) -> dict:
    """The ``options`` the user gave (declared with ``default=argparse.SUPPRESS``), so the library's defaults apply
    to the others."""
    return {name: getattr(args, name) for name in options if hasattr(args, name)}
