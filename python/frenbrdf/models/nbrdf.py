"""The NBRDF: a small MLP from (H, D) to mapped RGB reflectance, evaluated in batches.

The network's weights are not module parameters: the hypernetwork produces them, one
set per material, and :func:`nbrdf_forward` evaluates B materials at once with batched
matrix products. :class:`NBRDF` is the user-facing object: decoded materials plus the
mapping back to reflectance.
"""

from __future__ import annotations

import contextlib
import functools
import os
from dataclasses import dataclass

import numpy as np
import torch

from ..io.merl import CHANNEL_SCALES, SHAPE, merl_above_horizon, merl_bin_directions, merl_bin_rusinkiewicz, write_merl
from ..io.nbrdf import MAX_LAYERS, MAX_WIDTH, N_INPUTS, N_OUTPUTS, NBRDFWeights
from ..io.reflectance import MAX_REFLECTANCE
from ..io.samples import UNIT_TOLERANCE
from ..numerics.coords import half_diff_vectors, rusinkiewicz_to_directions, rusinkiewicz_to_half_diff
from .mapping import LogRelativeMapping

# What a file may hold is every reader's limit and the models' too (from frenbrdf.io): the NBRDF's inputs (H, D) and
# outputs (RGB), its widest and most hidden layers, the largest reflectance, how far from 1 a direction's length may be.
#: The input that carries a pair's order in an ordered NBRDF (:attr:`NBRDF.ordered`): H_y, 0 for every pair otherwise
#: (H is rotated onto the xz-plane), so no reciprocal NBRDF depends on its weights.
ORDER_INPUT = 1


@dataclass
class NBRDFConfig:
    """Size of the decoded NBRDF (ReLU hidden layers, linear output in the mapped space)."""

    hidden: tuple[int, ...] = (32, 32)
    """Hidden layer widths: (21, 21) is Sztrajman's NBRDF (675 weights), (60, 60, 60, 60) HyperBRDF's (11,583)."""

    def __post_init__(self):
        self.hidden = tuple(int(h) for h in self.hidden)
        if not self.hidden or min(self.hidden) < 1 or max(self.hidden) > MAX_WIDTH or len(self.hidden) > MAX_LAYERS:
            raise ValueError(f"nbrdf.hidden must be 1 to {MAX_LAYERS} positive layer widths, at most {MAX_WIDTH}, got "
                             f"{self.hidden}")

    def shapes(self) -> list[tuple[int, ...]]:
        """Shapes of the parameter tensors, in order: weight (out, in), bias (out,), …"""
        sizes = [N_INPUTS, *self.hidden, N_OUTPUTS]
        shapes = []
        for fan_in, fan_out in zip(sizes[:-1], sizes[1:], strict=True):
            shapes += [(fan_out, fan_in), (fan_out,)]
        return shapes

    @property
    def n_weights(self) -> int:
        return sum(int(np.prod(shape)) for shape in self.shapes())


@dataclass(frozen=True)
class BinGeometry:
    """What every MERL bin means to an NBRDF (φ_h = 0), shared by all materials."""

    half_diff: torch.Tensor
    """(N_BINS, 6) float32: the NBRDF input (H, D)."""
    cos_in: torch.Tensor
    """(N_BINS,) float32: cos θ_i clamped to [0, 1], the reconstruction-loss weight."""


@functools.cache
def bin_geometry() -> BinGeometry:
    wi, wo = (d.reshape(-1, 3) for d in merl_bin_directions())
    return BinGeometry(torch.from_numpy(nbrdf_coordinates(wi, wo).astype(np.float32)),
                       torch.from_numpy(np.clip(wi[:, 2], 0.0, 1.0).astype(np.float32)))


@functools.cache
def merl_bin_inputs() -> tuple[np.ndarray, np.ndarray]:
    """The MERL bins above the horizon, bool ``(90, 90, 180)``, and their NBRDF inputs ``(n, 6)``.

    The inputs are (H, D) with φ_h = 0 in float64, from the bins' angles
    (:func:`frenbrdf.numerics.coords.rusinkiewicz_to_half_diff`). The same for every material, so
    computed once (about 55 MB) and kept read-only.
    """
    above = merl_above_horizon()
    h, d = rusinkiewicz_to_half_diff(merl_bin_rusinkiewicz()[above])
    inputs = np.concatenate([h, d], axis=-1)
    above.flags.writeable = False
    inputs.flags.writeable = False
    return above, inputs


def nbrdf_merl_table(reflectance) -> np.ndarray:
    """Writes a network as a MERL table: the one NBRDF → MERL table writer.

    Parameters
    ----------
    reflectance
        ``reflectance(inputs) -> (n, 3)``: RGB reflectance at the NBRDF inputs ``(n, 6)``
        of the bins above the horizon (:func:`merl_bin_inputs`, in that order).

    Returns
    -------
    numpy.ndarray
        float64 ``(3, 90, 90, 180)`` in physical units, ready for
        :func:`frenbrdf.io.merl.write_merl`: the reflectance clamped to ≥ 0 on bins above
        the horizon, ``−CHANNEL_SCALES[c]`` (stored value −1, MERL's missing marker) on
        the others.
    """
    above, inputs = merl_bin_inputs()
    values = np.maximum(np.asarray(reflectance(inputs), dtype=np.float64), 0.0)
    table = np.empty(SHAPE)
    for channel, scale in enumerate(CHANNEL_SCALES):
        table[channel][above] = values[:, channel]
        table[channel][~above] = -1.0 * scale  # write_merl stores exactly −1
    return table


#: How near 0 a component of D counts as 0 when folding: on the seam φ_d ∈ {0, π} D_y's sign is rounding (a MERL
#: bin at φ_d = 0 comes out of the trigonometry with D_y = ±1e-17), and there D_x decides, unless D is the pole
#: (θ_d = 0: ω_i = ω_o, the pair is its own reverse).
SEAM = 1e-9


def _order_of_difference(d: np.ndarray) -> np.ndarray:
    x, y = d[..., 0], d[..., 1]
    return np.where((y < -SEAM) | ((np.abs(y) <= SEAM) & (x < -SEAM)), -1.0, 1.0)  # where fold_difference flips D


def fold_difference(d: np.ndarray) -> np.ndarray:
    """D ``(..., 3)`` folded onto the half-space a MERL table covers (φ_d ∈ [0, π), D_y ≥ 0).

    Swapping ω_i and ω_o turns D by π about H's pole, (x, y, z) → (−x, −y, z), and leaves a
    BRDF unchanged (reciprocity); MERL stores only φ_d ∈ [0, π) for that reason, so every
    training sample has D_y ≥ 0. Folding (x, y, z) → (−x, −y, z) where y < 0 (or y = 0 and
    x < 0, φ_d = π; "0" within :data:`SEAM`) asks the network only about inputs it was trained on, and makes every
    decoded BRDF exactly reciprocal. The Dr.Jit kernel (:mod:`frenbrdf.render.mitsuba.kernels`)
    folds the same way.
    """
    return np.where(_order_of_difference(d)[..., None] < 0, d * np.array([-1.0, -1.0, 1.0]), d)


def fold_edge_pairs(count: int, seed: int, ordered: bool = False) -> np.ndarray:
    """``count`` pairs of NBRDF inputs ``(count, 2, 6)`` on the two sides of the fold's edge, which a reciprocal BRDF
    gives one value: (H, (x, 0, z)) and (H, (−x, 0, z)), φ_d = 0 and π at the same (θ_h, θ_d), drawn at random (from
    ``seed``) where both directions lie above the horizon.

    :func:`fold_difference` sends a pair just before φ_d = 0 (at −ε) to just below π, so a network may put a step
    between the two sides, a line through every highlight of a render (research/results/seam). ``ordered``: inputs
    of an ordered NBRDF, in which the reverse of a pair is the other order: (x, 0, z) in one order and (−x, 0, z) in
    the other, for each of the two edges, half the pairs each (the pairs a BRDF continuous in φ_d gives one value).
    ``count`` 0: none."""
    if count < 0:
        raise ValueError(f"count must be ≥ 0, got {count}")
    rng, kept, total = np.random.default_rng(seed), [np.zeros((0, N_INPUTS))], 0
    while total < count:
        theta = rng.uniform(0.0, np.pi / 2, size=(2 * count, 2))
        angles = np.stack([theta[:, 0], np.zeros(len(theta)), theta[:, 1], np.zeros(len(theta))], axis=-1)
        wi, wo = rusinkiewicz_to_directions(angles)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        kept.append(nbrdf_coordinates(wi[above], wo[above]))
        total += int(above.sum())
    side = np.concatenate(kept)[:count]
    side[:, 4] = 0.0  # D_y: the edge itself
    other = side * np.array([1, 1, 1, -1, 1, 1])
    if ordered:  # the first half on φ_d = 0's edge, the second on π's: each side in one order, its mirror in the other
        first_edge = (np.arange(count) < count // 2)[:, None]
        side, other = np.where(first_edge, side, other), np.where(first_edge, other, side)
        side[:, ORDER_INPUT], other[:, ORDER_INPUT] = 1.0, -1.0
    return np.stack([side, other], axis=1)


def nbrdf_coordinates(wi, wo, ordered: bool = False) -> np.ndarray:
    """The NBRDF input of direction pairs, each ``(..., 3)`` → ``(..., 6)``: (H, D) with φ_h = 0,
    D folded by reciprocity (:func:`fold_difference`).

    An isotropic BRDF does not depend on φ_h, and the networks only ever see H in the
    xz-plane (as at the MERL bins), so H is rotated about the normal onto it:
    H = (sin θ_h, 0, cos θ_h). D is already expressed in H's frame. ``ordered``: the input
    :data:`ORDER_INPUT` carries the pair's order instead (:func:`pair_order`), for an ordered NBRDF.
    """
    h, d = half_diff_vectors(wi, wo)
    h_isotropic = np.stack([np.hypot(h[..., 0], h[..., 1]), np.zeros(h.shape[:-1]), h[..., 2]], axis=-1)
    coords = np.concatenate([h_isotropic, fold_difference(d)], axis=-1)
    if ordered:
        coords[..., ORDER_INPUT] = _order_of_difference(d)
    return coords


def pair_order(wi, wo) -> np.ndarray:
    """+1 where the pair ``(ω_i, ω_o)`` is in the order a MERL table keeps (D_y ≥ 0, φ_d ∈ [0, π)), −1 where it
    is the reverse of such a pair; ``(...)`` for directions ``(..., 3)``."""
    return _order_of_difference(half_diff_vectors(wi, wo)[1])


def mapped_samples(mapping: LogRelativeMapping, values, directions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One material's samples checked and prepared for a model: what the encoder reads and the loss compares.

    Parameters
    ----------
    mapping
        The model's mapping of reflectance to the network's output space.
    values
        Reflectance ``(N, 3)`` (physical units, ≥ 0; leave missing samples out).
    directions
        ``(wi, wo)``, unit vectors ``(N, 3)`` each, above the surface.

    Returns
    -------
    tuple
        Mapped values ``(N, 3)``, NBRDF inputs ``(N, 6)`` (:func:`nbrdf_coordinates`) and
        cos θ_i clamped to [0, 1] ``(N,)``, all float64.
    """
    values = np.asarray(values, dtype=np.float64)
    wi, wo = (np.asarray(d, dtype=np.float64) for d in directions)
    if values.ndim != 2 or values.shape[1] != 3 or len(values) == 0:
        raise ValueError(f"values must have shape (N, 3) with N ≥ 1, got {values.shape}")
    if wi.shape != values.shape or wo.shape != values.shape:
        raise ValueError(f"wi and wo must have the shape of values {values.shape}, got {wi.shape} and {wo.shape}")
    if not np.all(np.isfinite(values)) or values.min() < 0:
        raise ValueError("values must be finite and ≥ 0 (leave missing samples out)")
    if values.max() > MAX_REFLECTANCE:
        raise ValueError(f"values must be ≤ {MAX_REFLECTANCE:g} (1/sr; MERL's highest spikes are about 1e5), got "
                         f"{values.max():g}")
    for name, d in (("wi", wi), ("wo", wo)):  # what frenbrdf.io.samples checks of a file, for arrays
        length = np.linalg.norm(d, axis=-1)
        if not np.all(np.abs(length - 1) <= UNIT_TOLERANCE):
            first = int(np.flatnonzero(~(np.abs(length - 1) <= UNIT_TOLERANCE))[0])
            raise ValueError(f"{name} must hold unit vectors (length within {UNIT_TOLERANCE:g} of 1); row {first} "
                             f"has length {length[first]:.6g}")
        if not np.all(d[:, 2] > 0):
            first = int(np.flatnonzero(~(d[:, 2] > 0))[0])
            raise ValueError(f"{name} must lie above the surface (z > 0, the normal); row {first} has z = "
                             f"{d[first, 2]:.6g} (a sample there has no weight: losses of 0 would read as a perfect fit)")
    mapped = mapping.forward(values, mapping.reference_at(wi, wo))
    return mapped, nbrdf_coordinates(wi, wo), np.clip(wi[:, 2], 0.0, 1.0)


def check_params(params: list[torch.Tensor], where: str = "NBRDF") -> None:
    """Checks NBRDF parameters ``[(B, out, in), (B, out), …]`` (any source: a decoder, a file): a chain of layers
    from the 6 inputs to the 3 outputs, at most :data:`~frenbrdf.io.nbrdf.MAX_LAYERS` hidden layers of at most
    :data:`~frenbrdf.io.nbrdf.MAX_WIDTH`, finite floating-point values. A ValueError names what is wrong."""
    if not isinstance(params, (list, tuple)) or len(params) < 2 or len(params) % 2:
        raise ValueError(f"{where}: the parameters must be (weight, bias) pairs, got {_describe(params)}")
    if not all(isinstance(p, torch.Tensor) and p.is_floating_point() for p in params):
        raise ValueError(f"{where}: the parameters must be floating-point tensors, got {_describe(params)}")
    shapes = [tuple(p.shape) for p in params]
    n_layers, fan_in = len(params) // 2, N_INPUTS
    if n_layers > MAX_LAYERS + 1:
        raise ValueError(f"{where}: {n_layers - 1} hidden layers; an NBRDF has at most {MAX_LAYERS}")
    batch = shapes[0][0] if shapes[0] else None
    for layer in range(n_layers):
        weight, bias = shapes[2 * layer], shapes[2 * layer + 1]
        last = layer == n_layers - 1
        if len(weight) != 3 or len(bias) != 2 or weight[0] != batch or bias[0] != batch or weight[2] != fan_in \
                or bias[1] != weight[1] or (last and weight[1] != N_OUTPUTS):
            raise ValueError(f"{where}: layer {layer + 1} has weight {weight[1:]} and bias {bias[1:]}; an NBRDF maps "
                             f"{N_INPUTS} inputs through (out, in) weights and (out,) biases to {N_OUTPUTS} outputs "
                             f"(all shapes: {[s[1:] for s in shapes]})")
        if not last and not 1 <= weight[1] <= MAX_WIDTH:
            raise ValueError(f"{where}: hidden layer {layer + 1} is {weight[1]} wide; an NBRDF's are at most "
                             f"{MAX_WIDTH}")
        fan_in = weight[1]
    bad = [index for index, p in enumerate(params) if not torch.all(torch.isfinite(p))]
    if bad:
        raise ValueError(f"{where}: parameter tensor {bad[0]} holds NaN or inf")


def _describe(params) -> str:
    if isinstance(params, (list, tuple)):
        return "[" + ", ".join(f"{tuple(p.shape)} {p.dtype}" if isinstance(p, torch.Tensor) else type(p).__name__
                               for p in params[:8]) + ("…" * (len(params) > 8)) + "]"
    return type(params).__name__


@contextlib.contextmanager
def one_torch_thread():
    """Torch on one thread inside the block (restored after): on the thin products of one small NBRDF or decoder,
    its threads cost far more than they save, and between operations they spin on the cores that the native core's
    threads need (research/performance.md)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def nbrdf_forward(params: list[torch.Tensor], coords: torch.Tensor) -> torch.Tensor:
    """Evaluates B NBRDFs: ``params`` as from :meth:`NBRDFConfig.shapes` with a leading B,
    ``coords`` ``(B, N, 6)`` → mapped RGB ``(B, N, 3)``."""
    x = coords
    n_layers = len(params) // 2
    for layer in range(n_layers):
        weight, bias = params[2 * layer], params[2 * layer + 1]
        x = torch.baddbmm(bias.unsqueeze(1), x, weight.transpose(1, 2))
        if layer < n_layers - 1:
            x = torch.relu(x)
    return x


def widen_params(params: list[torch.Tensor], width: int, generator: torch.Generator) -> list[torch.Tensor]:
    """The same NBRDFs with every hidden layer at least ``width`` wide (wider ones kept), their output unchanged.

    ``params`` as for :func:`nbrdf_forward`. A new unit's incoming weights are drawn at the scale of its layer's
    (from ``generator``), its bias is 0, and every weight *from* a new unit is 0: the old units and the output see
    nothing new until training moves those weights, and the gradient reaches all of them at once.
    """
    n_layers = len(params) // 2
    widened: list[torch.Tensor] = []
    for layer in range(n_layers):
        weight, bias = params[2 * layer], params[2 * layer + 1]
        batch, rows, columns = weight.shape
        new_rows = max(rows, width) if layer < n_layers - 1 else rows
        new_columns = widened[-1].shape[1] if layer > 0 else columns  # the previous layer's new width
        grown = torch.zeros(batch, new_rows, new_columns, dtype=weight.dtype)
        grown[:, :rows, :columns] = weight
        scale = weight.std() if weight.numel() > 1 else weight.abs().max()  # a single weight has no spread: its size
        grown[:, rows:, :] = torch.randn(batch, new_rows - rows, new_columns, generator=generator,
                                         dtype=weight.dtype) * scale
        widened += [grown, torch.cat([bias, bias.new_zeros(batch, new_rows - rows)], dim=1)]
    return widened


class NBRDF:
    """Decoded materials: evaluate them at direction pairs or write them as MERL tables.

    Parameters
    ----------
    params
        Parameter tensors with a leading material axis B (see :func:`nbrdf_forward`).
    mapping
        The mapping from network outputs to reflectance.
    ordered
        Whether the network tells the two orders of a pair apart (input :data:`ORDER_INPUT` carries
        :func:`pair_order`): a measurement need not be reciprocal, and ``reconstruct``'s weight stage fits one
        whose samples hold both orders this way (:class:`frenbrdf.models.reconstruct.RefineConfig`,
        ``keep_order``). False (every decoded and fitted NBRDF): reciprocal, exactly.

    Examples
    --------
    >>> nbrdf = model.decode(z)                                        # doctest: +SKIP
    >>> rgb = nbrdf(wi, wo)          # (..., 3) reflectance, ≥ 0      # doctest: +SKIP
    >>> nbrdf.to_merl("decoded.binary")                                # doctest: +SKIP
    """

    def __init__(self, params: list[torch.Tensor], mapping: LogRelativeMapping, ordered: bool = False):
        check_params(params)
        self.params = [p.detach().cpu().to(torch.float32) for p in params]
        self.mapping = mapping
        #: Whether the network tells the two orders of a pair apart (the parameter ``ordered``).
        self.ordered = bool(ordered)

    @classmethod
    def from_weights(cls, weights: NBRDFWeights) -> NBRDF:
        """The NBRDF of a file (:func:`frenbrdf.io.read_material` of a ``.pt`` or ``.h5``), checked whole
        (:func:`check_params`: layer shapes and widths, finite weights; the mapping's f_ref and ε) before anything is
        evaluated. A ValueError names the file."""
        params = [p[None] if isinstance(p, torch.Tensor) else p for p in weights.params]
        try:
            return cls(params, LogRelativeMapping(weights.reference, weights.epsilon, weights.offset), weights.ordered)
        except ValueError as error:
            if not weights.source:
                raise
            raise ValueError(f"{weights.source}: not a valid {weights.what}: {error}") from None

    def weights(self) -> NBRDFWeights:
        """This one material as a file holds it (:func:`frenbrdf.io.write_material` writes it as a ``.pt``)."""
        self._only()
        return NBRDFWeights([p[0] for p in self.params], self.mapping.reference, self.mapping.epsilon,
                            self.mapping.offset, self.ordered)

    def __len__(self) -> int:
        return self.params[0].shape[0]

    def _only(self) -> None:
        if len(self) != 1:
            raise ValueError(f"this NBRDF holds {len(self)} materials; index one first, e.g. nbrdf[0]")

    def __getitem__(self, index: int) -> NBRDF:
        return NBRDF([p[[index]] for p in self.params], self.mapping, self.ordered)

    def in_table_order(self) -> NBRDF:
        """The reciprocal NBRDF that equals this one on every pair in the order a MERL table keeps (itself when it is
        not ordered): the order input's weights, times +1, moved into the first layer's bias."""
        if not self.ordered:
            return self
        weight, bias = self.params[0].clone(), self.params[1].clone()
        bias += weight[:, :, ORDER_INPUT]
        weight[:, :, ORDER_INPUT] = 0
        return NBRDF([weight, bias, *self.params[2:]], self.mapping)

    @torch.inference_mode()
    def mapped(self, coords) -> np.ndarray:
        """Network output (mapped values) at (H, D) ``(..., 6)`` → ``(..., 3)``."""
        self._only()
        coords = torch.as_tensor(np.asarray(coords, dtype=np.float32))
        flat = coords.reshape(1, -1, N_INPUTS)
        # Chunks small enough that the hidden activations stay in cache (5× faster than one big batch).
        out = torch.cat([nbrdf_forward(self.params, chunk) for chunk in flat.split(1 << 14, dim=1)], dim=1)
        return out.reshape(*coords.shape[:-1], N_OUTPUTS).numpy().astype(np.float64)

    def __call__(self, wi, wo) -> np.ndarray:
        """Reflectance at direction pairs, each ``(..., 3)`` → RGB ``(..., 3)``; 0 below the horizon.

        Raises ValueError where the reflectance is not finite (an NBRDF never returns inf or NaN)."""
        self._only()
        wi, wo = np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64)
        above = (wi[..., 2] > 0) & (wo[..., 2] > 0)
        rgb = self._reflectance(nbrdf_coordinates(wi, wo, self.ordered), self.mapping.reference_at(wi, wo),
                                above[..., None])
        return np.where(above[..., None], rgb, 0.0)

    def _reflectance(self, coords, reference, where=True) -> np.ndarray:
        """The reflectance at NBRDF inputs, checked to be finite (where ``where``)."""
        with np.errstate(over="ignore", invalid="ignore"):
            rgb = self.mapping.inverse(self.mapped(coords), reference)
        bad = ~np.isfinite(rgb) & where
        if bad.any():
            raise ValueError(f"this NBRDF's reflectance is not finite at {int(bad.any(axis=-1).sum())} of "
                             f"{int(np.size(bad) // 3)} direction pairs: its output overflows (decoded from an extreme "
                             "latent, or refined with too large a learning rate or on extreme values)")
        return rgb

    def merl_table(self) -> np.ndarray:
        """The material at every MERL bin, ``(3, 90, 90, 180)``, missing bins marked as MERL does (an ordered NBRDF:
        each pair in the table's order, the one order a table keeps)."""
        self._only()
        if self.ordered:
            return self.in_table_order().merl_table()
        above, _ = merl_bin_inputs()
        reference = self.mapping.reference_bins()[:, above.reshape(-1)].T
        return nbrdf_merl_table(lambda inputs: self._reflectance(inputs, reference))

    def to_merl(self, path: str | os.PathLike) -> None:
        """Writes the material as a MERL file (atomically)."""
        write_merl(path, self.merl_table())


def as_brdf(material):
    """What :func:`frenbrdf.io.read_material` returns, ready to evaluate and render: an NBRDF file's weights as
    their :class:`NBRDF` (:meth:`NBRDF.from_weights`); a MERL table or a measurement as it is."""
    return NBRDF.from_weights(material) if isinstance(material, NBRDFWeights) else material
