"""Atomic writes: the target appears whole or not at all, with the usual permissions."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from frenbrdf.io.atomic import atomic_path, save_csv, save_json, write_text


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "report.json"
    save_json(target, {"old": 1})
    with pytest.raises(RuntimeError):
        with atomic_path(target) as temporary:
            temporary.write_text("half")
            raise RuntimeError("the writer failed")
    assert target.read_text() == '{\n  "old": 1\n}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_the_temporary_keeps_the_suffix_and_the_file_gets_umask_permissions(tmp_path):
    with atomic_path(tmp_path / "figure.png") as temporary:
        assert temporary.suffix == ".png" and temporary.parent == tmp_path
        temporary.write_bytes(b"png")
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "figure.png").stat().st_mode & 0o777 == 0o666 & ~umask


def test_csv_columns_are_the_union_of_the_rows_keys(tmp_path):
    save_csv(tmp_path / "rows.csv", [{"a": 1}, {"b": 2, "a": 3}])
    assert (tmp_path / "rows.csv").read_text() == "a,b\n1,\n3,2\n"
    write_text(tmp_path / "note.md", "é")
    assert (tmp_path / "note.md").read_text(encoding="utf-8") == "é"
    with pytest.raises(ValueError, match="no rows"):
        save_csv(tmp_path / "empty.csv", [])


@pytest.fixture
def disk_log(monkeypatch):
    """Every fsync (the path it flushed) and rename, in order (Linux names a descriptor's path in /proc)."""
    events, fsync, replace = [], os.fsync, os.replace

    def logged_fsync(descriptor):
        events.append(("fsync", os.readlink(f"/proc/self/fd/{descriptor}")))
        return fsync(descriptor)

    def logged_replace(source, target):
        events.append(("replace", str(source)))
        return replace(source, target)

    monkeypatch.setattr(os, "fsync", logged_fsync)
    monkeypatch.setattr(os, "replace", logged_replace)
    return events


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="names a descriptor's path through Linux's /proc")
def test_a_file_reaches_the_disk_before_its_rename_and_the_rename_before_the_return(tmp_path, disk_log):
    save_json(tmp_path / "out.json", {"a": 1})
    (kind, temporary), (_, renamed), (_, folder) = disk_log
    assert (kind, renamed, folder) == ("fsync", temporary, str(tmp_path))


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="names a descriptor's path through Linux's /proc")
def test_a_staged_folder_reaches_the_disk_whole_before_it_is_put_in_place(tmp_path, disk_log):
    from frenbrdf.io.outputs import OutputFolder

    folder = OutputFolder.claim(tmp_path / "out", command="test")
    with folder.staged() as staging:
        (staging / "sub").mkdir()
        (staging / "sub" / "a.txt").write_text("a")
        (staging / "b.txt").write_text("b")
    flushed_before = {Path(path).name for kind, path in disk_log[:-2] if kind == "fsync"}
    assert {"a.txt", "b.txt", "sub"} <= flushed_before
    assert disk_log[-2][0] == "replace" and disk_log[-1] == ("fsync", str(tmp_path))
    assert (tmp_path / "out" / "sub" / "a.txt").read_text() == "a"
