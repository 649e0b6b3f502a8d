"""Atomic writes: every file frenbrdf writes appears whole or not at all.

A writer writes to a temporary file beside the target (same folder, so the rename stays
on one file system; same suffix, so writers that infer the format from it still work),
then renames it over the target. On failure the temporary file is removed and the
target, if it existed, is left as it was. The file reaches the disk before the rename, and the
rename before the call returns (:func:`sync`), so a power cut leaves the old file or the new one,
never an empty one in its place.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path to write to; renamed over ``path`` when the block ends without error.

    ``path``'s folder is created if missing (:func:`frenbrdf.io.outputs.check_output_file` accepts a folder that
    can be created: the work done must not be lost for want of it).

    >>> with atomic_path("out.png") as temporary:   # doctest: +SKIP
    ...     figure.savefig(temporary)
    """
    path = Path(path)
    temporary = path.with_name(temporary_name(path.name))
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        yield temporary
        sync(temporary)
        os.replace(temporary, path)
        sync_entries(path.parent)
    except BaseException as error:
        with contextlib.suppress(OSError):  # e.g. a name too long to create is too long to remove
            temporary.unlink(missing_ok=True)
        raise_naming(error, temporary, path)


def sync(path: Path) -> None:
    """Flushes the file ``path``, or every file and folder under the folder ``path``, to the disk (``fsync``):
    what a rename is about to put in place must be there before the rename is."""
    if path.is_dir():
        for folder, _, files in os.walk(path):
            for name in files:
                if not (Path(folder) / name).is_symlink():  # what was written here, not what a link names
                    _fsync(Path(folder) / name)
            sync_entries(Path(folder))
    elif path.is_file():
        _fsync(path)


def sync_entries(folder: Path) -> None:
    """Flushes ``folder``'s entries (the names a rename changed) to the disk, where the system can (not on
    Windows: a folder cannot be opened there; the rename is durable by itself)."""
    with contextlib.suppress(OSError):
        _fsync(folder)


def _fsync(path: Path) -> None:
    descriptor = os.open(path, os.O_RDONLY)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)


def raise_naming(error: BaseException, hidden: Path, shown: Path) -> None:
    """Raises ``error``, its message naming ``shown`` where it named ``hidden`` (a temporary file or a staging
    folder a user never sees: a message names the path the user gave)."""
    if isinstance(error, OSError) and error.filename is not None and str(hidden) in str(error.filename):
        raise type(error)(error.errno, error.strerror, str(error.filename).replace(str(hidden), str(shown))) from None
    if isinstance(error, ValueError) and str(hidden) in str(error):
        try:
            renamed = type(error)(str(error).replace(str(hidden), str(shown)))
        except TypeError:  # a subclass with other arguments
            renamed = ValueError(str(error).replace(str(hidden), str(shown)))
        raise renamed from None
    raise error


#: The longest file name (in bytes) most file systems take; a temporary name is kept within it.
NAME_MAX = 255


def temporary_name(name: str) -> str:
    """A hidden name beside ``name`` that no other process or thread picks, with the same suffix, and no
    longer than :data:`NAME_MAX` bytes however long ``name`` is (a legal 250-byte name must not fail for its
    temporary's sake). The writer creates the file, so it gets the usual permissions (a file made by mkstemp
    would be private to its owner)."""
    suffix = Path(name).suffix or ".tmp"
    tail = f".{os.getpid()}-{uuid.uuid4().hex[:8]}{suffix}"
    room = NAME_MAX - 1 - len(tail.encode())
    stem = name.encode()[:max(room, 0)].decode(errors="ignore")  # cut on a character, not inside one
    return f".{stem}{tail}"


def write_text(path: str | os.PathLike, text: str) -> None:
    """Writes UTF-8 text atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


def save_json(path: str | os.PathLike, data) -> None:
    """Writes :func:`json_text` of ``data`` atomically."""
    write_text(path, json_text(data))


def json_text(data) -> str:
    """``data`` as JSON, indented and newline-terminated, as every file and ``--json`` print of frenbrdf has it.
    JSON has no NaN nor infinity: a float that is not finite (no value; the PSNR of two identical images) is written
    as ``null``, so that every JSON reader reads it."""
    return json.dumps(_finite_or_none(data), indent=2, allow_nan=False) + "\n"


def _finite_or_none(value):
    """``value`` with every float that is not finite replaced by None, in copies of its dicts, lists and tuples."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _finite_or_none(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_or_none(item) for item in value]
    return value


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
