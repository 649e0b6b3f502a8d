"""Configs as JSON: nested dataclasses to plain dicts and back, refusing unknown keys.

Every config of the package is a dataclass with a docstring under each field; a run
saves its config as JSON and these two functions make the round trip.
"""

from __future__ import annotations

import dataclasses
import json


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
    for name, value in data.items():
        factory = fields[name].default_factory
        default = factory() if factory is not dataclasses.MISSING else None
        if dataclasses.is_dataclass(default):
            values[name] = from_dict(type(default), value, f"{where}.{name}")
        else:
            values[name] = tuple(value) if isinstance(value, list) else value
    return cls(**values)


def merge(base: dict, update: dict) -> dict:
    """``base`` with ``update`` laid over it, nested dicts merged key by key."""
    merged = dict(base)
    for key, value in update.items():
        nested = isinstance(value, dict) and isinstance(base.get(key), dict)
        merged[key] = merge(base[key], value) if nested else value
    return merged
