"""Atomic writes: every file frenbrdf writes appears whole or not at all.

A writer writes to a temporary file beside the target (same folder, so the rename stays
on one file system; same suffix, so writers that infer the format from it still work),
then renames it over the target. On failure the temporary file is removed and the
target, if it existed, is left as it was.
"""

from __future__ import annotations

import csv
import io
import json
import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path to write to; renamed over ``path`` when the block ends without error.

    >>> with atomic_path("out.png") as temporary:   # doctest: +SKIP
    ...     figure.savefig(temporary)
    """
    path = Path(path)
    # A name no other process or thread picks; the writer creates the file, so it gets the
    # usual permissions (a file made by mkstemp would be private to its owner).
    temporary = path.with_name(f".{path.name}.{os.getpid()}-{uuid.uuid4().hex[:8]}{path.suffix or '.tmp'}")
    try:
        yield temporary
        os.replace(temporary, path)
    except BaseException as error:
        temporary.unlink(missing_ok=True)
        # A message names the path the caller gave, never the hidden temporary one.
        if isinstance(error, OSError) and error.filename is not None and str(temporary) in str(error.filename):
            raise type(error)(error.errno, error.strerror, str(path)) from None
        if isinstance(error, ValueError) and str(temporary) in str(error):
            raise type(error)(str(error).replace(str(temporary), str(path))) from None
        raise


def write_text(path: str | os.PathLike, text: str) -> None:
    """Writes UTF-8 text atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


def save_json(path: str | os.PathLike, data) -> None:
    """Writes JSON (indented, newline-terminated) atomically."""
    write_text(path, json.dumps(data, indent=2) + "\n")


def save_csv(path: str | os.PathLike, rows: list[dict]) -> None:
    """Writes rows (dicts) as CSV with a header, atomically; the columns are the union of
    the rows' keys in first-seen order, and a row without a key leaves its cell empty."""
    if not rows:
        raise ValueError(f"{path}: no rows to write")
    buffer = io.StringIO()
    columns = list(dict.fromkeys(key for row in rows for key in row))
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text(path, buffer.getvalue())
