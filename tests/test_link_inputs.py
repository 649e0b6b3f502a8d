"""The training scripts' links (release/link_inputs.sh) never replace what is already under a name: a user's
file, a folder, or a link to another file stops the script with an error and stays as it was."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

HELPER = Path(__file__).resolve().parents[1] / "release" / "link_inputs.sh"
pytestmark = pytest.mark.skipif(shutil.which("bash") is None, reason="the training scripts need bash")


def _link(tmp_path: Path, call: str) -> subprocess.CompletedProcess:
    script = f'set -euo pipefail; source "{HELPER}"; {call}; echo done'
    return subprocess.run(["bash", "-c", script], cwd=tmp_path, capture_output=True, text=True)


@pytest.fixture
def inputs(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "work").mkdir()
    for name in ("a.binary", "b.binary"):
        (tmp_path / "data" / name).write_text(name)
    return tmp_path


def test_links_each_input_and_keeps_links_already_made(inputs):
    for _ in range(2):  # the second call finds its own links and keeps them
        result = _link(inputs, "link_into work data/a.binary data/b.binary")
        assert result.returncode == 0 and result.stdout == "done\n", result.stderr
    for name in ("a.binary", "b.binary"):
        link = inputs / "work" / name
        assert link.is_symlink() and link.resolve() == (inputs / "data" / name).resolve()
    assert _link(inputs, "link_as work/renamed.binary data/a.binary").returncode == 0
    assert (inputs / "work" / "renamed.binary").read_text() == "a.binary"


@pytest.mark.parametrize("in_the_way", ["file", "folder", "other link", "dangling link"])
def test_refuses_to_replace_what_is_in_the_way(inputs, in_the_way):
    target = inputs / "work" / "a.binary"
    if in_the_way == "file":
        target.write_text("a user's own file")
    elif in_the_way == "folder":
        target.mkdir()
        (target / "kept").write_text("kept")
    elif in_the_way == "other link":
        target.symlink_to(inputs / "data" / "b.binary")
    else:
        target.symlink_to(inputs / "nowhere")
    before = target.read_text() if in_the_way == "file" else None
    result = _link(inputs, "link_into work data/a.binary data/b.binary")
    assert result.returncode != 0 and "done" not in result.stdout
    assert "work/a.binary is in the way" in result.stderr
    if in_the_way == "file":
        assert not target.is_symlink() and target.read_text() == before
    elif in_the_way == "folder":
        assert (target / "kept").read_text() == "kept" and not (target / "a.binary").exists()
    elif in_the_way == "other link":
        assert target.resolve() == (inputs / "data" / "b.binary").resolve()
    else:
        assert target.is_symlink() and not target.exists()


def test_refuses_a_missing_input(inputs):
    result = _link(inputs, "link_into work data/missing.binary")
    assert result.returncode != 0 and "data/missing.binary: no such file" in result.stderr
    assert not (inputs / "work" / "missing.binary").is_symlink()
