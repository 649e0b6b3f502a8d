"""JSON that a user hands us (configs, charts, a run folder's records), read without trusting it.

Every JSON file frenbrdf reads goes through :func:`read_json`, and JSON text held inside
another file (a checkpoint's config) through :func:`parse_json`: a FIFO or a device is
refused before it is opened (it would block the reader for ever), an oversized file before
it is read, and what is read must be UTF-8 JSON (the message names the line and column of
the first error), nested at most :data:`MAX_DEPTH` deep (deeper nesting would end in a
RecursionError here or in the code that walks the result) and of the expected top-level type.
"""

from __future__ import annotations

import json
import os

from .paths import input_file

#: The most bytes :func:`read_json` reads by default (a training config is about 2 kB, a run's history
#: of thousands of epochs a few MB).
MAX_JSON_BYTES = 64 << 20
#: The deepest nesting of lists and objects accepted (frenbrdf's own files nest 4 deep).
MAX_DEPTH = 32

_NAMES: dict[type, str] = {dict: "a JSON object", list: "a JSON list"}


def read_json(path: str | os.PathLike, what: str = "JSON file", *, expect: type | None = dict,
              max_bytes: int = MAX_JSON_BYTES):
    """The JSON value of the file ``path``, checked.

    Parameters
    ----------
    path
        A regular file.
    what
        What the file is, for messages (``"training config"``).
    expect
        The type of the top-level value (``dict`` or ``list``); None: any.
    max_bytes
        The largest file accepted.

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        Nothing there, or a folder.
    ValueError
        A FIFO, socket or device; a larger file than ``max_bytes``; not UTF-8; not valid JSON (the message
        gives the line and column); nested deeper than :data:`MAX_DEPTH`; or not of type ``expect``.
    """
    path = input_file(path, what)
    with open(path, "rb") as file:
        data = file.read(max_bytes + 1)  # not stat's size alone: a file can grow between the two
    if len(data) > max_bytes:
        raise ValueError(f"{path}: larger than the {max_bytes:,} bytes a {what} may have")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not a {what}: not UTF-8 text (byte {error.start})") from None
    return parse_json(text, str(path), what, expect=expect)


def parse_json(text: str, where: str, what: str = "JSON", *, expect: type | None = dict):
    """The JSON value of ``text`` (read from ``where``, which messages name), checked as :func:`read_json` does."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"{where}: not valid JSON: {error.msg} at line {error.lineno}, column {error.colno}") from None
    except RecursionError:
        raise ValueError(f"{where}: its lists and objects nest too deeply for a {what} (at most {MAX_DEPTH} "
                         "levels)") from None
    except ValueError as error:  # an integer of more than 4300 digits (Python's limit): say so, without its advice
        why = "it holds an integer of more than 4300 digits" if "digits" in str(error) else str(error)
        raise ValueError(f"{where}: not a readable {what}: {why}") from None
    if depth(value) > MAX_DEPTH:
        raise ValueError(f"{where}: its lists and objects nest {depth(value)} levels deep; a {what} nests at most "
                         f"{MAX_DEPTH}")
    if expect is not None and not isinstance(value, expect):
        raise ValueError(f"{where}: a {what} must be {_NAMES.get(expect, expect.__name__)}, got "
                         f"{_kind(value)}")
    return value


def depth(value) -> int:
    """How deep lists and dicts nest in ``value`` (0 for a number or a string), without recursion."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, level = stack.pop()
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        if children is not None:
            deepest = max(deepest, level)
            stack.extend((child, level + 1) for child in children)
    return deepest


def _kind(value) -> str:
    """The JSON kind of a parsed value, for messages."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true or false"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    return _NAMES.get(type(value), type(value).__name__)

