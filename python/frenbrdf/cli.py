"""The ``frenbrdf`` command line."""

from __future__ import annotations

import argparse
import json
import platform
import sys


def _info(args: argparse.Namespace) -> int:
    """Reports the installation and checks that the native core works."""
    import numpy as np

    import frenbrdf
    from frenbrdf import _native

    # A tiny end-to-end check of the native core: a specular pair has θ_h = 0.
    angles = frenbrdf.directions_to_rusinkiewicz(np.array([0.0, 0.6, 0.8]), np.array([0.0, -0.6, 0.8]))
    report = {
        "frenbrdf": frenbrdf.__version__,
        "native_module": _native.__file__,
        "native_threads": _native.num_threads(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "torch": _torch_version(),
        "self_check": "ok" if abs(angles[0]) < 1e-12 else f"FAILED: θ_h = {angles[0]}",
    }
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        width = max(map(len, report))
        for key, value in report.items():
            print(f"{key:<{width}}  {value}")
    return 0 if report["self_check"] == "ok" else 1


def _torch_version() -> str:
    try:
        import torch
    except ImportError:
        return "not installed"
    return torch.__version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="frenbrdf", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    info = commands.add_parser("info", help="report the installation and run a self-check")
    info.add_argument("--json", action="store_true", help="print the report as JSON")
    info.set_defaults(run=_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
