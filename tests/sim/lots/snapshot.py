"""A normalised snapshot of every packaged workcell scenario as loaded, to compare loaders.

`tests.sim.snapshot.normalise` turns a loaded `CellScenario` into plain JSON data. The
snapshot in ``data/packaged_scenarios.json`` was written by the loader this one replaced;
``test_scenario.py`` checks that the present loader agrees on every packaged file.

Rewrite the snapshot (only when a packaged file changes on purpose)::

    python -m tests.sim.lots.snapshot
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tamp import scenarios
from tests.sim.snapshot import normalise, write

SNAPSHOT = Path(__file__).with_name("data") / "packaged_scenarios.json"


def packaged_files() -> list[Path]:
    """Every packaged workcell scenario (``tamp/scenarios/lots_sim``), in name order."""
    return sorted((scenarios.ROOT / "lots_sim").glob("*.yaml"))


def snapshot() -> dict[str, Any]:
    """Every packaged scenario, normalised, by file name."""
    from tamp.sim.lots.scenario import load_cell_scenario

    return {p.name: normalise(load_cell_scenario(p)) for p in packaged_files()}


if __name__ == "__main__":
    write(SNAPSHOT, snapshot())
