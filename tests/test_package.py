"""The installed package: public API, typing markers and the command line."""

from __future__ import annotations

import ast
import inspect
import json
import subprocess
import sys
from pathlib import Path

import pytest

import frenbrdf


def test_public_api_is_exported():
    for name in frenbrdf.__all__:
        assert hasattr(frenbrdf, name), name
    assert frenbrdf.__version__ == "0.1.0"


def _stub_signatures(stub: str) -> dict[str, list[str] | None]:
    """Name → parameter names (None for constants and properties) of the stub's functions, classes and methods."""
    found: dict[str, list[str] | None] = {}

    def parameters(function: ast.FunctionDef) -> list[str]:
        return [a.arg for a in function.args.args if a.arg != "self"]

    for node in ast.parse(stub).body:
        if isinstance(node, ast.FunctionDef):
            found[node.name] = parameters(node)
        elif isinstance(node, ast.AnnAssign):
            found[node.target.id] = None
        elif isinstance(node, ast.ClassDef):
            for member in node.body:
                if isinstance(member, ast.FunctionDef):
                    is_property = any(getattr(d, "id", None) == "property" for d in member.decorator_list)
                    key = node.name if member.name == "__init__" else f"{node.name}.{member.name}"
                    found[key] = None if is_property else parameters(member)
            found.setdefault(node.name, None)  # a class built by a static method has no __init__ to list
    return found


def _native_parameters(obj) -> list[str] | None:
    signature = getattr(obj, "__text_signature__", None)
    if signature is None:
        return None
    return [p.name for p in inspect.signature(obj).parameters.values() if p.name not in ("self", "$self")]


def test_native_stub_matches_the_module():
    """A stubtest of our own: every public name of ``_native`` is in ``_native.pyi`` with the
    same parameter names, and the stub declares nothing the module lacks."""
    package = Path(frenbrdf.__file__).parent
    assert (package / "py.typed").exists()
    from frenbrdf import _native

    stub = _stub_signatures((package / "_native.pyi").read_text())
    actual: dict[str, object] = {}
    for name in (n for n in dir(_native) if not n.startswith("_")):
        obj = getattr(_native, name)
        actual[name] = obj
        if inspect.isclass(obj):
            actual.update({f"{name}.{m}": getattr(obj, m) for m in vars(obj) if not m.startswith("_")})
    assert sorted(set(actual) - set(stub)) == [], "missing from _native.pyi"
    assert sorted(set(stub) - set(actual) - {"__version__"}) == [], "in _native.pyi but not in the module"
    for name, parameters in stub.items():
        if parameters is not None and name in actual:
            assert _native_parameters(actual[name]) == parameters, name


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
