"""Augmented training batches: mixes, gains and procedural materials are physical, seeded and consistent."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from frenbrdf import presets
from frenbrdf.data import analytic, synth
from frenbrdf.data.folders import (
    ALBEDO_INCIDENT_DEGREES,
    mapped_bank,
    max_directional_albedo,
)
from frenbrdf.io.merl import merl_above_horizon
from frenbrdf.io.sampling import bin_directions
from frenbrdf.models.autoencoder import AutoEncoder
from frenbrdf.models.losses import FrequencyLoss, FrequencyLossConfig, FrequencyTruth
from frenbrdf.models.mapping import LogRelativeMapping, MappingConfig
from frenbrdf.models.nbrdf import bin_geometry
from frenbrdf.training import config_for, loss_terms
from frenbrdf.training.augment import GAIN, MIX, PROCEDURAL, TABLE, BatchDrawer, HueTurn, draw_gains, hue_turn
from frenbrdf.training.config import AugmentConfig
from frenbrdf.training.procedural import NodeTruth, draw_procedural

from .conftest import EVERY_KIND


def _drawer(prepared, context_jitter=0.0, **augment):
    cfg, data = prepared
    cfg = dataclasses.replace(cfg, context_jitter=context_jitter, augment=AugmentConfig(**{**EVERY_KIND, **augment}))
    return BatchDrawer(cfg, data, with_truth=True), data


def _analytic_bank(materials) -> tuple[LogRelativeMapping, object, np.ndarray]:
    above = merl_above_horizon().reshape(-1)
    tables = []
    for material in materials:
        table = analytic.merl_table(material).reshape(3, -1)
        table[:, ~above] = np.nan
        tables.append(table)
    tables = np.stack(tables)
    # Per bin: the harder reference for the exact truth, which interpolates f_ref between bins (per
    # channel, a Lambertian material equal to the median would map to 0 everywhere).
    mapping = LogRelativeMapping.from_tables(tables, MappingConfig(reference="per_bin"))
    return mapping, mapped_bank([m.name for m in materials], tables, mapping), tables


def _albedo(material, nodes=96, degrees=ALBEDO_INCIDENT_DEGREES) -> np.ndarray:
    """The material's largest directional albedo per channel, by a fine analytic quadrature."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    mu, weight = (x + 1) / 2, w / 2
    phi = (np.arange(2 * nodes) + 0.5) * np.pi / nodes
    s = np.sqrt(1 - mu ** 2)
    wo = np.stack([np.outer(s, np.cos(phi)), np.outer(s, np.sin(phi)), np.repeat(mu[:, None], len(phi), 1)], -1)
    albedos = []
    for theta in np.radians(degrees):
        f = analytic.evaluate(material, [np.sin(theta), 0.0, np.cos(theta)], wo)
        albedos.append((f * (weight * mu)[:, None, None]).sum((0, 1)) * np.pi / nodes)
    return np.max(albedos, axis=0)


def test_augmented_batches_are_non_negative_and_mixes_are_convex_in_reflectance(prepared):
    drawer, data = _drawer(prepared)
    generator = torch.Generator().manual_seed(3)
    for _ in range(3):
        batch = drawer.draw(list(range(6)), generator)
        for samples in (batch.context, batch.query):
            assert torch.isfinite(samples.values).all()
        # Un-mapped without the clamp of mapping.inverse: every sample is a reflectance ≥ 0.
    bins, values = drawer.mixed(0, 2000, generator)
    reference = drawer.reference[bins]
    unclamped = (reference + data.mapping.epsilon) * torch.exp(values) - data.mapping.epsilon
    assert unclamped.min() > -1e-6
    a, b = drawer.reflectance(0, bins).double(), unclamped.double()
    others = [drawer.reflectance(m, bins).double() for m in range(1, data.n_train)]
    # The mix is t·a + (1 − t)·b for one t and one partner b: solve for t where a and b differ.
    fits = []
    for other in others:
        spread = a - other
        usable = spread.abs() > 0.05 * a.abs().max()
        t = ((b - other)[usable] / spread[usable])
        fits.append(float(t.std()) if usable.sum() > 10 else np.inf)
    assert min(fits) < 1e-3, fits


def test_procedural_materials_are_reciprocal_and_differ_between_steps(prepared):
    drawer, data = _drawer(prepared, procedural=1.0, mix=0.0, gain=0.0)
    generator = torch.Generator().manual_seed(0)
    first, second = drawer.draw([0, 1], generator), drawer.draw([0, 1], generator)
    assert not torch.allclose(first.query.values, second.query.values)
    assert not torch.allclose(first.truth, second.truth)
    assert first.truth_mask.all()  # procedural materials have their exact truth
    material = draw_procedural(torch.Generator().manual_seed(5))
    bins = drawer.above_horizon[torch.randint(len(drawer.above_horizon), (500,))]
    wi, wo = bin_directions(bins)
    np.testing.assert_allclose(analytic.evaluate(material, wi, wo), analytic.evaluate(material, wo, wi), rtol=1e-10)
    # The samples are the material at the bins' own directions, mapped with the run's mapping.
    values = data.mapping.forward(torch.from_numpy(analytic.evaluate(material, wi, wo)).float(), drawer.reference[bins])
    from frenbrdf.training.procedural import values_at_bins
    assert torch.allclose(values_at_bins(material, bins, data.mapping, drawer.reference[bins]), values)


def test_the_same_seed_draws_the_same_batches(prepared):
    drawer, _ = _drawer(prepared, context_jitter=0.5)
    batches = [drawer.draw(list(range(6)), torch.Generator().manual_seed(seed)) for seed in (1, 1, 2)]
    for name in ("coords", "values", "cos_in"):
        assert torch.equal(getattr(batches[0].context, name), getattr(batches[1].context, name))
        assert torch.equal(getattr(batches[0].query, name), getattr(batches[1].query, name))
    assert torch.equal(batches[0].truth, batches[1].truth)
    assert not torch.equal(batches[0].query.values, batches[2].query.values)


def test_roles_follow_the_fractions_and_only_mixes_and_gains_leave_l_fre(prepared):
    drawer, _ = _drawer(prepared, mix=0.2, gain=0.3, procedural=0.1)
    roles = drawer.roles(20000, torch.Generator().manual_seed(0))
    shares = [np.mean(roles == role) for role in (PROCEDURAL, MIX, GAIN, TABLE)]
    np.testing.assert_allclose(shares, [0.1, 0.2, 0.3, 0.4], atol=0.015)
    generator = torch.Generator().manual_seed(0)
    for _ in range(3):
        batch = drawer.draw(list(range(6)), generator)
        assert batch.truth_mask.tolist() == [role in (TABLE, PROCEDURAL) for role in batch.roles]


def test_l_fre_is_computed_over_the_materials_with_a_truth_only(prepared):
    drawer, data = _drawer(prepared)
    cfg = drawer.cfg
    batch = drawer.draw([0, 1, 2], torch.Generator().manual_seed(0))
    network, frequency = AutoEncoder(cfg.model), FrequencyLoss(cfg.loss.frequency)
    mask = torch.tensor([True, False, True])
    masked = loss_terms(network, frequency, cfg.loss, batch.context, batch.query, batch.truth, mask)
    _, params = network(batch.context.encoder_input())
    expected = frequency([p[mask] for p in params], batch.truth[mask])
    assert masked.logged["fre"] == pytest.approx(float(expected.detach()), rel=1e-5)
    assert "fre" not in loss_terms(network, frequency, cfg.loss, batch.context, batch.query, batch.truth,
                                   torch.zeros(3, dtype=torch.bool)).logged


def test_gains_keep_the_albedo_at_most_one():
    bright = analytic.AnalyticMaterial("bright", diffuse=(0.9, 0.6, 0.2), specular=1.0, roughness=0.2)
    gold = analytic.AnalyticMaterial("gold", metal_n=analytic.METALS["gold"][0], metal_k=analytic.METALS["gold"][1],
                                     roughness=0.2)
    matte = analytic.AnalyticMaterial("matte", diffuse=(0.8, 0.4, 0.1))
    mapping, bank, _ = _analytic_bank([bright, gold, matte])
    estimated = max_directional_albedo(bank, mapping)
    # A Lambertian material's albedo is its ρ at every angle.
    np.testing.assert_allclose(estimated[2], matte.diffuse, rtol=0.01)
    generator = torch.Generator().manual_seed(0)
    for i, material in enumerate((bright, gold)):
        np.testing.assert_allclose(estimated[i], _albedo(material), rtol=0.05)
        true = _albedo(material, degrees=np.linspace(0, 88, 23))  # at any incidence
        for _ in range(50):
            gains = draw_gains(estimated[i], (2.0, 4.0), generator).numpy()
            # The estimate is good to a few per cent (nearest bins, incidence up to 85°).
            assert (gains * true).max() <= 1.03
            assert (gains * estimated[i].numpy()).max() <= 1 + 1e-6
    # Gains that leave the albedo below 1 are kept as drawn, within their range.
    small = draw_gains(torch.tensor([0.2, 0.2, 0.2]), (0.5, 2.0), generator)
    assert ((small >= 0.5) & (small <= 2.0)).all()


def test_a_hue_turn_keeps_greys_and_takes_red_to_green_in_a_third_of_a_turn():
    np.testing.assert_allclose(hue_turn(0.0), torch.eye(3), atol=1e-7)
    third = hue_turn(2 * np.pi / 3)
    np.testing.assert_allclose(third @ torch.tensor([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(hue_turn(1.234) @ torch.full((3,), 0.4), torch.full((3,), 0.4), atol=1e-6)
    np.testing.assert_allclose(hue_turn(0.7) @ hue_turn(0.7).T, torch.eye(3), atol=1e-6)  # a rotation


def test_turned_tables_change_hue_stay_physical_and_earlier_batches_are_unchanged(prepared):
    _, data = prepared
    # hue_turn 0 draws nothing more: the batches of runs from before it existed are drawn bit for bit.
    plain = _drawer(prepared, gain=1.0, mix=0.0, procedural=0.0)[0]
    turned_off = _drawer(prepared, gain=1.0, mix=0.0, procedural=0.0, hue_turn=0.0)[0]
    for first, second in zip(plain.gained(0, 500, torch.Generator().manual_seed(4)),
                             turned_off.gained(0, 500, torch.Generator().manual_seed(4)), strict=True):
        assert torch.equal(first, second)
    drawer, _ = _drawer(prepared, gain=1.0, mix=0.0, procedural=0.0, hue_turn=1.0, gain_range=(1.0, 1.0))
    # The most coloured training material (toy tables: a coloured Lambertian base under a white lobe).
    chroma = [(lambda c: float((c.max() - c.min()) / c.max()))(drawer.reflectance(m, data.bank.valid_bins(m)).mean(0))
              for m in range(data.n_train)]
    material = int(np.argmax(chroma))
    generator, hues = torch.Generator().manual_seed(5), []
    for _ in range(12):
        bins, values = drawer.gained(material, 4000, generator)
        colours = data.mapping.inverse(values, drawer.reference[bins]).double()
        own = drawer.reflectance(material, bins).double()
        assert torch.isfinite(values).all() and colours.min() >= 0
        # At the same bins a turn keeps the grey level (the sum of the channels), up to the clip at 0 and the
        # albedo cap.
        assert 0.3 < float(colours.sum() / own.sum()) < 1.5
        hues.append(colours.sum(0) / colours.sum())
    assert torch.stack(hues).std(0).max() > 0.02, hues  # the drawn angles give different hues


def test_a_turn_that_shifts_with_angle_is_the_plain_turn_at_each_direction_and_its_bound_holds():
    geometry = bin_geometry()
    bins = torch.randperm(len(geometry.half_diff), generator=torch.Generator().manual_seed(0))[:300]
    coords, colours = geometry.half_diff[bins], torch.rand(300, 3, generator=torch.Generator().manual_seed(1))
    turn = HueTurn(0.4, shift_h=2.5, shift_d=-1.2)
    turned = turn.apply(colours, coords)
    plain = torch.stack([colours[i] @ hue_turn(float(angle)).T for i, angle in enumerate(turn.angles(coords))])
    np.testing.assert_allclose(turned, plain, atol=1e-5)
    # The angle moves with θ_h and θ_d as documented: the highlight (cos θ_h = 1) at normal incidence keeps `angle`.
    at_peak = torch.tensor([[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]])
    assert float(turn.angles(at_peak)) == pytest.approx(0.4)
    assert float((turned.sum(1) - colours.sum(1)).abs().max()) < 1e-4  # a turn keeps the grey level
    # largest() @ c bounds every turned channel of a non-negative colour, wherever the angle lands.
    assert (turned <= colours @ turn.largest().T + 1e-5).all()
    assert torch.equal(HueTurn(0.4).apply(colours, coords), colours @ hue_turn(0.4).T)


def test_hue_shift_draws_colour_that_changes_with_angle_and_leaves_earlier_batches_unchanged(prepared):
    _, data = prepared
    settings = dict(gain=1.0, mix=0.0, procedural=0.0, hue_turn=1.0, gain_range=(1.0, 1.0))
    still, shifting = (_drawer(prepared, hue_shift=shift, **settings)[0] for shift in (0.0, 0.5))
    plain = _drawer(prepared, **settings)[0]
    for first, second in zip(plain.gained(0, 500, torch.Generator().manual_seed(4)),
                             still.gained(0, 500, torch.Generator().manual_seed(4)), strict=True):
        assert torch.equal(first, second)
    turns = [shifting.draw_turn(torch.Generator().manual_seed(seed)) for seed in range(20)]
    assert all(abs(t.shift_h) <= np.pi and abs(t.shift_d) <= np.pi for t in turns)
    assert max(abs(t.shift_h) for t in turns) > 1.0 and max(abs(t.shift_d) for t in turns) > 1.0
    chroma = [(lambda c: float((c.max() - c.min()) / c.max()))(plain.reflectance(m, data.bank.valid_bins(m)).mean(0))
              for m in range(data.n_train)]
    material = int(np.argmax(chroma))
    turn = shifting.draw_turn(torch.Generator().manual_seed(6))  # the turn gained() draws first from the same seed
    bins, values = shifting.gained(material, 4000, torch.Generator().manual_seed(6))
    colours = data.mapping.inverse(values, shifting.reference[bins]).double()
    assert torch.isfinite(values).all() and colours.min() >= 0
    # Each bin's colour is the material's own turned by the angle at that bin (up to the one albedo-cap factor), and
    # not the turn of one angle for every bin.
    own, coords = shifting.reflectance(material, bins).double(), bin_geometry().half_diff[bins]
    angles = turn.angles(coords)
    assert float(angles.max() - angles.min()) > 0.5
    for expected, matches in ((turn.apply(own, coords).clamp_min(0), True),
                              ((own @ hue_turn(turn.angle).double().T).clamp_min(0), False)):
        scaled = expected * colours.sum() / expected.sum()
        error = float((colours - scaled).abs().max() / colours.abs().max())
        assert (error < 1e-3) if matches else (error > 0.05), error


@pytest.mark.parametrize("kind", ["diffuse", "metal"])
def test_exact_node_truth_agrees_with_the_knn_truth_of_the_table(kind):
    material = synth.draw_material(np.random.default_rng(1), kind)
    other = synth.draw_material(np.random.default_rng(2), "plastic")
    mapping, bank, _ = _analytic_bank([material, other])
    config = FrequencyLossConfig()
    knn = FrequencyTruth(config).coefficients(bank.mapped[0].numpy(), bank.valid[0].numpy())
    exact = NodeTruth(config, mapping).coefficients(material).numpy()
    assert np.linalg.norm(exact - knn) / np.linalg.norm(knn) < 0.03


def test_augment_config_refuses_bad_values():
    with pytest.raises(ValueError, match="mix must lie"):
        AugmentConfig(mix=1.5)
    with pytest.raises(ValueError, match="must be ≤ 1"):
        AugmentConfig(mix=0.5, gain=0.5, procedural=0.5)
    with pytest.raises(ValueError, match="gain_range"):
        AugmentConfig(gain_range=(2.0, 1.0))
    with pytest.raises(ValueError, match="hue_turn must lie"):
        AugmentConfig(hue_turn=float("nan"))
    with pytest.raises(ValueError, match="hue_turn 0.5 turns gained tables, but gain is 0"):
        AugmentConfig(gain=0.0, hue_turn=0.5)
    with pytest.raises(ValueError, match="hue_shift must lie"):
        AugmentConfig(hue_turn=0.5, hue_shift=float("nan"))
    with pytest.raises(ValueError, match="hue_shift 0.2 changes hue turns with angle, but hue_turn is 0"):
        AugmentConfig(hue_shift=0.2)
    paper = AugmentConfig(mix=0.0, gain=0.0)
    assert not paper.active and dataclasses.replace(paper, procedural=0.1).active
    # The default is the 'augmented' preset; 'paper' switches every kind off.
    assert AugmentConfig() == AugmentConfig(**presets.AUGMENTATION["augmented"], preset="augmented")
    assert not config_for("nbrdf", augmentation="paper").augment.active
    assert config_for("nbrdf", augmentation="augmented").augment.preset == "augmented"
    with pytest.raises(ValueError, match="augmentation must be one of"):
        config_for("nbrdf", augmentation="lots")
