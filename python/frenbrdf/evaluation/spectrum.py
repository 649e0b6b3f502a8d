"""Per-degree power spectra of materials, and of reconstructions against their truth: ``frenbrdf spectrum``.

A material is analysed as L_fre analyses it (:mod:`frenbrdf.models.losses`, research/frequency.md): each θ_h
slice of the BRDF as a function of the difference direction, expanded in spherical harmonics. The
settings are an L_fre variant (:data:`frenbrdf.presets.FREQUENCY_VARIANTS`; by default ``tone``: the
spectrum of ln(1 + f) fitted to the measured nodes only, so nothing below the horizon shows). The
per-degree power of slice s, channel c is

    P_l = Σ_m c_lm² / 4π,        Σ_l P_l = the mean square of the (band-limited) slice over the sphere,

and the error spectrum of a reconstruction A against its truth T is the same sum over c^A_lm − c^T_lm:
where A loses its frequencies shows as the degrees where the error's power reaches the truth's.

- A table (a MERL ``.binary``, or an RGL ``.bsdf`` at the MERL bins, :func:`frenbrdf.io.read_table`)
  is interpolated from its valid bins onto the grid (kNN), as L_fre's truth;
- an NBRDF (``.pt`` of ``fit-nbrdf``/``reconstruct``, a Keras ``.h5``, :func:`frenbrdf.io.read_material`)
  is evaluated at the grid nodes, as L_fre's prediction (its own values below the horizon too), and any
  other BRDF ``f(wi, wo)`` the same way (what it returns below the horizon, often 0). Under the ``"sphere"``
  fit (``paper``) the nodes below the horizon count, so a BRDF and its own table differ there: L_fre's floor.

Values "mapped" (the variants ``paper``, ``no-floor``) are ln(f + ε), ε = 0.002: the models' mapped space up to
a per-channel constant, which moves l = 0 only.

:func:`spectrum_report` writes ``spectrum.png``, ``spectrum.csv`` (one row per material, slice, channel and
degree) and ``spectrum.json`` into a checked folder, each file atomically; :func:`plot_spectra` draws the plot
for others (``frenbrdf reconstruct`` writes it for its reconstruction and the truth).
"""

from __future__ import annotations

import numbers
import os
from pathlib import Path

import numpy as np
import torch

from ..io.atomic import save_csv, save_json
from ..io.formats import read_material
from ..io.merl import N_BINS, merl_bin_angles
from ..io.nbrdf import NBRDFWeights
from ..io.outputs import OutputFolder
from ..io.paths import naming
from ..io.sampling import as_table
from ..models.frequency_fit import slice_directions
from ..models.losses import (
    MAX_LMAX,
    MAX_MEASURED_LMAX,
    SPHERE_AREA,
    FrequencyLoss,
    FrequencyLossConfig,
    FrequencyTruth,
    frequency_variant,
)
from ..models.mapping import LogRelativeMapping
from ..models.nbrdf import NBRDF, as_brdf
from ..numerics.sht import SHT

#: The files of a spectrum folder.
FILES = {"plot": "spectrum.png", "csv": "spectrum.csv", "report": "spectrum.json"}
#: ε of the "mapped" values, ln(f + ε).
EPSILON = 0.002
#: The largest band limit every variant takes, that of the default ``tone`` (a fit to the measured nodes; measured
#: peak memory of ``frenbrdf spectrum``: 1.6 GB); those fitting the whole sphere take more (:func:`largest_lmax`).
MAX_SPECTRUM_LMAX = MAX_MEASURED_LMAX
#: Degree bands of the summaries (as ``research/studies/lfre_floor.py``).
BANDS = ((0, 0), (1, 4), (5, 16), (17, 10_000))


class SpectrumAnalyser:
    """SH coefficients and per-degree power of materials, at the settings of an L_fre variant (default: ``tone``)."""

    def __init__(self, config: FrequencyLossConfig | None = None):
        config = frequency_variant("tone") if config is None else config
        self.config = config
        self.mapping = LogRelativeMapping(np.full(3, 1 - EPSILON), EPSILON)  # mapped = ln(f + ε)
        self.truth = FrequencyTruth(config, mapping=self.mapping)
        self.loss = FrequencyLoss(config, self.mapping)
        sht = SHT(config.nlat, config.nlon, config.lmax, config.grid)
        self.degrees = sht.degrees_orders()[:, 0]
        theta, phi = np.meshgrid(sht.theta[:self.loss.n_north], 2 * np.pi * np.arange(config.nlon // 2) / config.nlon,
                                 indexing="ij")
        theta_h = merl_bin_angles()[0][list(config.slices)]
        pairs = [slice_directions(t, theta.reshape(-1), phi.reshape(-1)) for t in theta_h]
        self.wi, self.wo = np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])

    @property
    def theta_h_degrees(self) -> list[float]:
        return [float(np.degrees(merl_bin_angles()[0][i])) for i in self.config.slices]

    def coefficients(self, source) -> np.ndarray:
        """``(S, 3, ncoeff)`` of a MERL-shaped table ``(3, 90, 90, 180)`` (missing bins negative) or of a BRDF
        ``f(wi, wo) -> (..., 3)`` (an :class:`~frenbrdf.NBRDF`, a measurement)."""
        if isinstance(source, np.ndarray):
            flat = source.reshape(3, N_BINS)
            valid = np.all(flat >= 0, axis=0)
            if not valid.any():
                raise ValueError("the table holds no valid bin")
            mapped = self.mapping.forward(np.where(valid, flat, 0.0), self.mapping.reference[:, None])
            return self.truth.coefficients(mapped.T, valid).astype(np.float64)
        if not callable(source):
            raise TypeError(f"cannot analyse a {type(source).__name__}: give a MERL table or a BRDF f(wi, wo)")
        if isinstance(source, NBRDF):  # as L_fre sees it: the network's own values, below the horizon too
            source = source.in_table_order()  # the grid's pairs are in a table's order
            with np.errstate(over="ignore"):
                reflectance = source.mapping.inverse(source.mapped(self.loss.node_coords.numpy()),
                                                     source.mapping.reference_at(self.wi, self.wo))
        else:
            reflectance = np.asarray(source(self.wi, self.wo), dtype=np.float64)
        if reflectance.shape != self.wi.shape or not np.all(np.isfinite(reflectance)):
            raise ValueError(f"the BRDF returned {reflectance.shape} values (expected {self.wi.shape}, all finite)")
        mapped = self.mapping.forward(np.maximum(reflectance, 0.0), self.mapping.reference)
        with torch.no_grad():
            return self.loss.coefficients_from_nodes(torch.from_numpy(mapped[None]))[0].numpy().astype(np.float64)

    def power(self, coefficients: np.ndarray) -> np.ndarray:
        """Per-degree power ``(..., lmax + 1)`` of coefficients ``(..., ncoeff)``: Σ_m c_lm² / 4π."""
        squared = np.moveaxis(np.asarray(coefficients) ** 2, -1, 0)
        power = np.zeros((self.config.lmax + 1,) + squared.shape[1:])
        np.add.at(power, self.degrees, squared)
        return np.moveaxis(power, 0, -1) / SPHERE_AREA


def band_shares(power: np.ndarray) -> dict[str, float]:
    """The share of the total power ``(..., L)`` in each degree band of :data:`BANDS`."""
    by_degree = power.reshape(-1, power.shape[-1]).sum(0)
    total = by_degree.sum() or 1.0
    return {_band_name(low, high, len(by_degree) - 1): float(by_degree[low:high + 1].sum() / total)
            for low, high in BANDS if low < len(by_degree)}


def relative_error_by_band(error: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Σ over a band of the error's power / Σ of the truth's, per degree band (1: as much error as signal)."""
    error, truth = (p.reshape(-1, p.shape[-1]).sum(0) for p in (error, truth))
    return {_band_name(low, high, len(truth) - 1): float(error[low:high + 1].sum() / max(truth[low:high + 1].sum(), 1e-30))
            for low, high in BANDS if low < len(truth)}


def _band_name(low: int, high: int, lmax: int) -> str:
    return f"l {low}" if high == low else f"l {low}–{min(high, lmax)}"


def load_source(path: str | os.PathLike):
    """A material file as :meth:`SpectrumAnalyser.coefficients` takes it: a ``.bsdf`` as its MERL table, a MERL
    file as its table, an NBRDF (``.pt``, ``.h5``) as itself."""
    material = read_material(path)
    return as_brdf(material) if isinstance(material, NBRDFWeights) else as_table(material)


def plot_spectra(powers: dict[str, np.ndarray], path: str | os.PathLike, *, errors: dict[str, np.ndarray] | None = None,
                 theta_h: list[float], title: str = "") -> None:
    """Draws per-degree power, one panel per θ_h slice, the channels' mean (log scale): each material a line,
    a reconstruction's error against its truth dashed in its colour. ``powers``: name → ``(S, 3, L)``; the
    first of them in black when ``errors`` are given (the truth). Written atomically as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..render.renderer import save_figure

    errors = errors or {}
    n = len(theta_h)
    figure, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8), squeeze=False, sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for s, ax in enumerate(axes[0]):
        for i, (name, power) in enumerate(powers.items()):
            truth_line = bool(errors) and i == 0
            colour = "k" if truth_line else colours[(i - bool(errors)) % len(colours)]
            curve = power[s].mean(0)
            ax.semilogy(np.arange(len(curve)), np.maximum(curve, 1e-16), color=colour, lw=2 if truth_line else 1.2,
                        label=name if s == 0 else None)
            if name in errors:
                error = errors[name][s].mean(0)
                ax.semilogy(np.arange(len(error)), np.maximum(error, 1e-16), "--", color=colour, lw=1,
                            label=f"{name} − truth" if s == 0 else None)
        ax.set_title(f"θ_h = {theta_h[s]:.2g}°", fontsize=9)
        ax.set_xlabel("degree l")
        ax.grid(alpha=0.3, which="both")
    axes[0][0].set_ylabel("power per degree, Σ_m c²/4π (mean over RGB)")
    axes[0][0].legend(fontsize=7)
    figure.suptitle(title, fontsize=9)
    figure.tight_layout()
    save_figure(figure, path, dpi=100)
    plt.close(figure)


def check_out(out_dir, inputs, *, overwrite: bool = False) -> OutputFolder:
    """Where :func:`spectrum_report` may write, checked before any work (:class:`frenbrdf.io.outputs.OutputFolder`):
    a new or empty folder or an earlier spectrum folder, not the folder of an input."""
    out = OutputFolder.claim(out_dir, command="spectrum", inputs=tuple(inputs), overwrite=overwrite)
    out.check_names(FILES.values())
    return out


def largest_lmax(variant: str) -> int:
    """The largest band limit a spectrum takes at a variant: :data:`MAX_SPECTRUM_LMAX` for a fit to the measured nodes
    (memory ∝ lmax⁴), :data:`frenbrdf.models.losses.MAX_LMAX` for the SHT of the whole sphere (memory ∝ lmax²)."""
    return MAX_SPECTRUM_LMAX if frequency_variant(variant).fit == "measured" else MAX_LMAX


def spectrum_report(sources, out_dir, *, truth: str | os.PathLike | None = None, variant: str = "tone",
                    lmax: int | None = None, overwrite: bool = False) -> dict:
    """Spectra of material files (and with ``truth``, each one's error spectrum against it) into ``out_dir``.

    Parameters
    ----------
    sources
        Material files: MERL ``.binary``, RGL ``.bsdf``, NBRDF ``.pt`` or Keras ``.h5``.
    out_dir
        The folder of ``spectrum.{png,csv,json}`` (:func:`check_out`).
    truth
        A material file each source is compared with (a reconstruction against its truth).
    variant, lmax
        The L_fre settings the spectra are taken at (:data:`frenbrdf.presets.FREQUENCY_VARIANTS`; lmax
        overrides the variant's band limit, 1 … :func:`largest_lmax`, checked before any work).
    overwrite
        Write into ``out_dir`` even when it holds entries of the user's (they are kept).

    Returns
    -------
    dict
        What ``spectrum.json`` holds.
    """
    sources = [Path(s) for s in sources]
    if not sources:
        raise ValueError("give at least one material file")
    config = frequency_variant(variant)
    if lmax is not None:  # 0 is a band limit asked for (and refused), not "the default"
        limit = largest_lmax(variant)
        if isinstance(lmax, bool) or not isinstance(lmax, numbers.Integral) or not 1 <= lmax <= limit:
            raise ValueError(f"lmax must be a whole number in 1 … {limit} for variant {variant!r}, got {lmax!r} ("
                             + ("its fit to the measured nodes holds about (lmax + 1)⁴ / 4 numbers per slice, 1.6 GB "
                                f"at {MAX_MEASURED_LMAX}; the variants fitting the whole sphere, e.g. 'paper', take up "
                                f"to {MAX_LMAX})" if config.fit == "measured" else f"the default is {config.lmax})"))
        config = frequency_variant(variant, lmax=int(lmax))
    out = check_out(out_dir, [*sources, *([truth] if truth else [])], overwrite=overwrite)
    analyser = SpectrumAnalyser(config)
    named: dict[str, tuple[Path, np.ndarray]] = {}
    for path in ([Path(truth)] if truth else []) + sources:
        name = path.stem if path.stem not in named else f"{path.stem} ({path.parent.name or path})"
        with naming(path):
            coefficients = analyser.coefficients(load_source(path))
        named[f"{name} (truth)" if truth and not named else name] = (path, coefficients)
    powers = {name: analyser.power(c) for name, (_, c) in named.items()}
    truth_name = next(iter(named)) if truth else ""  # no truth: no errors
    errors = ({name: analyser.power(c - named[truth_name][1]) for name, (_, c) in named.items() if name != truth_name}
              if truth else {})
    theta_h = analyser.theta_h_degrees
    rows = [{"material": name, "spectrum": kind, "slice": int(config.slices[s]), "theta_h_deg": round(theta_h[s], 4),
             "channel": "rgb"[c], "degree": int(degree), "power": float(power[s, c, degree])}
            for kind, group in (("material", powers), ("error", errors)) for name, power in group.items()
            for s in range(len(theta_h)) for c in range(3) for degree in range(power.shape[-1])]
    report = {"variant": variant, "frequency": {k: (list(v) if isinstance(v, tuple) else v)
                                                for k, v in vars(config).items()},
              "values": "ln(f + 0.002)" if config.values == "mapped" else config.values,
              "slices": list(config.slices), "theta_h_deg": theta_h, "truth": str(truth) if truth else None,
              "materials": {name: {"path": str(path), "band_shares": band_shares(powers[name]),
                                   "power": powers[name].tolist()} for name, (path, _) in named.items()},
              "errors": {name: {"relative_error_by_band": relative_error_by_band(error, powers[truth_name]),
                                "relative_error_by_slice": [float(error[s].sum() / max(powers[truth_name][s].sum(), 1e-30))
                                                            for s in range(len(theta_h))],
                                "power": error.tolist()} for name, error in errors.items()},
              "files": sorted(FILES.values())}
    with out.staged() as staging:
        save_csv(staging / FILES["csv"], rows)
        save_json(staging / FILES["report"], report)
        plot_spectra(powers, staging / FILES["plot"], errors=errors, theta_h=theta_h,
                     title=f"Per-degree power spectra, L_fre variant '{variant}' ({report['values']}, {config.fit} "
                           f"fit, lmax {config.lmax})" + (f"; dashed: error against {truth_name}" if truth else ""))
    return report


def summary_text(report: dict) -> str:
    """A few lines for the terminal: each material's share of power by degree band, each error by band."""
    lines = []
    for name, entry in report["materials"].items():
        lines.append(f"{name}: power " + ", ".join(f"{band} {share:.0%}" for band, share in entry["band_shares"].items()))
    for name, entry in report["errors"].items():
        lines.append(f"{name} vs truth: error / truth power "
                     + ", ".join(f"{band} {value:.2g}" for band, value in entry["relative_error_by_band"].items()))
    return "\n".join(lines)


class SpectrumSummary:
    """Mean spectra of several materials and of their reconstructions: what ``frenbrdf reconstruct`` and
    ``frenbrdf evaluate`` plot for what they measured. :meth:`add` one truth table and its reconstructions (by
    label: an NBRDF each), then :meth:`write` the plot and take :meth:`summary`."""

    def __init__(self, config: FrequencyLossConfig | None = None, variant: str = "tone"):
        self.variant = variant
        self.analyser = SpectrumAnalyser(config or frequency_variant(variant))
        self.truth: list[np.ndarray] = []
        self.powers: dict[str, list[np.ndarray]] = {}
        self.errors: dict[str, list[np.ndarray]] = {}

    def add(self, table: np.ndarray, reconstructions: dict) -> None:
        """Adds one material: its truth ``table`` and its ``reconstructions`` (label → NBRDF)."""
        truth = self.analyser.coefficients(table)
        self.truth.append(self.analyser.power(truth))
        for label, nbrdf in reconstructions.items():
            coefficients = self.analyser.coefficients(nbrdf)
            self.powers.setdefault(label, []).append(self.analyser.power(coefficients))
            self.errors.setdefault(label, []).append(self.analyser.power(coefficients - truth))

    def summary(self) -> dict:
        """Per reconstruction label: the error's power over the truth's, by degree band and by slice (means)."""
        truth = np.mean(self.truth, axis=0)
        return {"variant": self.variant, "materials": len(self.truth), "theta_h_deg": self.analyser.theta_h_degrees,
                "relative_error_by_band": {label: relative_error_by_band(np.mean(e, axis=0), truth)
                                           for label, e in self.errors.items()},
                "relative_error_by_slice": {label: [float(np.mean(e, axis=0)[s].sum() / max(truth[s].sum(), 1e-30))
                                                    for s in range(len(truth))] for label, e in self.errors.items()}}

    def write(self, path: str | os.PathLike, title: str = "") -> None:
        """Plots the mean spectra of the truth and of each reconstruction, with their errors, to ``path``."""
        label = "truth" if len(self.truth) == 1 else f"truth (mean of {len(self.truth)})"
        powers = {label: np.mean(self.truth, axis=0), **{k: np.mean(v, axis=0) for k, v in self.powers.items()}}
        plot_spectra(powers, path, errors={k: np.mean(v, axis=0) for k, v in self.errors.items()},
                     theta_h=self.analyser.theta_h_degrees,
                     title=title or f"Per-degree power spectra (L_fre variant '{self.variant}'); dashed: error against "
                                    "the truth")
