"""frenbrdf: neural BRDFs (FreNBRDF) from measured materials: train, reconstruct, render, evaluate."""

from __future__ import annotations

import os

from ..exceptions import TrainingDiverged
from .parser import build_parser

__all__ = ["build_parser", "main", "one_line"]


def one_line(error: BaseException) -> str:
    """The message of ``error`` on one line: an OSError as ``FILE: reason`` (no ``[Errno N]``), and line breaks (a
    file name may hold them) written as ``\\n``, so the error is always the one line a script reads."""
    text = str(error)
    if isinstance(error, OSError) and error.strerror and error.filename is not None:
        text = f"{os.fsdecode(error.filename)}: {error.strerror}"
        if error.filename2 is not None:
            text += f" (→ {os.fsdecode(error.filename2)})"
    return text.replace("\r", "\\r").replace("\n", "\\n")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except KeyboardInterrupt:  # reading an option's limit imports its module (torch, about 2 s)
        parser.exit(130, "frenbrdf: interrupted\n")
    try:
        return args.run(args)
    except (ValueError, OSError, TrainingDiverged) as error:  # bad input: a clear message, not a traceback
        parser.exit(2, f"frenbrdf {args.command}: error: {one_line(error)}\n")
    except KeyboardInterrupt:  # Ctrl-C: one line; every output is written atomically, so nothing is left half-written
        parser.exit(130, f"frenbrdf {args.command}: interrupted\n")
    except RuntimeError as error:
        if not str(error).startswith("Symlink loop"):  # pathlib raises this for a link loop before Python 3.13
            raise
        parser.exit(2, f"frenbrdf {args.command}: error: {one_line(error)} (a link that leads back to itself)\n")
