"""frenbrdf: neural BRDFs (FreNBRDF) from measured materials: train, reconstruct, render, evaluate."""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import platform
import sys
from pathlib import Path

from ._native import __version__
from .exceptions import TrainingDiverged
from .presets import AUGMENTATION, SELECTION_RULES, TRAINING, method_names


def _info(args: argparse.Namespace) -> int:
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
        "self_check": "ok" if abs(angles[0]) < 1e-12 else f"FAILED: θ_h = {angles[0]}",
    }
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        width = max(map(len, report))
        for key, value in report.items():
            print(f"{key:<{width}}  {value}")
    return 0 if report["self_check"] == "ok" else 1


def _torch_version() -> str:
    try:
        import torch
    except ImportError:
        return "not installed"
    return torch.__version__


def _synth(args: argparse.Namespace) -> int:
    from .data.synth import write_bank

    paths = write_bank(args.out_dir, n=args.n, seed=args.seed, mix=args.mix, overwrite=args.overwrite,
                       progress=not args.quiet)
    print(f"wrote {len(paths)} MERL files to {args.out_dir}")
    return 0


def _import_nbrdf(args: argparse.Namespace) -> int:
    from .data.nbrdf_import import import_nbrdf

    paths = import_nbrdf(args.weights, args.out_dir, overwrite=args.overwrite, progress=not args.quiet)
    print(f"wrote {len(paths)} MERL files to {args.out_dir}")
    return 0


def _train(args: argparse.Namespace) -> int:
    from .training import config_for, load_config, train
    from .training.loop import check_run_folder

    if args.config and (args.training or args.augmentation):
        raise ValueError("--training and --augmentation set presets; with --config the file says everything")
    if args.seeds is not None and args.seed is not None:
        raise ValueError("give --seed or --seeds, not both")
    if args.seeds is not None and not args.out:
        raise ValueError("--seeds needs --out: each seed trains into OUT/seed-S")
    configs = []  # every seed's config and run folder checked before any trains
    for seed in args.seeds if args.seeds is not None else [args.seed]:
        out = str(Path(args.out) / f"seed-{seed}") if args.seeds is not None else args.out
        overrides = {"method": args.method, "data": args.data, "out": out, "epochs": args.epochs, "seed": seed,
                     "device": args.device, "holdout": args.holdout, "render_every": args.render_every,
                     "select": args.select, "decoder_from": args.decoder_from, "init_from": args.init_from}
        if args.config:
            cfg = load_config(args.config, **overrides)
        else:
            cfg = config_for(args.method or "frenbrdf", training=args.training, augmentation=args.augmentation,
                             **{k: v for k, v in overrides.items() if v is not None and k != "method"})
        cfg.progress = not args.quiet
        check_run_folder(cfg, resume=args.resume, overwrite=args.overwrite)
        configs.append(cfg)
    for cfg in configs:
        run = train(cfg, resume=args.resume, overwrite=args.overwrite)
        best = run.best  # the history entry of the selected epoch
        summary = {"run_dir": str(run.path), "method": cfg.method, "seed": cfg.seed, "best_epoch": best["epoch"],
                   "selected_by": cfg.select, "best_val_rec": best["val_rec"], "seconds": round(run.seconds, 1)}
        if "val_psnr" in best:
            summary["best_val_psnr"] = best["val_psnr"]
        if os.environ.get("RANK", "0") == "0":  # under torchrun, one summary
            psnr = f", validation render PSNR {best['val_psnr']:.2f} dB" if "val_psnr" in best else ""
            print(json.dumps(summary, indent=2) if args.json else
                  f"{cfg.method} (seed {cfg.seed}): best epoch {best['epoch']} by validation {cfg.select}: "
                  f"L_rec {best['val_rec']:.4g}{psnr}; {run.seconds:.0f} s; run folder {run.path}")
    return 0


def _fit_nbrdf(args: argparse.Namespace) -> int:
    from .data.fitting import FitConfig, fit_nbrdf, save_nbrdf
    from .io.measured import read_table
    from .io.outputs import OutputFolder
    from .io.paths import input_file

    try:
        hidden = tuple(int(h) for h in args.hidden.split(","))
    except ValueError:
        raise ValueError(f"--hidden takes hidden widths separated by commas, e.g. 21,21; got {args.hidden!r}") from None
    config = FitConfig(hidden=hidden, epochs=args.epochs, seed=args.seed)
    # Every input and output checked before any work: no fit is lost to a later clash, no file replaced unasked.
    materials = [input_file(path, "material file") for path in args.materials]
    stems = [path.stem for path in materials]
    if len(set(stems)) < len(stems):
        raise ValueError(f"two inputs share a name and would write the same {args.out}/<name>.pt: "
                         f"{sorted({stem for stem in stems if stems.count(stem) > 1})}")
    suffixes = (".pt", ".binary") if args.merl else (".pt",)
    out = OutputFolder.claim(args.out, command="fit-nbrdf", inputs=materials, overwrite=args.overwrite,
                             additive=True)
    out.check_names(stem + suffix for stem in stems for suffix in suffixes)
    for path in materials:  # each fit moved in as soon as it is done: a long run keeps what it finished
        nbrdf = fit_nbrdf(read_table(path), config, progress=not args.quiet)
        with out.staged() as staging:
            save_nbrdf(staging / f"{path.stem}.pt", nbrdf)
            if args.merl:
                nbrdf.to_merl(staging / f"{path.stem}.binary")
        print(f"fitted {path.name} -> {out.path / (path.stem + '.pt')}")
    return 0


def _evaluate(args: argparse.Namespace) -> int:
    from .study.evaluation import EvaluateConfig, evaluate_seeds, report_markdown, seeds_markdown

    config = EvaluateConfig(samples=args.samples, edits=args.edits, resolution=args.resolution,
                            max_materials=args.max_materials, all_materials=args.all_materials,
                            refine=args.refine, progress=not args.quiet)
    if args.quick:
        config.edits, config.edit_resolution = min(args.edits, 120), 96
    report = evaluate_seeds(args.runs, args.out, data=args.data, config=config, overwrite=args.overwrite)
    print(seeds_markdown(report) if "comparison" in report else report_markdown(report))
    if args.json:
        print(json.dumps(report.get("comparison", report.get("summary")), indent=2))
    return 0


def _render(args: argparse.Namespace) -> int:
    from .io.outputs import check_output_file
    from .io.paths import input_file

    if args.spp is not None and not args.mitsuba:
        raise ValueError("--spp sets a --mitsuba render's samples per pixel; the metric renderer has none")
    input_file(args.material, "material file")
    check_output_file(args.out, (".png",), overwrite=args.overwrite, inputs=(args.material,))
    if args.mitsuba:  # the plugin reads the file with the same loader, frenbrdf.data.materials
        from .render.mitsuba import render_material

        render_material(args.material, out_path=args.out, spp=64 if args.spp is None else args.spp,
                        resolution=args.resolution)
    else:
        from .data.materials import load_material_file
        from .render.renderer import Scene, render, save_png

        save_png(args.out, render(load_material_file(args.material), Scene(resolution=args.resolution)))
    print(f"wrote {args.out}")
    return 0


def _spectrum(args: argparse.Namespace) -> int:
    from .study.spectrum import spectrum_report, summary_text

    report = spectrum_report(args.materials, args.out, truth=args.truth, variant=args.variant, lmax=args.lmax,
                             overwrite=args.overwrite)
    print(json.dumps(report["errors"] or report["materials"], indent=2) if args.json else summary_text(report))
    print(f"wrote {args.out}/spectrum.{{png,csv,json}}")
    return 0


def _select(args: argparse.Namespace) -> int:
    from .study.select import select_config
    from .study.variants import base_config
    from .training import load_config

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
        print(json.dumps(selection.summary, indent=2))
    elif selection.reached:
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


def _demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    out = run_demo(args.out, args.data, epochs=args.epochs, augmentation=args.augmentation, progress=not args.quiet,
                   overwrite=args.overwrite)
    print(f"report: {out / 'README.md'}")
    return 0


def _reconstruct(args: argparse.Namespace) -> int:
    from .material.outputs import reconstruct_file

    given = _given(args, "samples")
    if given and Path(args.input).suffix.lower() in (".csv", ".npz"):
        raise ValueError(f"--samples picks samples from a MERL file or a .bsdf; {args.input} is a file of samples, "
                         "read whole")
    if (args.width is not None or args.reciprocal) and args.refine != "full":
        raise ValueError(f"{'--width' if args.width is not None else '--reciprocal'} sets the NBRDF that "
                         f"--refine full fits; with --refine {args.refine} there is none")
    report = reconstruct_file(args.input, args.out, model=args.model, refine=args.refine, seed=args.seed,
                              progress=not args.quiet, overwrite=args.overwrite, width=args.width,
                              reciprocal=args.reciprocal, **given)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        metrics = report.get("metrics")
        quality = f"; render PSNR {metrics['psnr']:.2f} dB, ΔE {metrics['delta_e']:.2f}" if metrics else ""
        print(f"reconstructed {args.input} from {report['input']['samples']} samples "
              f"({sum(report['timings_s'].values()):.1f} s){quality}; wrote {os.path.join(args.out, '')}")
    return 0


def _convert(args: argparse.Namespace) -> int:
    from .material.convert import convert

    given = _given(args, "samples")
    if given and Path(args.output).suffix.lower() == ".binary":
        raise ValueError("--samples sets how many samples a .csv or .npz output holds; a .binary output is the whole "
                         "table")
    print(f"wrote {convert(args.input, args.output, seed=args.seed, overwrite=args.overwrite, **given)}")
    return 0


def _given(args: argparse.Namespace, *options: str) -> dict:
    """The ``options`` the user gave (declared with ``default=argparse.SUPPRESS``), so the library's defaults apply
    to the others."""
    return {name: getattr(args, name) for name in options if hasattr(args, name)}


#: The most epochs, renders, edits or materials an integer option of the CLI takes (more would run for years).
MAX_COUNT = 1_000_000
#: The most samples per pixel of a --mitsuba render.
MAX_SPP = 1 << 16


def _limit(module: str, name: str):
    """A limit the library sets (``module.name``), read when an option is parsed: its module is imported then,
    not at every start of the CLI."""
    return lambda: getattr(importlib.import_module(module, __package__), name)


def _whole(low: int, high, what: str = ""):
    """An argparse type: a whole number in ``low … high`` (an int, or a function giving it: :func:`_limit`);
    the message says the range. ``what``: the noun for messages ("a seed")."""
    def parse(text: str) -> int:
        top = high() if callable(high) else high
        digits = text.strip().removeprefix("-").removeprefix("+")
        # ASCII digits only ("²".isdigit() is true), and few of them (int() refuses more than 4300).
        if not (digits.isascii() and digits.isdigit() and len(digits) <= 30 and low <= int(text) <= top):
            raise argparse.ArgumentTypeError(f"{f'{what} is' if what else 'expected'} a whole number in "
                                             f"{low:,} … {top:,}, got {text!r}")
        return int(text)

    return parse


def _seed(text: str) -> int:
    from .configs import MAX_SEED

    return _whole(0, MAX_SEED, "a seed")(text)


# The checked argparse types of the integer options.
_positive_count, _count = _whole(1, MAX_COUNT), _whole(0, MAX_COUNT)
_bank_size = _whole(1, _limit(".data.synth", "MAX_BANK"))
_table_samples = _whole(1, _limit(".io.merl", "N_BINS"))  # drawn from a MERL table's bins
_resolution = _whole(8, _limit(".render.renderer", "MAX_RESOLUTION"))
_evaluate_resolution = _whole(8, _limit(".study.evaluation", "MAX_RESOLUTION"))
_nbrdf_width = _whole(1, _limit(".models.nbrdf", "MAX_WIDTH"))
_lmax = _whole(1, _limit(".models.losses", "MAX_LMAX"))


def _decibels(text: str) -> float:
    """An argparse type: a finite number of dB > 0 (NaN and inf are numbers to ``float()``)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number of dB > 0, got {text!r}")
    return value


def _sample_count(text: str) -> int | None:
    from .material.measurements import MIN_SAMPLES

    if text == "all":
        return None
    if not text.isdigit() or int(text) < MIN_SAMPLES:  # as many as a file of samples must hold
        raise argparse.ArgumentTypeError(f"expected a number ≥ {MIN_SAMPLES} or 'all', got {text!r}")
    return int(text)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="frenbrdf", description=__doc__)
    parser.add_argument("--version", action="version", version=f"frenbrdf {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    info = commands.add_parser("info", help="report the installation and run a self-check")
    info.add_argument("--json", action="store_true", help="print the report as JSON")
    info.set_defaults(run=_info)

    from .data.synth import MIXES

    synth = commands.add_parser("synth", help="write the default bank of analytic materials as MERL files")
    synth.add_argument("out_dir", help="folder to write: a new or empty one, or an earlier bank, which is replaced "
                       "whole")
    synth.add_argument("--n", type=_bank_size, default=100, help="number of materials (default 100)")
    synth.add_argument("--seed", type=_seed, default=0, help="random seed (default 0)")
    synth.add_argument("--mix", choices=tuple(MIXES), default="default",
                       help="default: paints, plastics, metals, fabrics, clear coats; features: what real "
                            "measurements show beyond those (car-paint flakes, retro-reflection, thin films, "
                            "sheen, coats over saturated bases)")
    synth.add_argument("--overwrite", action="store_true",
                       help="replace out_dir even if it holds other files (they are deleted)")
    synth.add_argument("--quiet", action="store_true", help="no progress bar")
    synth.set_defaults(run=_synth)

    imported = commands.add_parser("import-nbrdf", help="evaluate published NBRDF weights (Keras .h5) "
                                   "at every MERL bin and write MERL files")
    imported.add_argument("weights", nargs="+", help=".h5 files")
    imported.add_argument("out_dir", help="folder to write to: a new or empty one, or an earlier import's, which "
                          "grows")
    imported.add_argument("--overwrite", action="store_true", help="replace files an earlier import wrote, and write "
                          "into a folder holding other files (they are kept)")
    imported.add_argument("--quiet", action="store_true", help="no progress bar")
    imported.set_defaults(run=_import_nbrdf)

    train = commands.add_parser("train", help="train FreNBRDF or a baseline on a folder of MERL files and .bsdf "
                                "measurements")
    train.add_argument("--method", choices=method_names(), help="default: frenbrdf")
    train.add_argument("--data", help="folder of MERL .binary files and .bsdf measurements")
    train.add_argument("--out", help="run folder (created)")
    train.add_argument("--config", help="JSON file with any TrainConfig keys, over the method's preset")
    train.add_argument("--epochs", type=_positive_count)
    train.add_argument("--seed", type=_seed)
    train.add_argument("--seeds", type=_seed, nargs="+", metavar="S",
                       help="train once per seed (each its own split and initialisation) into OUT/seed-S")
    train.add_argument("--training", choices=sorted(TRAINING),
                       help="a training length of frenbrdf.presets over the method's preset (default: the full one)")
    train.add_argument("--augmentation", choices=sorted(AUGMENTATION),
                       help="what the batches hold beyond the tables (frenbrdf.presets.AUGMENTATION; default: augmented, "
                       "mixes and colour gains; paper: the tables only, the paper's protocol)")
    train.add_argument("--holdout", nargs="+", metavar="PATTERN",
                       help="glob patterns over material names: the matching materials are the test split "
                       "(a held-out family), the others train and validate")
    train.add_argument("--render-every", type=_count, metavar="N",
                       help="render the validation materials every N epochs and log their PSNR and ΔE (docs/charts: "
                       "chart 7)")
    train.add_argument("--select", choices=SELECTION_RULES,
                       help="what picks best.pt: the validation loss (default) or the validation render PSNR "
                       "(needs --render-every)")
    train.add_argument("--device", choices=("cpu", "cuda", "auto"))
    train.add_argument("--decoder-from", metavar="MODEL", help="train only an encoder, for the decoder and mapping "
                       "of this model (a run folder, a checkpoint, a packed model's folder or 'pretrained'), kept frozen")
    train.add_argument("--init-from", metavar="MODEL", help="fine-tune: start from every weight and the mapping of "
                       "this model (a run folder, a checkpoint, a packed folder or 'pretrained'; the same model config)")
    train.add_argument("--resume", action="store_true", help="continue from RUN_DIR/last.pt")
    train.add_argument("--overwrite", action="store_true", help="train into --out although it holds files (an "
                       "earlier run's files are replaced); without it a non-empty --out is refused")
    train.add_argument("--json", action="store_true", help="print the summary as JSON")
    train.add_argument("--quiet", action="store_true", help="no progress bars")
    train.set_defaults(run=_train)

    fit = commands.add_parser("fit-nbrdf", help="fit one NBRDF per material (Sztrajman et al.; the quality ceiling)")
    fit.add_argument("materials", nargs="+", help="MERL files or .bsdf measurements")
    fit.add_argument("--out", required=True, help="folder for the fitted NBRDFs (<name>.pt)")
    fit.add_argument("--hidden", default="21,21", help="hidden widths (default 21,21)")
    fit.add_argument("--epochs", type=_positive_count, default=10)
    fit.add_argument("--seed", type=_seed, default=0)
    fit.add_argument("--merl", action="store_true", help="also write each fit as a MERL file")
    fit.add_argument("--quiet", action="store_true", help="no progress bar")
    fit.add_argument("--overwrite", action="store_true", help="replace fits already in --out")
    fit.set_defaults(run=_fit_nbrdf)

    evaluate = commands.add_parser("evaluate", help="reconstruction and editing tables and figures for runs")
    evaluate.add_argument("runs", nargs="+", help="run folders: one per method, of one seed or of several "
                          "(grouped by their split; several seeds give mean ± sd and paired intervals)")
    evaluate.add_argument("--out", required=True, help="folder for the tables and figures (a new or empty one, or "
                          "an earlier evaluation's)")
    evaluate.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files")
    evaluate.add_argument("--data", metavar="DIR", help="folder of MERL files and .bsdf measurements (default: the one the runs were "
                          "trained on); with --all, the folder whose materials to evaluate")
    evaluate.add_argument("--all", dest="all_materials", action="store_true",
                          help="evaluate every material of --data DIR that no run trained or validated on "
                          "(out-of-distribution), not the runs' test split")
    evaluate.add_argument("--max-materials", type=_count, default=0, metavar="N",
                          help="evaluate only the first N materials by name (default and 0: all)")
    evaluate.add_argument("--samples", type=_table_samples, default=4000,
                          help="samples given to the encoder (default 4000)")
    evaluate.add_argument("--edits", type=_count, default=2000, help="interpolations for editing (default 2000; 0: no editing table)")
    evaluate.add_argument("--resolution", type=_evaluate_resolution, default=256,
                          help="render size of the reconstruction table (8 … 1024)")
    evaluate.add_argument("--refine", choices=("none", "latent", "full"), default="none",
                          help="also refine each material at test time on the same samples (latent: optimise z; "
                          "full: then the NBRDF's weights) and report the refined rows beside the encoder-only ones "
                          "(default none: encoder only, the paper's protocol)")
    evaluate.add_argument("--quick", action="store_true", help="at most 120 interpolations, 96² editing renders")
    evaluate.add_argument("--json", action="store_true", help="also print the summary as JSON")
    evaluate.add_argument("--quiet", action="store_true", help="no progress bars")
    evaluate.set_defaults(run=_evaluate)

    render = commands.add_parser("render", help="render a material (MERL .binary, RGL .bsdf measurement, saved "
                                 "NBRDF .pt or Keras NBRDF .h5) on a sphere")
    render.add_argument("material")
    render.add_argument("--out", required=True, help="PNG file")
    render.add_argument("--resolution", type=_resolution, default=256)
    render.add_argument("--mitsuba", action="store_true", help="path-trace with Mitsuba 3 instead")
    render.add_argument("--spp", type=_whole(1, MAX_SPP), help="samples per pixel of a --mitsuba render (default 64)")
    render.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    render.set_defaults(run=_render)

    select = commands.add_parser("select", help="the smallest NBRDF/latent configuration (chart 3) whose "
                                 "validation render PSNR reaches a target")
    select.add_argument("--data", required=True, help="folder of MERL files")
    select.add_argument("--target-psnr", required=True, type=_decibels, metavar="DB",
                        help="validation render PSNR to reach, in dB")
    select.add_argument("--out", required=True, help="folder for config.json and the selection report (created)")
    select.add_argument("--front", help="a chart-3 JSON (docs/charts/chart3_capacity.json): choose from its "
                        "measurements, train nothing")
    select.add_argument("--config", help="without --front: JSON training config of the candidates "
                        "(default: FreNBRDF with the sweeps' short training)")
    select.add_argument("--epochs", type=_positive_count, help="without --front: training epochs per candidate")
    select.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files "
                        "(they are kept)")
    select.add_argument("--json", action="store_true", help="print the selection as JSON")
    select.add_argument("--quiet", action="store_true", help="no progress bars")
    select.set_defaults(run=_select)

    rec = commands.add_parser("reconstruct", help="a material from your measurements (CSV/NPZ of samples, a "
                              "MERL file or an RGL .bsdf): NBRDF, MERL table, render and report in one folder")
    rec.add_argument("input", help="CSV or NPZ with columns wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b (or angles; see "
                     "frenbrdf.material.measurements), a MERL .binary file or an RGL .bsdf measurement")
    rec.add_argument("--out", required=True, help="result folder: a new or empty one, or an earlier result "
                     "folder, which is replaced whole (never the input's folder)")
    rec.add_argument("--overwrite", action="store_true", help="replace --out even if it holds other files "
                     "(they are deleted)")
    rec.add_argument("--model", default="pretrained", help="training run folder, checkpoint, or 'pretrained' "
                     "(the model shipped in the package; the default)")
    rec.add_argument("--samples", type=_sample_count, default=argparse.SUPPRESS, metavar="N|all",
                     help="MERL or .bsdf input: random valid bins given to the model (default 4000), or all")
    rec.add_argument("--refine", choices=("none", "latent", "full"), default="full",
                     help="test-time refinement: none (encoder only), latent (optimise z: stays in the latent "
                     "space, for editing), full (then the NBRDF's weights; the default: charts 8–8c)")
    rec.add_argument("--width", type=_nbrdf_width, metavar="N",
                     help="with --refine full: widen the NBRDF to at least N hidden "
                     "units per layer before refining its weights (default 64; wider: more fidelity for more "
                     "time)")
    rec.add_argument("--reciprocal", action="store_true", help="with --refine full: keep the NBRDF reciprocal even "
                     "when the samples hold both orders of pairs (a .bsdf measurement does; by default the NBRDF then "
                     "tells them apart, as the measurement does near grazing)")
    rec.add_argument("--seed", type=_seed, default=0, help="seeds the sampling and the refinement (default 0)")
    rec.add_argument("--json", action="store_true", help="print the report as JSON")
    rec.add_argument("--quiet", action="store_true", help="no progress bars")
    rec.set_defaults(run=_reconstruct)

    convert = commands.add_parser("convert", help="an RGL .bsdf measurement into a MERL .binary table, or a .bsdf "
                                  "or MERL file into a CSV/NPZ of samples that reconstruct reads")
    convert.add_argument("input", help="a .bsdf measurement or a MERL .binary file")
    convert.add_argument("output", help="a .binary (MERL table), .csv or .npz (samples) file to write")
    convert.add_argument("--samples", type=_sample_count, default=argparse.SUPPRESS, metavar="N|all",
                         help="CSV/NPZ output: random valid MERL bins to sample (default 4000), or all")
    convert.add_argument("--seed", type=_seed, default=0, help="seeds the sampling (default 0)")
    convert.add_argument("--overwrite", action="store_true", help="replace the output file if it exists")
    convert.set_defaults(run=_convert)

    from .presets import FREQUENCY_VARIANTS

    spectrum = commands.add_parser("spectrum", help="per-degree power spectra of materials (MERL .binary, RGL "
                                   ".bsdf, NBRDF .pt/.h5) and of reconstructions against their truth, per θ_h slice "
                                   "and channel: plot, CSV and JSON")
    spectrum.add_argument("materials", nargs="+", help="material files")
    spectrum.add_argument("--out", required=True, help="folder of spectrum.{png,csv,json}: a new or empty one, or "
                          "an earlier spectrum folder")
    spectrum.add_argument("--truth", help="a material file every material is compared with (its error spectrum)")
    spectrum.add_argument("--variant", choices=sorted(FREQUENCY_VARIANTS), default="tone",
                          help="the L_fre settings the spectra are taken at (default tone: ln(1 + f), fitted to the "
                          "measured nodes only; docs/frequency.md)")
    spectrum.add_argument("--lmax", type=_lmax, help="band limit (default: the variant's, 49)")
    spectrum.add_argument("--overwrite", action="store_true", help="replace --out even if it holds other files")
    spectrum.add_argument("--json", action="store_true", help="print the band summaries as JSON")
    spectrum.set_defaults(run=_spectrum)

    demo = commands.add_parser("demo", help="the main job: synthesise data, train all methods, evaluate, report")
    demo.add_argument("--out", default="frenbrdf-demo", help="report folder (default frenbrdf-demo)")
    demo.add_argument("--data", help="folder of MERL files instead of the synthetic bank")
    demo.add_argument("--epochs", type=_positive_count, help="training epochs per method (default: the demo's)")
    demo.add_argument("--augmentation", choices=sorted(AUGMENTATION), default="augmented",
                      help="what the batches hold beyond the tables (default: augmented, mixes and colour gains; "
                      "paper: the tables only)")
    demo.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files (they "
                      "are kept); an earlier demo's report folder is replaced without it")
    demo.add_argument("--quiet", action="store_true", help="no progress bars")
    demo.set_defaults(run=_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except (ValueError, OSError, TrainingDiverged) as error:  # bad input: a clear message, not a traceback
        parser.exit(2, f"frenbrdf {args.command}: error: {error}\n")
    except KeyboardInterrupt:  # Ctrl-C: one line; every output is written atomically, so nothing is left half-written
        parser.exit(130, f"frenbrdf {args.command}: interrupted\n")
    except RuntimeError as error:
        if not str(error).startswith("Symlink loop"):  # pathlib raises this for a link loop before Python 3.13
            raise
        parser.exit(2, f"frenbrdf {args.command}: error: {error} (a link that leads back to itself)\n")


if __name__ == "__main__":
    sys.exit(main())
