"""A normalised snapshot of every packaged SMP-MRO scenario as loaded, to compare loaders.

`normalise` turns a loaded `SimScenario` into plain JSON data: dataclasses as mappings of
their fields (``source``, a file's path, left out at every level), tuples and lists as
lists, sets as sorted lists, floats exact (JSON writes a float's shortest repr, which reads
back to the same float; NaN, the position of an object that has not appeared yet, as the
string ``"nan"``). The snapshot in ``data/packaged_scenarios.json`` was written by the
loader this one replaced; ``test_scenario_snapshot.py`` checks that the present loader
agrees on every packaged file. `recorded_layout` maps today's `SimScenario` onto the layout
the snapshot was written in (the same values; only where they sit differs).

Rewrite the snapshot (only when a packaged file changes on purpose)::

    python -m tests.sim.smp.snapshot
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path, PurePath
from typing import Any

from tamp import scenarios

SNAPSHOT = Path(__file__).with_name("data") / "packaged_scenarios.json"
#: fields that say where a file was, not what it holds
EXCLUDED = ("source",)


def packaged_files() -> list[Path]:
    """Every packaged SMP-MRO scenario (``tamp/scenarios/sim``), in name order."""
    return sorted((scenarios.ROOT / "sim").glob("*.yaml"))


def normalise(value: Any) -> Any:
    """``value`` as plain JSON data (module docstring)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: normalise(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if f.name not in EXCLUDED
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


#: sections of today's `SimScenario` whose fields sat at its top level when it was recorded
FLATTENED = ("planner", "plant", "executor")
#: `ObjectKind` fields added since: a packaged model's are None (its file is the packaged
#: one, its colour the SDF's)
ADDED_KIND_FIELDS = ("path", "colour")


def recorded_layout(scenario: dict[str, Any]) -> dict[str, Any]:
    """A normalised `SimScenario` in the snapshot's layout (module docstring)."""
    out = {k: v for k, v in scenario.items() if k not in FLATTENED}
    for section in FLATTENED:
        out.update(scenario[section])
    objects = []
    for o in scenario["objects"]:
        kind = {k: v for k, v in o["kind"].items() if k not in ADDED_KIND_FIELDS}
        if any(o["kind"].get(k) is not None for k in ADDED_KIND_FIELDS):
            kind["added"] = {k: o["kind"][k] for k in ADDED_KIND_FIELDS}  # never recorded
        objects.append({**o, "kind": kind})
    out["objects"] = objects
    return out


def snapshot() -> dict[str, Any]:
    """Every packaged scenario, normalised, in the recorded layout, by file name."""
    from tamp.sim.smp.scenario import load_scenario

    return {p.name: recorded_layout(normalise(load_scenario(p))) for p in packaged_files()}


if __name__ == "__main__":
    SNAPSHOT.parent.mkdir(exist_ok=True)
    SNAPSHOT.write_text(json.dumps(snapshot(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {SNAPSHOT}")
