"""A normalised snapshot of every packaged workcell scenario as loaded, to compare loaders.

`normalise` turns a loaded `CellScenario` into plain JSON data: dataclasses as mappings of
their fields (``source``, the file's path, left out), tuples as lists, floats exact (JSON
writes a float's shortest repr, which reads back to the same float). The snapshot in
``data/packaged_scenarios.json`` was written by the loader this one replaced;
``test_scenario.py`` checks that the present loader agrees on every packaged file.

Rewrite the snapshot (only when a packaged file changes on purpose)::

    python -m tests.sim.lots.snapshot
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

from tamp import scenarios

SNAPSHOT = Path(__file__).with_name("data") / "packaged_scenarios.json"
#: fields that say where the file was, not what it holds
EXCLUDED = ("source",)


def packaged_files() -> list[Path]:
    """Every packaged workcell scenario (``tamp/scenarios/lots_sim``), in name order."""
    return sorted((scenarios.ROOT / "lots_sim").glob("*.yaml"))


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
    if isinstance(value, bool) or value is None or isinstance(value, int | str):
        return value
    number = float(value)  # a float or a NumPy scalar
    if not math.isfinite(number):
        raise ValueError(f"not a finite number: {value!r}")
    return number


def snapshot() -> dict[str, Any]:
    """Every packaged scenario, normalised, by file name."""
    from tamp.sim.lots.scenario import load_cell_scenario

    return {p.name: normalise(load_cell_scenario(p)) for p in packaged_files()}


if __name__ == "__main__":
    SNAPSHOT.write_text(json.dumps(snapshot(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {SNAPSHOT}")
