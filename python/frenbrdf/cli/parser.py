"""The CLI's parser: one function per command declares its options."""

from __future__ import annotations

import argparse

from .._native import __version__
from ..presets import AUGMENTATION, FREQUENCY_VARIANTS, SAMPLING, SELECTION_RULES, TRAINING, method_names
from . import commands, options

DESCRIPTION = "frenbrdf: neural BRDFs (FreNBRDF) from measured materials: train, reconstruct, render, evaluate."


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command; each command's run function is ``args.run``."""
    parser = argparse.ArgumentParser(prog="frenbrdf", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"frenbrdf {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for add in COMMANDS:
        add(subparsers)
    return parser


def _info(subparsers) -> None:
    info = subparsers.add_parser("info", help="report the installation and run a self-check")
    info.add_argument("--json", action="store_true", help="print the report as JSON")
    info.set_defaults(run=commands.info)


def _synth(subparsers) -> None:
    synth = subparsers.add_parser("synth", help="write the default bank of analytic materials as MERL files")
    synth.add_argument("out_dir", help="folder to write: a new or empty one, or an earlier bank, which is replaced")
    synth.add_argument("--n", type=options.bank_size, default=100, help="number of materials (default 100)")
    synth.add_argument("--seed", type=options.seed, default=0, help="random seed (default 0)")
    synth.add_argument("--mix", type=options.bank_mix, default="default", metavar="MIX",
                       help="default: paints, plastics, metals, fabrics, clear coats; features: what real "
                            "measurements show beyond those (car-paint flakes, retro-reflection, thin films, "
                            "sheen, coats over saturated bases); families: thin-film iridescence, pearlescent "
                            "pigments whose colour turns with angle, glitter of one hue over a base of another; "
                            "diffractive: flakes with a grating, rainbows about every highlight")
    synth.add_argument("--overwrite", action="store_true",
                       help="write into out_dir although it holds other files (they are kept)")
    synth.add_argument("--quiet", action="store_true", help="no progress bar")
    synth.set_defaults(run=commands.synth)


def _import_nbrdf(subparsers) -> None:
    imported = subparsers.add_parser("import-nbrdf", help="evaluate published NBRDF weights (Keras .h5) "
                                   "at every MERL bin and write MERL files")
    imported.add_argument("weights", nargs="+", help=".h5 files")
    imported.add_argument("out_dir", help="folder to write to: a new or empty one, or an earlier import's, which "
                          "grows")
    imported.add_argument("--overwrite", action="store_true", help="replace files an earlier import wrote, and write "
                          "into a folder holding other files (they are kept)")
    imported.add_argument("--quiet", action="store_true", help="no progress bar")
    imported.set_defaults(run=commands.import_nbrdf)


def _train(subparsers) -> None:
    train = subparsers.add_parser("train", help="train FreNBRDF or a baseline on a folder of MERL files and .bsdf "
                                "measurements")
    train.add_argument("--method", choices=method_names(), help="default: frenbrdf")
    train.add_argument("--data", help="folder of MERL .binary files and .bsdf measurements")
    train.add_argument("--out", help="run folder: a new or empty one")
    train.add_argument("--config", help="JSON file with any TrainConfig keys, over the method's preset")
    train.add_argument("--epochs", type=options.positive_count)
    train.add_argument("--seed", type=options.seed)
    train.add_argument("--seeds", type=options.seed, nargs="+", metavar="S",
                       help="train once per seed (each its own split and initialisation) into OUT/seed-S")
    train.add_argument("--training", choices=sorted(TRAINING),
                       help="a training length of frenbrdf.presets over the method's preset (default: the full one)")
    train.add_argument("--augmentation", choices=sorted(AUGMENTATION),
                       help="what the batches hold beyond the tables (frenbrdf.presets.AUGMENTATION; default: augmented, "
                       "mixes and colour gains; paper: the tables only, the paper's protocol)")
    train.add_argument("--sampling", choices=sorted(SAMPLING),
                       help="how the encoder's samples of each material are drawn (frenbrdf.presets.SAMPLING; default: "
                       "paper, random valid MERL bins; instruments: the sampling patterns of real devices, 300 … 4000 "
                       "samples; mixed: random bins half the time, the devices' patterns the rest, which reads devices "
                       "best)")
    train.add_argument("--holdout", nargs="+", metavar="PATTERN",
                       help="glob patterns over material names: the matching materials are the test split "
                       "(a held-out family), the others train and validate")
    train.add_argument("--render-every", type=options.count, metavar="N",
                       help="render the validation materials every N epochs and log their PSNR and ΔE")
    train.add_argument("--select", choices=SELECTION_RULES,
                       help="what picks best.pt: the validation loss (default) or the validation render PSNR "
                       "(needs --render-every)")
    train.add_argument("--device", choices=("cpu", "cuda", "auto"))
    train.add_argument("--decoder-from", metavar="MODEL", help="train only an encoder, for the decoder and mapping "
                       "of this model (a run folder, a checkpoint, a packed model's folder or 'pretrained'), kept frozen")
    train.add_argument("--init-from", metavar="MODEL", help="fine-tune: start from every weight and the mapping of "
                       "this model (a run folder, a checkpoint, a packed folder or 'pretrained'; the same model config); with "
                       "--decoder-from, only the encoder starts from this model's")
    train.add_argument("--resume", action="store_true", help="continue from RUN_DIR/last.pt")
    train.add_argument("--overwrite", action="store_true", help="train into --out although it holds an earlier "
                       "run (its files are replaced) or other files (they are kept)")
    train.add_argument("--json", action="store_true", help="print the summary as JSON")
    train.add_argument("--quiet", action="store_true", help="no progress bars")
    train.set_defaults(run=commands.train)


def _fit_nbrdf(subparsers) -> None:
    fit = subparsers.add_parser("fit-nbrdf", help="fit one NBRDF per material (Sztrajman et al.; the quality ceiling)")
    fit.add_argument("materials", nargs="+", help="MERL files or .bsdf measurements")
    fit.add_argument("--out", required=True, help="folder for the fitted NBRDFs (<name>.pt): a new or empty one, or "
                     "an earlier fit-nbrdf's, which grows")
    fit.add_argument("--hidden", default="21,21", help="hidden widths (default 21,21)")
    fit.add_argument("--epochs", type=options.positive_count, default=10)
    fit.add_argument("--seed", type=options.seed, default=0)
    fit.add_argument("--merl", action="store_true", help="also write each fit as a MERL file")
    fit.add_argument("--quiet", action="store_true", help="no progress bar")
    fit.add_argument("--overwrite", action="store_true", help="replace fits an earlier fit-nbrdf wrote, and write "
                     "into a folder holding other files (they are kept)")
    fit.set_defaults(run=commands.fit_nbrdf)


def _fit_decoder(subparsers) -> None:
    fit = subparsers.add_parser("fit-decoder", help="fit a trained run's decoder further, each training material's "
                                "latent free: `latent` then reaches more of every material (train its encoders "
                                "again with `train --decoder-from OUT`)")
    fit.add_argument("source", metavar="RUN", help="a training run folder (`frenbrdf train --out`); its data "
                     "folder must hold its materials still")
    fit.add_argument("--out", required=True, help="the fitted run folder: a new or empty one")
    fit.add_argument("--epochs", type=options.fit_epochs, default=300, help="passes over the training materials "
                     "(default 300)")
    fit.add_argument("--decoder-lr", type=options.rate, default=1e-4, help="Adam rate of the decoder (default 1e-4)")
    fit.add_argument("--latent-lr", type=options.rate, default=1e-3, help="Adam rate of the latents (default 1e-3)")
    fit.add_argument("--encoder-weight", type=options.loss_weight, default=0.0, help="0 (default): the encoder's "
                     "z plays no part; above 0: the loss adds the decoding of its z, weighted by this, so the decoder "
                     "stays one the encoder can read")
    fit.add_argument("--encoder-lr", type=options.rate_or_zero, default=1e-4, help="with --encoder-weight: Adam "
                     "rate of the encoder (default 1e-4); 0 keeps it as it is")
    fit.add_argument("--encoder-augment", action="store_true", help="with --encoder-weight: the encoder's "
                     "materials drawn as the run's training drew them (its mixes, gains, hue turns, procedural "
                     "materials, sampling patterns)")
    fit.add_argument("--seed", type=options.seed, default=0)
    fit.add_argument("--overwrite", action="store_true", help="replace an earlier fit-decoder's output in --out")
    fit.add_argument("--quiet", action="store_true", help="no progress bar")
    fit.set_defaults(run=commands.fit_decoder)


def _evaluate(subparsers) -> None:
    evaluate = subparsers.add_parser("evaluate", help="reconstruction and editing tables and figures for runs")
    evaluate.add_argument("runs", nargs="+", help="run folders: one per method, of one seed or of several "
                          "(grouped by their split; several seeds give mean ± sd and paired intervals)")
    evaluate.add_argument("--out", required=True, help="folder for the tables and figures (a new or empty one, or "
                          "an earlier evaluation's)")
    evaluate.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files "
                          "(they are kept)")
    evaluate.add_argument("--data", metavar="DIR", help="folder of MERL files and .bsdf measurements (default: the one the runs were "
                          "trained on); with --all, the folder whose materials to evaluate")
    evaluate.add_argument("--all", dest="all_materials", action="store_true",
                          help="evaluate every material of --data DIR that no run trained or validated on "
                          "(out-of-distribution), not the runs' test split")
    evaluate.add_argument("--max-materials", type=options.count, default=0, metavar="N",
                          help="evaluate only the first N materials by name (default and 0: all)")
    evaluate.add_argument("--samples", type=options.table_samples, default=4000,
                          help="samples given to the encoder (default 4000)")
    evaluate.add_argument("--patterns", type=options.pattern, nargs="+", default=["merl-bins"], metavar="NAME",
                          help="sampling patterns to encode each material from, each its own rows (default "
                          "merl-bins: random valid bins; gonioreflectometer, image-based, in-plane, …: "
                          "frenbrdf.io.patterns); editing and the figures use the first")
    evaluate.add_argument("--edits", type=options.count, default=2000, help="interpolations for editing (default 2000; 0: no editing table)")
    evaluate.add_argument("--resolution", type=options.evaluate_resolution, default=256,
                          help="render size of the reconstruction table (8 … 1024)")
    evaluate.add_argument("--refine", choices=("none", "latent", "full"), default="none",
                          help="also refine each material at test time on the same samples (latent: optimise z; "
                          "full: then the NBRDF's weights) and report the refined rows beside the encoder-only ones "
                          "(default none: encoder only, the paper's protocol)")
    evaluate.add_argument("--quick", action="store_true", help="at most 120 interpolations, 96² editing renders")
    evaluate.add_argument("--json", action="store_true", help="also print the summary as JSON")
    evaluate.add_argument("--quiet", action="store_true", help="no progress bars")
    evaluate.set_defaults(run=commands.evaluate)


def _render(subparsers) -> None:
    render = subparsers.add_parser("render", help="render a material (MERL .binary, RGL .bsdf measurement, saved "
                                 "NBRDF .pt or Keras NBRDF .h5) on a sphere")
    render.add_argument("material")
    render.add_argument("--out", required=True, help="PNG file")
    render.add_argument("--resolution", type=options.resolution, default=256)
    render.add_argument("--mitsuba", action="store_true", help="path-trace with Mitsuba 3 instead")
    render.add_argument("--spp", type=options.whole(1, options.MAX_SPP), help="samples per pixel of a --mitsuba render (default 64)")
    render.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    render.add_argument("--quiet", action="store_true", help="no progress bar (shown for renders of 1024² and up)")
    render.set_defaults(run=commands.render)


def _select(subparsers) -> None:
    select = subparsers.add_parser("select", help="the smallest NBRDF/latent configuration whose "
                                 "validation render PSNR reaches a target")
    select.add_argument("--data", required=True, help="folder of MERL files")
    select.add_argument("--target-psnr", required=True, type=options.decibels, metavar="DB",
                        help="validation render PSNR to reach, in dB")
    select.add_argument("--out", required=True, help="folder for config.json and the selection report: a new or "
                        "empty one, or an earlier selection's (its trained candidates are reused)")
    select.add_argument("--front", help="a measured capacity front (JSON, as research/charts/chart_capacity.py "
                        "writes it): choose from its measurements, train nothing")
    select.add_argument("--config", help="without --front: JSON training config of the candidates "
                        "(default: FreNBRDF with the sweeps' short training)")
    select.add_argument("--epochs", type=options.positive_count, help="without --front: training epochs per candidate")
    select.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files "
                        "(they are kept)")
    select.add_argument("--json", action="store_true", help="print the selection as JSON")
    select.add_argument("--quiet", action="store_true", help="no progress bars")
    select.set_defaults(run=commands.select)


def _reconstruct(subparsers) -> None:
    rec = subparsers.add_parser("reconstruct", help="a material from your measurements (CSV/NPZ/ASTM E1392 "
                              "samples, a MERL file or an RGL .bsdf): NBRDF, MERL table, render and report in one "
                              "folder")
    rec.add_argument("input", help="CSV or NPZ with columns wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b (or angles; see "
                     "frenbrdf.io.samples), an ASTM E1392 .astm file (theta_i,phi_i,theta_s,phi_s in radians, "
                     "then R,G,B or one BRDF column; see frenbrdf.io.astm), a MERL .binary file or an RGL .bsdf "
                     "measurement")
    rec.add_argument("--out", required=True, help="result folder: a new or empty one, or an earlier result "
                     "folder, which is replaced (never the input's folder)")
    rec.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files "
                     "(they are kept)")
    rec.add_argument("--model", default="pretrained", help="training run folder, checkpoint, or 'pretrained' "
                     "(the model shipped in the package; the default)")
    rec.add_argument("--samples", type=options.sample_count, default=argparse.SUPPRESS, metavar="N|all",
                     help="MERL or .bsdf input: random valid bins given to the model (default 4000), or all; "
                     "with --pattern, its pairs")
    rec.add_argument("--pattern", type=options.pattern, default=argparse.SUPPRESS, metavar="NAME",
                     help="MERL or .bsdf input: the sampling pattern, the device imitated (default merl-bins: "
                     "random valid bins; gonioreflectometer, image-based, in-plane, …: frenbrdf.io.patterns, "
                     "docs/usage.md)")
    rec.add_argument("--refine", choices=("none", "latent", "full"), default="full",
                     help="test-time refinement: none (encoder only), latent (optimise z: stays in the latent "
                     "space, for editing), full (then the NBRDF's weights; the default)")
    rec.add_argument("--width", type=options.nbrdf_width, metavar="N",
                     help="with --refine full: widen the NBRDF to at least N hidden "
                     "units per layer before refining its weights (default 64; wider: more fidelity for more "
                     "time)")
    rec.add_argument("--reciprocal", action="store_true", help="with --refine full: keep the NBRDF reciprocal even "
                     "when the samples hold both orders of pairs (a .bsdf measurement does; by default the NBRDF then "
                     "tells them apart, as the measurement does near grazing)")
    rec.add_argument("--coverage", type=options.coverage_k, metavar="K",
                     help="with --refine latent or full: the latent stage weighs each sample by how thinly the "
                     "samples cover its region (k-NN densities with this K; 0: every sample alike). Default: 32 "
                     "with --refine latent where the samples come from a device (--pattern other than merl-bins, "
                     "or an .astm file: +2 dB), else 0 (random bins: -0.2 dB; full: not measured); docs/usage.md")
    rec.add_argument("--seed", type=options.seed, default=0, help="seeds the sampling and the refinement (default 0)")
    rec.add_argument("--json", action="store_true", help="print the report as JSON")
    rec.add_argument("--quiet", action="store_true", help="no progress bars")
    rec.set_defaults(run=commands.reconstruct)


def _edit(subparsers) -> None:
    edit = subparsers.add_parser("edit", help="the edit between two measured materials that keeps each (at t = 0 and "
                                 "1 each one's reconstruction, unlike the latent interpolation): MERL tables and "
                                 "renders along t in one folder")
    edit.add_argument("input_a", metavar="A", help="the material at t = 0: a file of samples (.csv, .npz, .astm), a "
                      "MERL .binary file or an RGL .bsdf measurement, as reconstruct reads it")
    edit.add_argument("input_b", metavar="B", help="the material at t = 1 (the same file as A is allowed)")
    edit.add_argument("--t", type=options.unit_interval, nargs="+", action="extend", metavar="T",
                      help="positions along the edit, each in 0 … 1 (0: A, 1: B), at most 33; --t 0 0.5 1 or --t 0.3 "
                      "--t 0.6 (default 0 0.25 0.5 0.75 1)")
    edit.add_argument("--out", required=True, help="result folder: a new or empty one, or an earlier edit's "
                      "folder, which is replaced (never an input's folder)")
    edit.add_argument("--latent", action="store_true", help="the plain latent interpolation instead: the model's "
                      "decodings of (1 − t) z_A + t z_B, whose ends are the decodings, not the materials "
                      "(the inputs then refined with --refine latent unless given)")
    edit.add_argument("--model", default="pretrained", help="training run folder, checkpoint, packed model's "
                      "folder or 'pretrained' (the default): the model that reconstructs both and holds the "
                      "latent space")
    edit.add_argument("--refine", choices=("none", "latent", "full"),
                      help="how each input is reconstructed (as reconstruct's --refine; default full, latent with "
                      "--latent)")
    edit.add_argument("--samples", type=options.sample_count, default=argparse.SUPPRESS, metavar="N|all",
                      help="MERL or .bsdf input: random valid bins given to the model (default 4000), or all")
    edit.add_argument("--pattern", type=options.pattern, default=argparse.SUPPRESS, metavar="NAME",
                      help="MERL or .bsdf input: the sampling pattern (default merl-bins; see reconstruct)")
    edit.add_argument("--resolution", type=options.edit_resolution, default=256, help="render size (8 … 1024, "
                      "default 256)")
    edit.add_argument("--seed", type=options.seed, default=0, help="seeds the sampling and the refinement "
                      "(default 0)")
    edit.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files "
                      "(they are kept)")
    edit.add_argument("--json", action="store_true", help="print the report as JSON")
    edit.add_argument("--quiet", action="store_true", help="no progress bars")
    edit.set_defaults(run=commands.edit)


def _convert(subparsers) -> None:
    convert = subparsers.add_parser("convert", help="an RGL .bsdf measurement into a MERL .binary table, a .bsdf "
                                  "or MERL file into a CSV/NPZ/ASTM E1392 file of samples that reconstruct reads, "
                                  "or a file of samples into another format")
    convert.add_argument("input", help="a .bsdf measurement, a MERL .binary file, or a .csv, .npz or .astm file of "
                         "samples")
    convert.add_argument("output", help="a .binary (MERL table; not from samples), .csv, .npz or .astm (samples) "
                         "file to write")
    convert.add_argument("--samples", type=options.sample_count, default=argparse.SUPPRESS, metavar="N|all",
                         help="a .bsdf or MERL input into samples: random valid MERL bins to sample (default "
                         "4000), or all; with --pattern, its pairs")
    convert.add_argument("--pattern", type=options.pattern, default=argparse.SUPPRESS, metavar="NAME",
                         help="a .bsdf or MERL input into samples: the sampling pattern, the device imitated "
                         "(default merl-bins; see reconstruct)")
    convert.add_argument("--seed", type=options.seed, default=0, help="seeds the sampling (default 0)")
    convert.add_argument("--overwrite", action="store_true", help="replace the output file if it exists")
    convert.set_defaults(run=commands.convert)


def _view(subparsers) -> None:
    view = subparsers.add_parser("view", help="one self-contained HTML page that renders a material live in WebGL2 "
                               "(turn the light, polar plot, θ_h × θ_d image); two materials: an edit slider")
    view.add_argument("input", help="a saved NBRDF (.pt), a Keras NBRDF (.h5), a reconstruct result folder, a MERL "
                      ".binary file or an RGL .bsdf measurement (these two shown as the packaged model's fit)")
    view.add_argument("input_b", nargs="?", metavar="INPUT_B", help="a second material: the page edits between them")
    view.add_argument("--out", required=True, help="the HTML file to write")
    view.add_argument("--model", help="the model that fits measurements and holds the edit's latent space (default: "
                      "a result folder's, else the packaged one)")
    view.add_argument("--title", help="the page's heading (default: the materials' names)")
    view.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    view.add_argument("--quiet", action="store_true", help="no progress bars")
    view.set_defaults(run=commands.view)


def _spectrum(subparsers) -> None:
    spectrum = subparsers.add_parser("spectrum", help="per-degree power spectra of materials (MERL .binary, RGL "
                                   ".bsdf, NBRDF .pt/.h5) and of reconstructions against their truth, per θ_h slice "
                                   "and channel: plot, CSV and JSON")
    spectrum.add_argument("materials", nargs="+", help="material files")
    spectrum.add_argument("--out", required=True, help="folder of spectrum.{png,csv,json}: a new or empty one, or "
                          "an earlier spectrum folder")
    spectrum.add_argument("--truth", help="a material file every material is compared with (its error spectrum)")
    spectrum.add_argument("--variant", choices=sorted(FREQUENCY_VARIANTS), default="tone",
                          help="the L_fre settings the spectra are taken at (default tone: ln(1 + f), fitted to the "
                          "measured nodes only; research/frequency.md)")
    spectrum.add_argument("--lmax", type=options.lmax, help="band limit (default: the variant's, 49)")
    spectrum.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files "
                          "(they are kept)")
    spectrum.add_argument("--json", action="store_true", help="print the band summaries as JSON")
    spectrum.set_defaults(run=commands.spectrum)


def _demo(subparsers) -> None:
    demo = subparsers.add_parser("demo", help="the main job: synthesise data, train all methods, evaluate, report")
    demo.add_argument("--out", default="frenbrdf-demo", help="report folder (default frenbrdf-demo)")
    demo.add_argument("--data", help="folder of MERL files instead of the synthetic bank")
    demo.add_argument("--epochs", type=options.positive_count, help="training epochs per method (default: the demo's)")
    demo.add_argument("--augmentation", choices=sorted(AUGMENTATION), default="augmented",
                      help="what the batches hold beyond the tables (default: augmented, mixes and colour gains; "
                      "paper: the tables only)")
    demo.add_argument("--overwrite", action="store_true", help="write into --out although it holds other files (they "
                      "are kept); an earlier demo's report folder is replaced without it")
    demo.add_argument("--quiet", action="store_true", help="no progress bars")
    demo.set_defaults(run=commands.demo)


#: Every command, in the order ``--help`` lists them.
COMMANDS = (_info, _synth, _import_nbrdf, _train, _fit_nbrdf, _fit_decoder, _evaluate, _render, _select, _reconstruct, _edit, _convert, _view, _spectrum, _demo)
