"""Issue 47: training on the sampling patterns of real devices, and density-weighted pooling in the encoder."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli, presets
from frenbrdf.configs import from_dict, to_dict
from frenbrdf.io import checkpoints
from frenbrdf.io.merl import N_BINS, merl_lookup_directions
from frenbrdf.io.patterns import PATTERNS, sample_pattern
from frenbrdf.models import encoder as encoders
from frenbrdf.models.autoencoder import Model
from frenbrdf.models.encoder import EncoderConfig, SetEncoder, density_weights, knn_radius
from frenbrdf.training import Run, config_for, load_config, train
from frenbrdf.training.augment import TABLE, BatchDrawer
from frenbrdf.training.config import MAX_PATTERN_COUNT, AugmentConfig, SamplingConfig, TrainConfig
from frenbrdf.training.patterns import PatternSampler, nearest_bins

from .conftest import EVERY_KIND, tiny, unit_vectors

NO_AUGMENT = {"mix": 0.0, "gain": 0.0, "procedural": 0.0, "preset": "paper"}



def _drawer(prepared, sampling: SamplingConfig | None = None, augment=None, with_truth=True, **fields):
    cfg, data = prepared
    cfg = dataclasses.replace(cfg, augment=AugmentConfig(**(augment or NO_AUGMENT)),
                              sampling=sampling or SamplingConfig(), **fields)
    return BatchDrawer(cfg, data, with_truth=with_truth), data


def _same(a, b) -> bool:
    return all(torch.equal(getattr(getattr(a, part), name), getattr(getattr(b, part), name))
               for part in ("context", "query") for name in ("coords", "values", "cos_in"))


# ---------------------------------------------------------------------------------------------------------------
# The config


def test_the_sampling_config_round_trips_and_its_presets_name_every_pattern(tmp_path):
    assert presets.ALL_PATTERNS == tuple(PATTERNS)
    assert config_for("frenbrdf").sampling == SamplingConfig() and SamplingConfig().paper
    cfg = config_for("nbrdf", sampling="instruments")
    assert cfg.sampling.preset == "instruments" and cfg.sampling.counts == (300, 4000)
    assert set(cfg.sampling.patterns) == set(PATTERNS) and not cfg.sampling.paper
    mixed = config_for("frenbrdf", sampling="mixed").sampling  # random bins half the time, the rest the others
    assert mixed.patterns["merl-bins"] == sum(w for name, w in mixed.patterns.items() if name != "merl-bins")
    assert from_dict(TrainConfig, json.loads(json.dumps(to_dict(cfg)))) == cfg
    # A config file's patterns replace the preset's whole: the uniform pattern alone, not merl-bins and it.
    path = tmp_path / "config.json"
    path.write_text(json.dumps({"method": "nbrdf", "sampling": {"patterns": {"uniform": 2}, "counts": [50, 60]}}))
    loaded = load_config(path)
    assert loaded.sampling.patterns == {"uniform": 2.0} and loaded.sampling.counts == (50, 60)
    assert loaded.loss.eta == 0.0  # the method's preset still lies under it
    by_values = config_for("frenbrdf", sampling={"patterns": {"specular": 1.0}, "preset": "custom"})
    assert by_values.sampling.patterns == {"specular": 1.0} and by_values.sampling.counts is None
    # Weights of 0 leave the paper's sampling as it is.
    assert SamplingConfig(patterns={"merl-bins": 2.0, "peaks": 0.0}).paper


@pytest.mark.parametrize(("sampling", "match"), [
    ({"patterns": {"sphere": 1.0}}, "unknown pattern"),
    ({"patterns": {"uniform": -1.0}}, "finite numbers ≥ 0"),
    ({"patterns": {"uniform": float("nan")}}, "finite numbers ≥ 0"),
    ({"patterns": {"uniform": 0.0, "merl-bins": 0.0}}, "at least one pattern weight"),
    ({"patterns": {}}, "at least one"),
    ({"counts": (500, 300)}, "1 ≤ low ≤ high"),
    ({"counts": (0, 300)}, "1 ≤ low ≤ high"),
    ({"counts": (300, MAX_PATTERN_COUNT + 1)}, "1 ≤ low ≤ high"),
    ({"counts": (300.5, 400)}, "two whole numbers"),
])
def test_bad_sampling_configs_are_refused_by_name(sampling, match):
    with pytest.raises(ValueError, match=f"invalid sampling config: .*{match}"):
        SamplingConfig(**sampling)


def test_bad_sampling_values_in_a_file_are_refused_before_any_work(tmp_path):
    path = tmp_path / "config.json"
    for sampling, match in (({"patterns": {"uniform": "1"}}, r"patterns\['uniform'\] must be a number"),
                            ({"patterns": ["uniform"]}, "patterns must be a JSON object"),
                            ({"counts": [300]}, "counts must be a list of 2 values"),
                            ({"pattern": {}}, r"unknown key\(s\) \['pattern'\]")):
        path.write_text(json.dumps({"sampling": sampling}))
        with pytest.raises(ValueError, match=match):
            load_config(path)
    with pytest.raises(ValueError, match="context_jitter .* and sampling.counts"):
        config_for("frenbrdf", context_jitter=0.5, sampling="instruments")
    with pytest.raises(ValueError, match="sampling must be one of"):
        config_for("frenbrdf", sampling="devices")
    # The memory check counts the largest context a step may draw.
    with pytest.raises(ValueError, match="sampling.counts' high"):
        config_for("frenbrdf", batch_materials=64, sampling={"counts": [300, MAX_PATTERN_COUNT]})


def test_the_cli_takes_a_sampling_preset_but_not_beside_a_config_file(tmp_path, capsys):
    config_file = tmp_path / "c.json"
    config_file.write_text("{}")
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["train", "--config", str(config_file), "--sampling", "instruments", "--quiet"])
    assert exit_info.value.code == 2 and "--sampling" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------------------
# The drawer


def test_nearest_bins_are_those_of_the_nearest_lookup():
    index_table = np.broadcast_to(np.arange(N_BINS, dtype=np.float64).reshape(90, 90, 180), (3, 90, 90, 180))
    rng = np.random.default_rng(3)
    for name in ("uniform", "specular", "gonioreflectometer", "in-plane"):
        wi, wo = sample_pattern(name, 3000, rng)
        found = merl_lookup_directions(np.ascontiguousarray(index_table), wi, wo, method="nearest")[:, 0]
        np.testing.assert_array_equal(nearest_bins(wi, wo), found.astype(np.int64))


def test_the_paper_sampling_draws_exactly_what_the_drawer_drew_before(prepared):
    """With the default sampling a step's samples are the two bank draws of every earlier run, from the same
    generator states (augmented runs too: test_augment's batches are unchanged)."""
    drawer, data = _drawer(prepared)
    assert drawer.patterns is None
    ours, theirs = torch.Generator().manual_seed(11), torch.Generator().manual_seed(11)
    for _ in range(3):
        batch = drawer.draw([0, 2, 4], ours)
        context = data.bank.sample([0, 2, 4], drawer.cfg.context_samples, theirs)
        query = data.bank.sample([0, 2, 4], drawer.cfg.query_samples, theirs)
        assert _same(batch, type(batch)(context, query))
    assert torch.equal(ours.get_state(), theirs.get_state())
    # Patterns of weight 0 change nothing, augmentation and jitter included.
    silent = SamplingConfig(patterns={"merl-bins": 3.0, "peaks": 0.0}, preset="custom")
    for fields in ({}, {"context_jitter": 0.5}):
        plain, _ = _drawer(prepared, augment=EVERY_KIND, **fields)
        quiet, _ = _drawer(prepared, silent, augment=EVERY_KIND, **fields)
        a, b = plain.draw(list(range(6)), torch.Generator().manual_seed(4)), \
            quiet.draw(list(range(6)), torch.Generator().manual_seed(4))
        assert _same(a, b) and torch.equal(a.truth, b.truth) and np.array_equal(a.roles, b.roles)


def _recording(drawer, monkeypatch):
    """Records the context bins of every material the drawer draws: (material rows, bins) of the tables, and the
    (valid mask, bins) of the augmented ones."""
    tables, augmented = [], []
    bank = drawer.data.bank
    at_bins, role_bins = bank.at_bins, drawer.role_bins

    def record_tables(materials, bins):
        tables.append((list(materials), bins))
        return at_bins(materials, bins)

    def record_roles(valid_bins, valid, n, generator, pattern):
        bins = role_bins(valid_bins, valid, n, generator, pattern)
        augmented.append((valid(), bins[:n - drawer.cfg.query_samples]))
        return bins

    monkeypatch.setattr(bank, "at_bins", record_tables)
    monkeypatch.setattr(drawer, "role_bins", record_roles)
    return tables, augmented


def test_a_mixture_draws_counts_in_range_and_valid_bins_of_every_pattern(prepared, monkeypatch):
    sampling = SamplingConfig(**presets.sampling_overrides("instruments"))
    # L_fre's truth of procedural materials is what takes time here; their bins are what is checked.
    drawer, data = _drawer(prepared, sampling, augment={**EVERY_KIND, "procedural": 0.1}, with_truth=False)
    tables, augmented = _recording(drawer, monkeypatch)
    generator = torch.Generator().manual_seed(0)
    counts, seen = [], set()
    for _ in range(20):
        patterns_before = generator.get_state()
        batch = drawer.draw(list(range(6)), generator)
        n = batch.context.coords.shape[1]
        counts.append(n)
        assert 300 <= n <= 4000 and batch.query.coords.shape[1] == drawer.cfg.query_samples
        replay = torch.Generator()
        replay.set_state(patterns_before)
        drawer.context_count(replay)
        seen.update(drawer.patterns.choose(6, replay))
        for name in ("coords", "values", "cos_in"):
            assert torch.isfinite(getattr(batch.context, name)).all()
    assert seen == set(PATTERNS)
    assert min(counts) < 1000 < max(counts)  # log-uniform: both ends of the range are drawn
    for materials, bins in tables:
        assert bins.shape[0] == len(materials)
        assert all(data.bank.valid[m, row].all() for m, row in zip(materials, bins, strict=True))
    assert augmented and all(valid[bins].all() for valid, bins in augmented)


def test_a_pattern_shapes_the_context_and_leaves_the_query_to_random_bins(prepared):
    drawer, _ = _drawer(prepared, SamplingConfig(patterns={"specular": 1.0}, preset="custom"), augment=EVERY_KIND)
    batch = drawer.draw(list(range(6)), torch.Generator().manual_seed(2))
    assert (batch.roles != TABLE).any()  # augmented materials are read through the pattern too
    theta_h = torch.rad2deg(torch.acos(batch.context.coords[..., 2].clamp(max=1)))  # H_z = cos θ_h
    assert theta_h.max() < 21  # specular: θ_h within 4 × 5° (and a bin)
    assert torch.rad2deg(torch.acos(batch.query.coords[..., 2].clamp(max=1))).max() > 60


def test_pattern_batches_are_seeded_and_each_setup_is_one_device(prepared):
    sampling = SamplingConfig(**presets.sampling_overrides("instruments"))
    drawer, _ = _drawer(prepared, sampling, augment=EVERY_KIND)
    again, _ = _drawer(prepared, sampling, augment=EVERY_KIND)
    first, second = (d.draw(list(range(6)), torch.Generator().manual_seed(8)) for d in (drawer, again))
    assert _same(first, second) and torch.equal(first.truth, second.truth)
    other = drawer.draw(list(range(6)), torch.Generator().manual_seed(9))
    assert first.context.coords.shape != other.context.coords.shape or not _same(first, other)
    # A gonioreflectometer setup has 5 incidence angles: its pairs lie on few curves, not all over the domain.
    pool = drawer.patterns.pools["gonioreflectometer"]
    assert pool.bins.shape == (64, 4000)
    assert len(np.unique(pool.bins[0].numpy())) < 0.7 * 4000


def test_a_pattern_no_bin_of_which_a_material_holds_is_refused_by_name():
    sampler = PatternSampler(SamplingConfig(patterns={"specular": 1.0}), 100, seed=0)
    nothing = torch.zeros(N_BINS, dtype=torch.bool)
    with pytest.raises(ValueError, match="'specular'"):
        sampler.bins("specular", torch.arange(5), nothing, 10, torch.Generator())
    few = torch.zeros(N_BINS, dtype=torch.bool)
    few[sampler.pools["specular"].bins[:, :3].reshape(-1)] = True  # 3 bins of each setup: drawn with replacement
    drawn = sampler.bins("specular", torch.nonzero(few).squeeze(1), few, 50, torch.Generator().manual_seed(0))
    assert len(drawn) == 50 and few[drawn].all()


# ---------------------------------------------------------------------------------------------------------------
# Density pooling


def _half_diff(theta_h: np.ndarray, d: np.ndarray) -> np.ndarray:
    return np.concatenate([np.stack([np.sin(theta_h), np.zeros_like(theta_h), np.cos(theta_h)], -1), d], axis=-1)


def _even(rng, n: int) -> np.ndarray:
    """Coordinates (H, D) spread evenly over their domain: θ_h uniform, D uniform over the sphere."""
    return _half_diff(rng.uniform(0, np.pi / 2, n), unit_vectors(rng, n))


def _crowded(rng, n: int) -> np.ndarray:
    """90 % of the samples in one small corner (θ_h < 0.15, D within about 0.15 of the pole), the rest even."""
    m = int(0.9 * n)
    d = rng.normal(size=(m, 3)) * 0.15 + [0.0, 0.0, 1.0]
    corner = _half_diff(rng.uniform(0, 0.15, m), d / np.linalg.norm(d, axis=1, keepdims=True))
    return np.concatenate([corner, _even(rng, n - m)])


class Field(torch.nn.Module):
    """A smooth code field over the coordinates: what a per-sample MLP computes, without its weights."""

    def forward(self, samples):
        x = samples[..., 3:]
        return torch.stack([torch.sin(2 * x[..., 0]) + x[..., 5], torch.cos(3 * x[..., 3]) * x[..., 2],
                            x[..., 4] ** 2 - x[..., 0]], dim=-1)


def test_density_pooling_hardly_moves_when_the_sampling_crowds_one_corner():
    gaps = {"mean": [], "density": []}
    for pooling in gaps:
        encoder = SetEncoder(EncoderConfig(hidden=(4,), latent=3, pooling=pooling))
        encoder.per_sample = Field()
        for seed in range(6):
            rng = np.random.default_rng(seed)
            even, crowded = (torch.from_numpy(np.concatenate([rng.uniform(size=(2000, 3)), f(rng, 2000)], axis=1))
                             for f in (_even, _crowded))
            both = encoder(torch.stack([even, crowded]).float())
            gaps[pooling].append(float(torch.linalg.norm(both[0] - both[1])))
    mean, density = np.mean(gaps["mean"]), np.mean(gaps["density"])
    assert mean > 0.5  # the plain mean follows the crowd
    assert density < 0.15 * mean, (density, mean)  # measured: 0.07 × the mean's gap


def test_density_weights_sum_to_one_favour_sparse_samples_and_survive_degenerate_sets():
    rng = np.random.default_rng(0)
    coordinates = torch.from_numpy(_crowded(rng, 1000))[None]
    weights = density_weights(coordinates, 8)[0]
    assert torch.isclose(weights.sum(), torch.tensor(1.0, dtype=weights.dtype))
    assert weights[:900].sum() < 0.2  # the crowded 90 % cover a small corner
    one = density_weights(torch.zeros(2, 1, 6), 8)
    assert torch.equal(one, torch.ones(2, 1))
    same = density_weights(torch.ones(1, 30, 6), 8)  # every sample at one point: weighed evenly
    assert torch.allclose(same, torch.full((1, 30), 1 / 30))
    few = density_weights(torch.randn(1, 4, 6), 8)  # k beyond the set: its size − 1
    assert torch.isclose(few.sum(), torch.tensor(1.0)) and (few > 0).all()


def test_the_k_d_tree_and_the_exhaustive_search_agree():
    points = torch.randn(3, 500, 6, dtype=torch.float64)
    tree, exhaustive = knn_radius(points, 8), knn_radius(points, 8, exhaustive=True)
    torch.testing.assert_close(tree, exhaustive, rtol=1e-6, atol=1e-9)
    brute = torch.cdist(points, points).sort(dim=-1).values[..., 8]
    torch.testing.assert_close(tree, brute, rtol=1e-6, atol=1e-9)
    with pytest.raises(ValueError, match="k must lie in"):
        knn_radius(points, 500)


def test_mean_pooling_is_the_paper_encoder_and_density_pooling_has_its_weights():
    torch.manual_seed(0)
    mean = SetEncoder(EncoderConfig((16, 16), 5))
    density = SetEncoder(EncoderConfig((16, 16), 5, pooling="density", density_k=4))
    assert list(mean.state_dict()) == list(density.state_dict())  # no parameters of its own
    density.load_state_dict(mean.state_dict())
    samples = torch.randn(2, 300, 9)
    assert torch.equal(mean(samples), mean.per_sample(samples).mean(dim=-2))  # exactly the plain mean
    weights = density_weights(samples[..., 3:], 4)
    torch.testing.assert_close(density(samples), (weights[..., None] * mean.per_sample(samples)).sum(dim=-2))
    samples.requires_grad_(True)
    density(samples).sum().backward()  # the weights carry no gradient, the codes do
    assert samples.grad is not None and torch.isfinite(samples.grad).all()
    for bad, match in (({"pooling": "max"}, "pooling must be one of"), ({"density_k": 0}, "density_k")):
        with pytest.raises(ValueError, match=match):
            EncoderConfig(**bad)


def test_attention_pooling_starts_as_the_mean_and_weighs_each_head_over_the_set(monkeypatch):
    monkeypatch.setattr(encoders, "_SCORE_CHUNK", 64)  # the scores of a set in several chunks, one softmax
    torch.manual_seed(0)
    mean = SetEncoder(EncoderConfig((16, 16), 8))
    attention = SetEncoder(EncoderConfig((16, 16), 8, pooling="attention", attention_heads=4))
    attention.load_state_dict(mean.state_dict(), strict=False)  # the same φ; the score network its own
    samples = torch.randn(2, 300, 9)
    torch.testing.assert_close(attention(samples), mean(samples))  # an untrained score layer: the plain mean
    torch.nn.init.normal_(attention.scores[-1].weight)
    weights = attention.weights(samples)
    assert weights.shape == (2, 300, 4)
    torch.testing.assert_close(weights.sum(dim=1), torch.ones(2, 4))
    codes = mean.per_sample(samples)  # head h pools features 2h, 2h + 1 with its own weights
    expected = torch.cat([(weights[..., h, None] * codes[..., 2 * h:2 * h + 2]).sum(dim=1) for h in range(4)], dim=-1)
    torch.testing.assert_close(attention(samples), expected)
    assert not torch.allclose(attention(samples), mean(samples))
    samples.requires_grad_(True)
    attention(samples).sum().backward()  # the weights carry gradient to the scores
    assert attention.scores[-1].weight.grad is not None and attention.scores[-1].weight.grad.abs().sum() > 0
    with_rho = SetEncoder(EncoderConfig((16, 12), 5, pooled=(8,), pooling="attention", attention_heads=3))
    assert with_rho(samples).shape == (2, 5)  # ρ's input (12 features) is cut in 3
    with pytest.raises(ValueError, match="attention_heads must be"):
        EncoderConfig((16, 16), 8, pooling="attention", attention_heads=3)  # 3 does not divide 8
    with pytest.raises(ValueError, match="attention_heads must be"):
        EncoderConfig((16, 16), 8, pooling="attention", attention_heads=True)
    EncoderConfig((16, 16), 10, attention_heads=3)  # checked only where attention pools


def test_an_attention_model_encodes_a_large_set_in_chunks_and_fine_tunes_only_as_attention(toy_materials, tmp_path,
                                                                                         monkeypatch):
    cfg = tiny("nbrdf", toy_materials, tmp_path / "run", epochs=1)
    cfg.model.encoder.pooling = "attention"
    run = train(cfg)
    model = Model.load(run.path)
    torch.nn.init.normal_(model.network.encoder.scores[-1].weight)  # weights that are not even
    rng = np.random.default_rng(0)
    wi, wo = sample_pattern("uniform", 3000, rng)
    values = rng.uniform(0.01, 1.0, (3000, 3))
    whole = model.encode(values, (wi, wo))
    monkeypatch.setattr("frenbrdf.models.autoencoder.ENCODE_CHUNK", 700)  # one softmax over all the chunks
    np.testing.assert_allclose(model.encode(values, (wi, wo)), whole, rtol=1e-5, atol=1e-6)
    tuned = tiny("nbrdf", toy_materials, tmp_path / "tuned", epochs=1, init_from=str(run.path))
    tuned.model.encoder.pooling = "attention"
    assert train(tuned).history[-1]["epoch"] == 0
    mean = tiny("nbrdf", toy_materials, tmp_path / "mean", epochs=1, init_from=str(run.path))
    with pytest.raises(ValueError, match="init_from"):  # the score network has nowhere to go
        train(mean)


def test_a_model_saved_before_pooling_loads_with_the_mean_and_the_same_latents(toy_materials, tmp_path):
    run = train(tiny("nbrdf", toy_materials, tmp_path / "run", epochs=1))
    model = Model.load(run.path)
    assert model.config.encoder.pooling == "mean"
    checkpoint = checkpoints.load(run.path / "best.pt")
    saved = json.loads(checkpoint["config"])
    for key in encoders.POOLING_FIELDS:
        del saved["model"]["encoder"][key]
    checkpoint["config"] = json.dumps(saved)
    checkpoints.save(tmp_path / "old.pt", checkpoint)
    checkpoints.save_mapping(tmp_path, model.mapping.state())
    old = Model.load(tmp_path / "old.pt")
    assert old.config.encoder == model.config.encoder
    rng = np.random.default_rng(0)
    wi, wo = sample_pattern("uniform", 500, rng)
    values = rng.uniform(0, 0.5, (500, 3))
    np.testing.assert_array_equal(old.encode(values, (wi, wo)), model.encode(values, (wi, wo)))


def test_a_run_from_before_pooling_resumes(toy_materials, tmp_path):
    cfg = tiny("nbrdf", toy_materials, tmp_path / "run", epochs=1)
    train(cfg)
    last = checkpoints.load(tmp_path / "run" / "last.pt")
    saved = json.loads(last["config"])
    for key in encoders.POOLING_FIELDS:
        del saved["model"]["encoder"][key]
    last["config"] = json.dumps(saved)
    checkpoints.save(tmp_path / "run" / "last.pt", last)
    (tmp_path / "run" / "config.json").write_text(json.dumps(saved))
    resumed = train(dataclasses.replace(Run(tmp_path / "run").config, epochs=2), resume=True)
    assert [entry["epoch"] for entry in resumed.history] == [-1, 0, 1]
    with pytest.raises(ValueError, match="model.encoder.pooling"):  # a run is resumed with its own pooling
        density = dataclasses.replace(cfg, epochs=3)
        density.model.encoder.pooling = "density"
        train(density, resume=True)


# ---------------------------------------------------------------------------------------------------------------
# Training


def test_a_tiny_run_with_instruments_and_density_pooling_trains_and_reconstructs(toy_materials, tmp_path):
    cfg = tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=2, sampling="instruments")
    cfg.model.encoder.pooling = "density"
    run = train(cfg)
    assert all(np.isfinite(entry["val_rec"]) for entry in run.history)
    saved = Run(run.path).config
    assert saved.sampling == cfg.sampling and saved.model.encoder.pooling == "density"
    model = Model.load(run.path)
    assert model.config.encoder.pooling == "density"
    samples = frenbrdf.io.read_samples(sorted(toy_materials.glob("*.binary"))[0], samples=1500, seed=1,
                                       pattern="gonioreflectometer")
    result = model.reconstruct(samples.values, (samples.wi, samples.wo), refine="none")
    assert np.all(np.isfinite(result.z))
    assert np.all(np.isfinite(result.nbrdf(samples.wi, samples.wo)))
    # A fine-tune may change how the codes are pooled: the weights are the same.
    tuned = tiny("frenbrdf", toy_materials, tmp_path / "tuned", epochs=1, init_from=str(run.path))
    assert tuned.model.encoder.pooling == "mean"
    assert train(tuned).history[-1]["epoch"] == 0


def test_validation_reads_its_tables_through_the_sampling_when_asked(prepared):
    from frenbrdf.models.autoencoder import AutoEncoder
    from frenbrdf.training import evaluate_split

    cfg, data = prepared
    network = AutoEncoder(cfg.model)
    specular = SamplingConfig(patterns={"specular": 1.0}, counts=(50, 60))
    losses = {}
    for through in ("merl-bins", "sampling"):
        drawer, _ = _drawer(prepared, sampling=specular, validate_through=through)
        runs = [evaluate_split(network, None, drawer.cfg, data, data.validation, "cpu", drawer=drawer)["rec"]
                for _ in range(2)]
        assert runs[0] == runs[1]  # the same samples every epoch
        losses[through] = runs[0]
    assert losses["sampling"] != losses["merl-bins"]
    # Without a pattern mixture, or without the drawer, the validation stays on random bins.
    drawer, _ = _drawer(prepared, validate_through="sampling")
    assert evaluate_split(network, None, drawer.cfg, data, data.validation, "cpu", drawer=drawer)["rec"] == \
        losses["merl-bins"]
    drawer, _ = _drawer(prepared, sampling=specular, validate_through="sampling")
    assert evaluate_split(network, None, drawer.cfg, data, data.validation, "cpu")["rec"] == losses["merl-bins"]
    with pytest.raises(ValueError, match="validate_through must be one of"):
        dataclasses.replace(cfg, validate_through="uniform").validate()
