"""Configs as JSON: nested dataclasses to plain dicts and back, refusing unknown keys.

Every config of the package is a dataclass with a docstring under each field; a run
saves its config as JSON and these two functions make the round trip.
"""

from __future__ import annotations

import dataclasses
import json
import numbers
import types
import typing

#: The largest seed (2³² − 1): every generator the package seeds (numpy's, torch's) accepts it, and offsets added to it.
MAX_SEED = (1 << 32) - 1


def to_dict(config) -> dict:
    """A (nested) dataclass as a JSON-ready dict (tuples become lists)."""
    return json.loads(json.dumps(dataclasses.asdict(config)))


def from_dict(cls, data: dict, where: str = "config"):
    """Builds a (nested) dataclass from a dict, refusing unknown keys by name.

    ``where`` names the source in error messages (a file, or ``config.loss``).
    """
    if not isinstance(data, dict):
        raise ValueError(f"{where} must be a JSON object, got {type(data).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} in {where}; valid keys: {sorted(fields)}")
    values = {}
    hints = typing.get_type_hints(cls)
    for name, value in data.items():
        factory = fields[name].default_factory
        default = factory() if factory is not dataclasses.MISSING else None
        if dataclasses.is_dataclass(default):
            values[name] = from_dict(type(default), value, f"{where}.{name}")
        else:
            values[name] = checked_value(value, hints[name], f"{where}: {name}")
    return cls(**values)


def checked_value(value, hint, where: str):
    """``value`` checked against a field's type (``int``, ``float``, ``str``, ``bool``, ``X | None``,
    ``tuple[X, ...]``, ``tuple[X, Y]``, ``dict[K, V]``, a dataclass); lists become tuples. A wrong type is a ValueError naming the setting:
    ``"1"`` is not an integer, 1.5 is not an integer, ``true`` is not a number.

    A config read from a file meets here what the code assumes, before any work is done.
    """
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):  # e.g. an item of tuple[EncoderConfig, ...]
        return value if isinstance(value, hint) else from_dict(hint, value, where)
    if origin is dict:  # a mapping such as dict[str, float]: a JSON object, keys and values checked
        if not isinstance(value, dict):
            raise ValueError(f"{where} must be a JSON object, got {value!r}")
        key_hint, value_hint = args or (str, typing.Any)
        return {checked_value(key, key_hint, f"{where} key"): checked_value(item, value_hint, f"{where}[{key!r}]")
                for key, item in value.items()}
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        return checked_value(value, options[0], where) if len(options) == 1 else value
    if origin is tuple:
        if isinstance(value, str) and args and args[-1] is Ellipsis and args[0] is str:
            return (value,)  # one glob pattern for tuple[str, ...]
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{where} must be a list, got {value!r}")
        if not args:  # a bare ``tuple``: its items unchecked
            return tuple(value)
        if args[-1] is Ellipsis:
            return tuple(checked_value(item, args[0], f"{where}[{i}]") for i, item in enumerate(value))
        if len(value) != len(args):
            raise ValueError(f"{where} must be a list of {len(args)} values, got {value!r}")
        return tuple(checked_value(item, arg, f"{where}[{i}]")
                     for i, (item, arg) in enumerate(zip(value, args, strict=True)))
    if hint is bool:
        if not isinstance(value, bool):
            raise ValueError(f"{where} must be true or false, got {value!r}")
    elif hint is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise ValueError(f"{where} must be an integer, got {value!r}")
        return int(value)
    elif hint is float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ValueError(f"{where} must be a number, got {value!r}")
        return float(value)
    elif hint is str and not isinstance(value, str):
        raise ValueError(f"{where} must be a string, got {value!r}")
    return value


def merge(base: dict, update: dict, cls=None) -> dict:
    """``base`` with ``update`` laid over it, nested dicts merged key by key.

    ``cls``: the config dataclass the dicts describe. With it, only its nested config sections are merged key by
    key; a field that is itself a mapping (e.g. ``sampling.patterns``, pattern → weight) is replaced whole, so that
    ``{"patterns": {"uniform": 1}}`` means the uniform pattern alone, not the default's patterns and it.
    """
    merged = dict(base)
    sections = _sections(cls) if cls is not None else None
    for key, value in update.items():
        nested = isinstance(value, dict) and isinstance(base.get(key), dict)
        if nested and sections is not None and key not in sections:
            nested = False
        merged[key] = merge(base[key], value, sections[key] if sections is not None else None) if nested else value
    return merged


def _sections(cls) -> dict:
    """The fields of a config dataclass that are config dataclasses themselves, with their classes."""
    sections = {}
    for f in dataclasses.fields(cls):
        default = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
        if dataclasses.is_dataclass(default):
            sections[f.name] = type(default)
    return sections
