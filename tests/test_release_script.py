"""release/: train_shipped_model.sh goes on where a failed run stopped (each finished stage is skipped on a rerun,
a training stopped midway resumes, the shipped model is packed again), tested with stand-ins for the commands it
calls that log their arguments (the real ones are tested elsewhere); its Python half finds held-out measurements
as well as tables and replaces no file of a user's in its work folder."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
from pathlib import Path

import pytest

from .conftest import script_module

SCRIPT = Path(__file__).resolve().parents[1] / "release" / "train_shipped_model.sh"
pytestmark = pytest.mark.skipif(shutil.which("bash") is None, reason="the release script needs bash")

# A stand-in for `frenbrdf` and `python`: logs its call; `frenbrdf train --out D` leaves D/last.pt and fails where
# D's name is in $FAIL_TRAINING.
STAND_IN = """#!/usr/bin/env bash
echo "$(basename "$0") $*" | sed "s|$WORK_ROOT/||g" >> "$WORK_ROOT/calls.log"
if [[ $(basename "$0") == frenbrdf && $1 == train ]]; then
    out=$(echo "$@" | sed 's/.*--out \\([^ ]*\\).*/\\1/'); mkdir -p "$out"; touch "$out/last.pt"
    [[ " $FAIL_TRAINING " == *" $(basename "$out") "* ]] && exit 1
fi
exit 0
"""


def _shared(root: Path) -> Path:
    shared = root / "shared"
    for name in ("merl-nbrdf/alum.h5", "rgl-nbrdf/paper.h5", "rgl-nbrdf/felt.h5", "rgl-measured/felt.bsdf"):
        (shared / name).parent.mkdir(parents=True, exist_ok=True)
        (shared / name).write_text(name)
    return shared


def _run(root: Path, fail: str = "") -> list[str]:
    (root / "calls.log").unlink(missing_ok=True)
    bin_dir = root / "bin"
    bin_dir.mkdir(exist_ok=True)
    for name in ("frenbrdf", "python"):
        (bin_dir / name).write_text(STAND_IN)
        (bin_dir / name).chmod(stat.S_IRWXU)
    env = {**os.environ, "PATH": f"{bin_dir}:{os.environ['PATH']}", "WORK_ROOT": str(root), "FAIL_TRAINING": fail}
    result = subprocess.run(["bash", str(SCRIPT), str(root / "shared"), str(root / "work"), "--trained-on", "X"],
                            env=env, capture_output=True, text=True)
    calls = (root / "calls.log").read_text().splitlines()
    assert (result.returncode != 0) == bool(fail), result.stderr
    return calls


def test_a_rerun_skips_what_finished_and_resumes_the_training_that_failed(tmp_path):
    _shared(tmp_path)
    first = _run(tmp_path, fail="devices-mean")
    assert sum(call.startswith("frenbrdf import-nbrdf") for call in first) == 2
    assert "paper.h5" in first[1] and "felt.h5" not in first[1]  # a measured material's fit is left out
    decoder = next(call for call in first if "train_shipped_model.py" in call)
    assert "--resume" not in decoder and decoder.endswith("--trained-on X")
    assert sum(call.startswith("frenbrdf train") for call in first) == 4
    assert (tmp_path / "work" / "measured" / "felt.bsdf").is_symlink()
    assert not any("pack_" in call for call in first)  # an encoder failed: nothing packed

    second = _run(tmp_path)
    trainings = [call for call in second if call.startswith("frenbrdf train")]
    assert len(trainings) == 1 and "encoders/devices-mean" in trainings[0] and "--resume" in trainings[0]
    assert not any("import-nbrdf" in call or "synth" in call or "train_shipped_model.py" in call for call in second)
    packed = next(call for call in second if "pack_encoder_mean.py" in call)
    assert "--dest work/v9" in packed  # version 9 goes to the work folder, the package gets it with its second look
    looks = [call for call in second if "second_look.py train" in call]
    assert sorted(call.split("--seed ")[1].split()[0] for call in looks) == ["1", "2", "3"]
    assert all("--base work/v9" in call for call in looks)
    assert "pack_second_look.py" in second[-1] and "work/looks/s1 work/looks/s2 work/looks/s3" in second[-1]
    assert "--mean --steps 2 --version 12" in second[-1]  # the three looks averaged, twice (look-ensemble)

    third = _run(tmp_path)
    assert len(third) == 1 and "pack_second_look.py" in third[0]


def test_a_decoder_stopped_midway_resumes(tmp_path):
    _shared(tmp_path)
    run = tmp_path / "work" / "base-work" / "run"
    run.mkdir(parents=True)
    (run / "last.pt").write_text("an epoch")
    decoder = next(call for call in _run(tmp_path) if "train_shipped_model.py" in call)
    assert "--resume" in decoder


def test_the_held_out_files_are_found_whatever_their_kind(tmp_path):
    shipped = script_module("train_shipped_model")
    (tmp_path / "data").mkdir()
    for name in ("alum.binary", "felt.bsdf", "paper.binary"):
        (tmp_path / "data" / name).write_bytes(b"")
    assert [p.name for p in shipped.held_out_files(tmp_path, {"felt", "alum"})] == ["alum.binary", "felt.bsdf"]
    with pytest.raises(FileNotFoundError, match="lacks the held-out materials \\['wood'\\]"):
        shipped.held_out_files(tmp_path, ["alum", "wood"])
    with pytest.raises(FileNotFoundError, match="sources.json is missing.*--reuse"):
        shipped.read_sources(tmp_path)


def test_the_linked_data_folder_keeps_its_links_and_refuses_a_users_file(tmp_path):
    shipped = script_module("train_shipped_model")
    source = tmp_path / "tables"
    source.mkdir()
    for name in ("alum.binary", "felt.binary"):
        (source / name).write_bytes(name.encode())
    data = tmp_path / "work" / "data"
    for _ in range(2):  # a rerun finds its own links
        shipped.linked_data([source], data)
    assert all((data / name).is_symlink() for name in ("alum.binary", "felt.binary"))
    (data / "felt.binary").unlink()
    (data / "felt.binary").write_bytes(b"a user's own table")
    with pytest.raises(ValueError, match="felt.binary is in the way"):
        shipped.linked_data([source], data)
    assert (data / "felt.binary").read_bytes() == b"a user's own table"
