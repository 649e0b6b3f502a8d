"""Published NBRDF weights → MERL tables: agreement with a hand-written evaluation,
MERL's missing markers, and clean errors on bad weight files."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

import frenbrdf
from frenbrdf.data.nbrdf_import import (
    evaluate_keras_nbrdf,
    import_nbrdf,
    keras_merl_table,
    keras_nbrdf,
)
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.io.merl import CHANNEL_SCALES, SHAPE
from frenbrdf.models.nbrdf import nbrdf_coordinates

from .conftest import PUBLISHED, PUBLISHED_DIR, needs_published, random_layers, write_keras_h5

# ---------------------------------------------------------------------------------------
# Helpers: an evaluation written out by hand (Keras-layout files: conftest.write_keras_h5).

def reference_rgb(kernels, biases, i: int, j: int, k: int) -> np.ndarray:
    """The network at MERL bin (i, j, k), from the angles of docs/method.md §1 and explicit products."""
    theta_h = (i / 90) ** 2 * math.pi / 2
    theta_d = j / 90 * math.pi / 2
    phi_d = k / 180 * math.pi
    x = np.array([math.sin(theta_h), 0.0, math.cos(theta_h),
                  math.sin(theta_d) * math.cos(phi_d), math.sin(theta_d) * math.sin(phi_d), math.cos(theta_d)])
    for layer, (kernel, bias) in enumerate(zip(kernels, biases, strict=True)):
        x = np.matmul(x, kernel) + bias
        x = np.exp(x) - 1 if layer == len(kernels) - 1 else np.maximum(x, 0)
    return x


def both_above_horizon(i: int, j: int, k: int) -> bool:
    """ω_i and ω_o of bin (i, j, k), φ_h = 0, both above the surface (z of R_y(θ_h) D)."""
    theta_h, theta_d, phi_d = (i / 90) ** 2 * math.pi / 2, j / 90 * math.pi / 2, k / 180 * math.pi
    along, across = math.cos(theta_h) * math.cos(theta_d), math.sin(theta_h) * math.sin(theta_d) * math.cos(phi_d)
    return along - across > 0 and along + across > 0


# ---------------------------------------------------------------------------------------
# The published weights

@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """One published material imported through import_nbrdf, and its weight file."""
    weights = PUBLISHED_DIR / "gold-paint.h5"
    if not weights.exists():
        pytest.skip(f"published NBRDF weights not found in {PUBLISHED_DIR} (set FRENBRDF_SHARED_DATA)")
    (written,) = import_nbrdf([weights], tmp_path_factory.mktemp("merl"), progress=False)
    return weights, written


def test_import_matches_a_direct_evaluation_of_the_network(imported):
    weights, written = imported
    assert written.name == "gold-paint.binary"
    table = frenbrdf.read_merl(written)
    with h5py.File(weights, "r") as file:
        kernels = [file[f"dense_{n}/dense_{n}/kernel:0"][()].astype(np.float64) for n in (1, 2, 3)]
        biases = [file[f"dense_{n}/dense_{n}/bias:0"][()].astype(np.float64) for n in (1, 2, 3)]

    rng = np.random.default_rng(7)
    checked = 0
    for i, j, k in zip(rng.integers(0, 90, 400), rng.integers(0, 90, 400), rng.integers(0, 180, 400), strict=True):
        if not both_above_horizon(i, j, k):
            continue
        expected = np.maximum(reference_rgb(kernels, biases, i, j, k), 0)
        np.testing.assert_allclose(table[:, i, j, k], expected, rtol=1e-12, atol=1e-15,
                                   err_msg=f"bin {(i, j, k)}")
        checked += 1
    assert checked > 250
    # Plausible reflectance, not stored units: a paint's median is well below 1.
    assert 1e-3 < np.median(table[:, frenbrdf.merl_above_horizon()]) < 1


def test_missing_bins_are_exactly_those_below_the_horizon(imported):
    _, written = imported
    stored = frenbrdf.read_merl(written, physical_units=False)
    above = frenbrdf.merl_above_horizon()
    assert 0.5 < above.mean() < 0.9
    assert np.all(stored[:, ~above] == -1.0)
    valid = stored[:, above]
    assert np.all(np.isfinite(valid)) and np.all(valid >= 0)
    np.testing.assert_array_equal(frenbrdf.valid_mask(stored), above)
    # merl_above_horizon agrees with the horizon written out by hand.
    rng = np.random.default_rng(3)
    for i, j, k in zip(rng.integers(0, 90, 300), rng.integers(0, 90, 300), rng.integers(0, 180, 300), strict=True):
        assert above[i, j, k] == both_above_horizon(i, j, k), (i, j, k)


@needs_published
def test_every_published_file_loads_as_6_21_21_3():
    assert len(PUBLISHED) == 80, f"expected the 80 published materials in {PUBLISHED_DIR}"
    for path in PUBLISHED:
        layers = read_keras_nbrdf(path)
        assert [kernel.shape for kernel, _ in layers] == [(6, 21), (21, 21), (21, 3)], path
        assert [bias.shape for _, bias in layers] == [(21,), (21,), (3,)], path
        assert all(kernel.dtype == bias.dtype == np.float64 for kernel, bias in layers)


def test_bin_inputs_follow_the_nbrdf_convention():
    """rusinkiewicz_to_half_diff with φ_h = 0 is H = (sin θ_h, 0, cos θ_h), D = spherical (θ_d, φ_d)."""
    grid = frenbrdf.merl_bin_grid()[::7, ::5, ::9].reshape(-1, 3)
    theta_h, theta_d, phi_d = grid.T
    h, d = frenbrdf.rusinkiewicz_to_half_diff(np.stack([theta_h, 0 * theta_h, theta_d, phi_d], axis=-1))
    np.testing.assert_allclose(h, np.stack([np.sin(theta_h), 0 * theta_h, np.cos(theta_h)], axis=-1), atol=1e-15)
    np.testing.assert_allclose(d, np.stack([np.sin(theta_d) * np.cos(phi_d), np.sin(theta_d) * np.sin(phi_d),
                                            np.cos(theta_d)], axis=-1), atol=1e-15)


# ---------------------------------------------------------------------------------------
# Synthetic networks

def test_load_and_evaluate_round_trip_a_deeper_network(tmp_path):
    """6→8→8→8→3 named dense_8 … dense_11: numeric order, not string order."""
    layers = [(k.astype(np.float32).astype(np.float64), b.astype(np.float32).astype(np.float64))
              for k, b in random_layers([6, 8, 8, 8, 3])]
    path = write_keras_h5(tmp_path / "deep.h5", layers, names=["dense_8", "dense_9", "dense_10", "dense_11"])

    loaded = read_keras_nbrdf(path)
    assert len(loaded) == 4
    for (kernel, bias), (expected_kernel, expected_bias) in zip(loaded, layers, strict=True):
        np.testing.assert_array_equal(kernel, expected_kernel)
        np.testing.assert_array_equal(bias, expected_bias)

    rng = np.random.default_rng(1)
    h, d = rng.normal(size=(5, 1, 3)), rng.normal(size=(1, 4, 3))
    rgb = evaluate_keras_nbrdf(loaded, h, d)
    assert rgb.shape == (5, 4, 3) and rgb.dtype == np.float64
    x = np.concatenate(np.broadcast_arrays(h, d), axis=-1)
    for kernel, bias in layers[:-1]:
        x = np.maximum(x @ kernel + bias, 0)
    np.testing.assert_allclose(rgb, np.exp(x @ layers[-1][0] + layers[-1][1]) - 1, rtol=1e-13, atol=1e-15)


def test_table_of_a_synthetic_network(tmp_path):
    layers = random_layers([6, 8, 8, 3], seed=2)
    table = keras_merl_table(layers)
    assert table.shape == SHAPE and table.dtype == np.float64
    above = frenbrdf.merl_above_horizon()
    for channel, scale in enumerate(CHANNEL_SCALES):
        assert np.all(table[channel][~above] == -scale)

    # Away from the missing bins: the network's output clamped at 0, bin for bin.
    grid = frenbrdf.merl_bin_grid()
    angles = np.stack([grid[..., 0], 0 * grid[..., 0], grid[..., 1], grid[..., 2]], axis=-1)
    h, d = frenbrdf.rusinkiewicz_to_half_diff(angles[::3, ::3])
    raw = np.moveaxis(evaluate_keras_nbrdf(layers, h, d), -1, 0)
    sub_above = above[::3, ::3]
    assert (raw[:, sub_above] < 0).any(), "the test network should produce some negative outputs"
    np.testing.assert_array_equal(table[:, ::3, ::3][:, sub_above], np.maximum(raw[:, sub_above], 0))

    written = import_nbrdf([write_keras_h5(tmp_path / "synthetic.h5", layers)], tmp_path / "out", progress=False)
    stored = frenbrdf.read_merl(written[0], physical_units=False)
    assert np.all(stored[:, ~above] == -1.0) and np.all(stored[:, above] >= 0)


def test_import_writes_one_file_per_input_in_order(tmp_path):
    paths = [write_keras_h5(tmp_path / f"{name}.h5", random_layers([6, 5, 3], seed=s))
             for s, name in enumerate(["b-material", "a-material"])]
    out_dir = tmp_path / "nested" / "out"
    written = import_nbrdf(iter(paths), out_dir, progress=False)
    assert written == [out_dir / "b-material.binary", out_dir / "a-material.binary"]
    first, second = (frenbrdf.read_merl(p) for p in written)
    assert not np.array_equal(first, second)


# ---------------------------------------------------------------------------------------
# Bad weight files

def _good(tmp_path):
    return write_keras_h5(tmp_path / "good.h5", random_layers([6, 4, 3]))


def _delete(key):
    def edit(path):
        with h5py.File(path, "a") as file:
            del file[key]
    return edit


def _replace(key, value, *more):
    """Replaces dataset ``key`` by ``value`` (and further key, value pairs)."""
    def edit(path):
        with h5py.File(path, "a") as file:
            for k, v in zip((key, *more[::2]), (value, *more[1::2]), strict=True):
                del file[k]
                file[k] = v
    return edit


def _extra_layer(path):
    with h5py.File(path, "a") as file:
        file["batch_normalization_1/batch_normalization_1/gamma:0"] = np.ones(4, np.float32)


def _truncate(path):
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _not_hdf5(path):
    path.write_text('{"class_name": "Sequential"}')


def _no_layers(path):
    with h5py.File(path, "w") as file:
        file.create_group("lambda_1")


@pytest.mark.parametrize("edit, message", [
    (_not_hdf5, "not a readable HDF5 file"),
    (_truncate, "not a readable HDF5 file"),
    (_no_layers, "no Dense layer groups"),
    (_delete("dense_2/dense_2/kernel:0"), "missing dataset 'dense_2/dense_2/kernel:0'"),
    (_delete("dense_1/dense_1/bias:0"), "missing dataset 'dense_1/dense_1/bias:0'"),
    (_replace("dense_2/dense_2/kernel:0", np.zeros((5, 3), np.float32)),
     r"'dense_2' takes 5 inputs but layer 'dense_1' has 4"),
    (_replace("dense_1/dense_1/kernel:0", np.zeros((7, 4), np.float32)),
     r"takes 7 inputs but the network input \(H, D\) has 6"),
    (_replace("dense_2/dense_2/kernel:0", np.zeros((4, 2), np.float32),
              "dense_2/dense_2/bias:0", np.zeros(2, np.float32)),
     "last layer 'dense_2' has 2 outputs, expected 3"),
    (_replace("dense_1/dense_1/bias:0", np.zeros(5, np.float32)), "bias shape"),
    (_replace("dense_1/dense_1/kernel:0", np.zeros(24, np.float32)), "kernel shape"),
    (_replace("dense_2/dense_2/bias:0", np.array([0, np.nan, 0], np.float32)), r"'dense_2' bias holds NaN.*\(1,\)"),
    (_replace("dense_1/dense_1/kernel:0", np.full((6, 4), np.inf, np.float32)), "kernel holds NaN or infinite"),
    (_replace("dense_1/dense_1/kernel:0", np.array(["a"] * 24, dtype="S1").reshape(6, 4)), "expected real numbers"),
    (_extra_layer, "'batch_normalization_1' has weights but is not a Dense layer"),
])
def test_bad_weight_files_give_clear_errors(tmp_path, edit, message):
    path = _good(tmp_path)
    edit(path)
    with pytest.raises(ValueError, match=message) as error:
        read_keras_nbrdf(path)
    assert str(path) in str(error.value)


def test_missing_weight_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="absent.h5"):
        read_keras_nbrdf(tmp_path / "absent.h5")


def test_one_bad_file_stops_the_import_before_writing(tmp_path):
    good = [write_keras_h5(tmp_path / f"good{i}.h5", random_layers([6, 4, 3], seed=i)) for i in range(2)]
    bad = _good(tmp_path).rename(tmp_path / "bad.h5")
    _truncate(bad)
    out_dir = tmp_path / "out"
    with pytest.raises(ValueError, match="bad.h5"):
        import_nbrdf([good[0], bad, good[1]], out_dir, progress=False)
    assert not out_dir.exists()


def test_duplicate_names_are_refused(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    paths = [write_keras_h5(tmp_path / folder / "same.h5", random_layers([6, 4, 3])) for folder in "ab"]
    with pytest.raises(ValueError, match="same: .*a/same.h5.*b/same.h5"):
        import_nbrdf(paths, tmp_path / "out", progress=False)
    with pytest.raises(ValueError, match="no NBRDF weight files"):
        import_nbrdf([], tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------------------
# One forward pass, one table writer

def test_keras_network_as_an_nbrdf_agrees_with_the_float64_evaluation():
    """keras_nbrdf (float32 NBRDF, mapping exp(x) − 1) against evaluate_keras_nbrdf (float64)."""
    layers = random_layers([6, 8, 8, 3], seed=6)
    nbrdf = keras_nbrdf(layers)
    rng = np.random.default_rng(8)
    wi, wo = rng.normal(size=(500, 3)), rng.normal(size=(500, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]) + 0.05, np.abs(wo[:, 2]) + 0.05
    wi, wo = wi / np.linalg.norm(wi, axis=1, keepdims=True), wo / np.linalg.norm(wo, axis=1, keepdims=True)
    coords = nbrdf_coordinates(wi, wo)
    expected = np.maximum(evaluate_keras_nbrdf(layers, coords[:, :3], coords[:, 3:]), 0)
    np.testing.assert_allclose(nbrdf(wi, wo), expected, rtol=1e-4, atol=1e-6)
    # The same table writer for both: the NBRDF object's table equals the import's to float32 accuracy.
    np.testing.assert_allclose(nbrdf.merl_table(), keras_merl_table(layers), rtol=1e-4, atol=1e-6)
