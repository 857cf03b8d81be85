"""Normalised snapshots of loaded scenarios, to compare a loader with the one it replaced.

`normalise` turns a loaded scenario into plain JSON data: dataclasses as mappings of their
fields (``source``, a file's path, left out at every level), tuples and lists as lists, sets
as sorted lists, paths as strings, floats exact (JSON writes a float's shortest repr, which
reads back to the same float; NaN, e.g. the position of an object that has not appeared yet,
as the string ``"nan"``). Each cell's ``snapshot.py`` says which files it snapshots.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path, PurePath
from typing import Any

#: fields that say where a file was, not what it holds
EXCLUDED = ("source",)
#: fields added after the snapshot was written, left out while they hold their default (a
#: scenario's appearance of one object: `tamp.world.events.Appear.count`)
ADDED_DEFAULTS = {"count": 1}


def normalise(value: Any) -> Any:
    """``value`` as plain JSON data (module docstring)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: normalise(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if f.name not in EXCLUDED
            and not (f.name in ADDED_DEFAULTS and getattr(value, f.name) == ADDED_DEFAULTS[f.name])
        }
    if isinstance(value, dict):
        return {str(k): normalise(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [normalise(v) for v in value]
    if isinstance(value, set | frozenset):
        items = [normalise(v) for v in value]
        return sorted(items, key=lambda v: json.dumps(v, sort_keys=True))
    if isinstance(value, bool) or value is None or isinstance(value, int | str):
        return value
    if isinstance(value, PurePath):
        return str(value)
    number = float(value)  # a float or a NumPy scalar
    if math.isnan(number):
        return "nan"
    if not math.isfinite(number):
        raise ValueError(f"not a finite number: {value!r}")
    return number


def write(path: Path, data: dict[str, Any]) -> None:
    """Write a snapshot (sorted keys, one level of indent per line)."""
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}")
