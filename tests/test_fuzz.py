"""Fuzzing every reader, config and output path (issue 30): whatever a file or a setting holds, frenbrdf either
reads it or raises a named error (ValueError or OSError, which the CLI reports with exit 2) — never another
exception, never a hang, never a write outside the folder asked for.

The default run is quick (a few hundred examples in all); the ``slow`` tests feed large inputs.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import frenbrdf
from frenbrdf import cli
from frenbrdf.io import checkpoints, outputs, read_material, read_samples, write_material
from frenbrdf.io.merl import N_BINS
from frenbrdf.io.nbrdf import read_nbrdf
from frenbrdf.models.autoencoder import MAX_PARAMETERS
from frenbrdf.models.nbrdf import NBRDF, as_brdf
from frenbrdf.training import config_for, load_config

from .io.test_bsdf_native import flat_material, tensor_file
from .test_measurements import VECTORS, samples

NAMED = (ValueError, OSError)
FAST = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                        HealthCheck.too_slow])


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def _valid_csv() -> bytes:
    rows = samples(60)
    return ("\n".join([",".join(VECTORS)] + [",".join(repr(float(v)) for v in row) for row in rows]) + "\n").encode()


def _valid_npz() -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **{name: samples(60)[:, i] for i, name in enumerate(VECTORS)})
    return buffer.getvalue()


def _valid_astm() -> bytes:
    """An ASTM E1392 file of the same samples: angles in radians, then R,G,B."""
    rows = samples(60)
    angles = [np.arccos(rows[:, 2]), np.arctan2(rows[:, 1], rows[:, 0]), np.arccos(rows[:, 5]),
              np.arctan2(rows[:, 4], rows[:, 3])]
    table = np.column_stack([*angles, rows[:, 6:]])
    header = ["SOURCE fuzz", 'SAMPLE_NAME "valid"', "SCATTER_TYPE BRDF", "NUM_POINTS 60",
              "VARS theta_i,phi_i,theta_s,phi_s,R,G,B"]
    return ("\n".join(header + [",".join(repr(float(v)) for v in row) for row in table]) + "\n").encode()


def _valid_nbrdf() -> bytes:
    buffer = io.BytesIO()
    torch.save({"params": [torch.randn(8, 6), torch.zeros(8), torch.randn(3, 8), torch.zeros(3)],
                "reference": torch.zeros(3), "epsilon": 0.002, "offset": 0.0}, buffer)
    return buffer.getvalue()


VALID = {".csv": _valid_csv(), ".npz": _valid_npz(), ".astm": _valid_astm(), ".pt": _valid_nbrdf(),
         ".bsdf": tensor_file(flat_material())}  # a small RGL measurement (tests/io/test_bsdf_native.py)


def _mutated(original: bytes, data) -> bytes:
    """A valid file with bytes flipped, cut short, or a chunk inserted."""
    kind = data.draw(st.sampled_from(["flip", "truncate", "insert"]))
    if kind == "truncate":
        return original[: data.draw(st.integers(0, len(original) - 1))]
    position = data.draw(st.integers(0, len(original) - 1))
    if kind == "insert":
        return original[:position] + data.draw(st.binary(max_size=64)) + original[position:]
    flips = data.draw(st.lists(st.tuples(st.integers(0, len(original) - 1), st.integers(1, 255)), min_size=1,
                               max_size=8))
    mutable = bytearray(original)
    for index, value in flips:
        mutable[index] ^= value
    return bytes(mutable)


def _reads_or_names(reader, path: Path) -> None:
    try:
        reader(path)
    except NAMED as error:
        assert str(error), f"an empty message for {path.name}"
        text = str(error)
        assert "allow_pickle" not in text and "weights_only" not in text  # never advice to load unsafely


def _network(path):
    """A material file as what renders: the network of an NBRDF file, checked whole."""
    return as_brdf(read_material(path))


READERS = {".csv": [read_samples], ".npz": [read_samples], ".astm": [read_samples],
           ".pt": [read_nbrdf, _network, checkpoints.load],
           ".binary": [read_samples, _network, frenbrdf.read_merl],
           ".h5": [_network], ".json": [load_config],
           ".bsdf": [frenbrdf.read_bsdf, read_samples, _network]}


@FAST
@given(suffix=st.sampled_from(sorted(READERS)), content=st.binary(max_size=2048))
def test_random_bytes_in_every_reader(folder, suffix, content):
    path = folder / f"random{suffix}"
    path.write_bytes(content)
    for reader in READERS[suffix]:
        _reads_or_names(reader, path)


@FAST
@given(suffix=st.sampled_from(sorted(VALID)), data=st.data())
def test_mutated_valid_files(folder, suffix, data):
    path = folder / f"mutated{suffix}"
    path.write_bytes(_mutated(VALID[suffix], data))
    for reader in READERS[suffix]:
        _reads_or_names(reader, path)


@FAST
@given(cells=st.lists(st.lists(st.text(max_size=12), min_size=1, max_size=10), min_size=1, max_size=70),
       header=st.permutations(VECTORS))
def test_generated_csv_tables(folder, cells, header):
    path = folder / "generated.csv"
    with open(path, "w", encoding="utf-8", newline="") as file:
        file.write(",".join(header) + "\n")
        for row in cells:
            file.write(",".join(cell.replace("\n", " ") for cell in row) + "\n")
    _reads_or_names(read_samples, path)


JSON = st.recursive(st.none() | st.booleans() | st.integers(-10**12, 10**12) | st.floats(allow_nan=False)
                    | st.text(max_size=8), lambda inner: st.lists(inner, max_size=4)
                    | st.dictionaries(st.text(max_size=8), inner, max_size=4), max_leaves=8)
KEYS = ["method", "epochs", "lr", "seed", "split", "holdout", "context_samples", "query_samples", "batch_materials",
        "grad_clip", "patience", "render_every", "select", "device", "progress", "context_jitter"]
NESTED = {"model": {"nbrdf": ["hidden"],
                    "encoder": ["hidden", "latent", "dropout", "pooling", "density_k", "attention_heads"],
                    "decoder": ["hidden", "last_layer_scale"], "mapping": ["epsilon", "reference", "form"]},
          "loss": {"frequency": ["lmax", "grid", "slices", "k", "sigma", "extension"]},
          "augment": {"": ["mix", "gain", "gain_range", "procedural"]},
          "sampling": {"": ["patterns", "counts"]}}


@st.composite
def configs(draw):
    config = {key: draw(JSON) for key in draw(st.lists(st.sampled_from(KEYS), max_size=4, unique=True))}
    for top, groups in NESTED.items():
        if draw(st.booleans()):
            section = {}
            for group, keys in groups.items():
                values = {key: draw(JSON | st.integers(-10**9, 10**9)) for key in
                          draw(st.lists(st.sampled_from(keys), max_size=2, unique=True))}
                section.update(values if not group else {group: values})
            config[top] = section
    return config


@FAST
@given(config=configs())
@example(config={"model": {"encoder": {"hidden": []}}})  # once a TypeError: max() of no hidden widths
def test_generated_train_configs(folder, config):
    path = folder / "config.json"
    path.write_text(json.dumps(config))
    try:
        cfg = load_config(path)
    except ValueError as error:
        assert str(error)
    else:  # an accepted config describes a model that can be built cheaply
        assert cfg.model.n_parameters <= MAX_PARAMETERS


NAMES = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=12)


@FAST
@given(name=NAMES, suffix=st.sampled_from(["", ".png", ".PNG", ".jpg", "/", ".png/"]))
def test_render_output_paths(folder, name, suffix):
    target = str(folder / "renders") + os.sep + name + suffix
    try:
        checked = outputs.check_output_file(target, (".png",), overwrite=True)
    except NAMED:
        return
    assert checked.suffix.lower() == ".png" and not checked.is_dir()


@FAST
@given(name=st.sampled_from(["", ".", "..", "out", "input", "input/x", "file.txt", "user", "result"]),
       overwrite=st.booleans())
def test_output_folders_never_take_the_users_files(name, overwrite):
    with tempfile.TemporaryDirectory() as root:
        root = Path(root)
        (root / "input").mkdir()
        source = root / "input" / "measured.csv"
        source.write_bytes(VALID[".csv"])
        (root / "file.txt").write_text("mine")
        (root / "user").mkdir()
        (root / "user" / "notes.txt").write_text("mine")
        (root / "result").mkdir()
        (root / "result" / "reconstruction.json").write_text("{}")
        cwd = os.getcwd()
        os.chdir(root / "input")
        try:
            out = outputs.OutputFolder.claim(Path("..") / name if name else "", command="reconstruct",
                                             inputs=(source,), overwrite=overwrite).path
        except NAMED:
            return
        finally:
            os.chdir(cwd)
        resolved = (root / "input" / out).resolve()
        assert resolved not in (source.parent, root)  # neither the input's folder nor one holding it
        assert resolved != root / "file.txt"
        assert resolved != root / "user" or overwrite


# --------------------------------------------------------------------------- large inputs


@pytest.mark.slow
def test_a_ten_million_row_csv_reads_in_memory_near_its_size(tmp_path):
    import resource

    path = tmp_path / "big.csv"
    rows = samples(1000)
    with open(path, "w") as file:
        file.write(",".join(VECTORS) + "\n")
        block = "\n".join(",".join(f"{v:.6f}" for v in row) for row in rows) + "\n"
        for _ in range(10_000):
            file.write(block)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    measured = read_samples(path)
    grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - before
    data = 10_000_000 * 9 * 8
    assert len(measured) == 10_000_000
    assert grown < 3 * data, f"{grown / 1e9:.1f} GB for {data / 1e9:.2f} GB of data"


@pytest.mark.slow
def test_a_real_zip_bomb_and_huge_counts_are_refused_before_allocating(tmp_path, toy_materials):
    path = tmp_path / "bomb.npz"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        with archive.open("wi_x.npy", "w", force_zip64=True) as member:
            header = io.BytesIO()
            np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False,
                                                          "shape": (900_000_000,)})
            member.write(header.getvalue())
            zeros = bytes(1 << 24)
            for _ in range(7_200_000_000 // len(zeros)):
                member.write(zeros)
    assert path.stat().st_size < 20_000_000
    with pytest.raises(ValueError, match="declares .* bytes uncompressed"):
        read_samples(path)
    with pytest.raises(ValueError, match="context_samples must be ≤"):
        config_for("frenbrdf", context_samples=10**9)
    source = sorted(toy_materials.glob("*.binary"))[0]
    assert len(read_samples(source, samples=10**9)) <= N_BINS


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(suffix=st.sampled_from(sorted(VALID)), data=st.data())
def test_many_mutated_files(folder, suffix, data):
    test_mutated_valid_files.hypothesis.inner_test(folder, suffix, data)


def test_the_cli_reports_fuzzed_inputs_with_exit_2(folder, capsys):
    for suffix in (".csv", ".npz", ".pt", ".bsdf"):
        path = folder / f"cli{suffix}"
        path.write_bytes(os.urandom(512))
        with pytest.raises(SystemExit) as exit_info:
            cli.main(["render", str(path), "--out", str(folder / "x.png"), "--resolution", "16"])
        assert exit_info.value.code == 2
        assert str(path) in capsys.readouterr().err


def test_a_saved_nbrdf_round_trips(folder):
    path = folder / "round.pt"
    path.write_bytes(VALID[".pt"])
    nbrdf = NBRDF.from_weights(read_material(path))
    write_material(folder / "again.pt", nbrdf.weights())
    assert torch.equal(NBRDF.from_weights(read_material(folder / "again.pt")).params[0], nbrdf.params[0])
