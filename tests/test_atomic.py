"""Atomic writes: the target appears whole or not at all, with the usual permissions."""

from __future__ import annotations

import os

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
