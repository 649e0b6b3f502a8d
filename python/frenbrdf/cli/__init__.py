"""frenbrdf: neural BRDFs (FreNBRDF) from measured materials: train, reconstruct, render, evaluate."""

from __future__ import annotations

from ..exceptions import TrainingDiverged
from .parser import build_parser

__all__ = ["build_parser", "main"]


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except (ValueError, OSError, TrainingDiverged) as error:  # bad input: a clear message, not a traceback
        parser.exit(2, f"frenbrdf {args.command}: error: {error}\n")
    except KeyboardInterrupt:  # Ctrl-C: one line; every output is written atomically, so nothing is left half-written
        parser.exit(130, f"frenbrdf {args.command}: interrupted\n")
    except RuntimeError as error:
        if not str(error).startswith("Symlink loop"):  # pathlib raises this for a link loop before Python 3.13
            raise
        parser.exit(2, f"frenbrdf {args.command}: error: {error} (a link that leads back to itself)\n")
