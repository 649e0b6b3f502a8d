"""The installed package: public API, typing markers and the command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import frenbrdf


def test_public_api_is_exported():
    for name in frenbrdf.__all__:
        assert hasattr(frenbrdf, name), name
    assert frenbrdf.__version__ == "0.1.0"


def test_native_module_is_private_and_typed():
    package = Path(frenbrdf.__file__).parent
    assert (package / "py.typed").exists()
    stub = (package / "_native.pyi").read_text()
    from frenbrdf import _native

    public_native = [name for name in dir(_native) if not name.startswith("_")]
    for name in public_native:
        assert name in stub, f"_native.{name} is missing from _native.pyi"


def test_cli_info_reports_a_working_install():
    result = subprocess.run(
        [sys.executable, "-m", "frenbrdf.cli", "info", "--json"], capture_output=True, text=True, check=True
    )
    report = json.loads(result.stdout)
    assert report["self_check"] == "ok"
    assert report["frenbrdf"] == frenbrdf.__version__
    assert report["native_threads"] >= 1


def test_cli_rejects_unknown_commands():
    result = subprocess.run([sys.executable, "-m", "frenbrdf.cli", "frobnicate"], capture_output=True, text=True)
    assert result.returncode == 2
    assert "invalid choice" in result.stderr
