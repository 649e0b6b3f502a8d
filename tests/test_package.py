"""The installed package: public API, typing markers and the command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import frenbrdf
from frenbrdf.models import pretrained


def test_public_api_is_exported():
    for name in frenbrdf.__all__:
        assert hasattr(frenbrdf, name), name
    assert frenbrdf.__version__ == "0.1.0"


def test_the_subpackages_are_attributes_without_their_own_import():
    # ``import frenbrdf`` imports them lazily; code written when it imported them at once still reads frenbrdf.io.
    code = "import frenbrdf; print(frenbrdf.io.read_samples is frenbrdf.read_samples, frenbrdf.render.render.__name__)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout == "True render\n"
    with pytest.raises(AttributeError, match="has no attribute 'nothing'"):
        frenbrdf.nothing  # noqa: B018


def test_package_is_typed():
    """The package ships its typing marker; that ``_native.pyi`` matches the extension is mypy's stubtest's check
    (.ci/run: ``python -m mypy.stubtest frenbrdf._native``)."""
    assert (Path(frenbrdf.__file__).parent / "py.typed").exists()


def test_cli_info_reports_a_working_install():
    result = subprocess.run(
        [sys.executable, "-m", "frenbrdf.cli", "info", "--json"], capture_output=True, text=True, check=True
    )
    report = json.loads(result.stdout)
    assert report["self_check"] == "ok"
    assert report["frenbrdf"] == frenbrdf.__version__
    assert report["native_threads"] >= 1
    assert report["pretrained_model"] == f"version {pretrained.VERSION}"


def test_cli_info_says_when_the_shipped_model_is_absent_or_damaged(tmp_path, monkeypatch):
    from frenbrdf.cli import commands

    monkeypatch.setattr(pretrained, "PACKAGE_DIR", tmp_path)
    assert commands._pretrained_version() == "none shipped with this installation"
    (tmp_path / pretrained.CARD_FILE).write_text("{not json")
    assert commands._pretrained_version().startswith("unreadable: ")


def test_cli_rejects_unknown_commands():
    result = subprocess.run([sys.executable, "-m", "frenbrdf.cli", "frobnicate"], capture_output=True, text=True)
    assert result.returncode == 2
    assert "invalid choice" in result.stderr


def test_cli_version_and_help_read_as_plain_text(capsys):
    from frenbrdf import cli

    with pytest.raises(SystemExit) as stop:
        cli.main(["--version"])
    assert stop.value.code == 0 and capsys.readouterr().out.strip() == f"frenbrdf {frenbrdf.__version__}"
    parser = cli.build_parser()
    subcommands = next(action for action in parser._actions if action.choices and "train" in action.choices)
    for text in [parser.format_help(), *(sub.format_help() for sub in subcommands.choices.values())]:
        for markup in ("``", ":mod:", ":func:", ":class:"):
            assert markup not in text, text
