"""A normalised snapshot of every packaged SMP-MRO scenario as loaded, to compare loaders.

`tests.sim.snapshot.normalise` turns a loaded `SimScenario` into plain JSON data. The
snapshot in ``data/packaged_scenarios.json`` was written by the loader this one replaced;
``test_scenario_snapshot.py`` checks that the present loader agrees on every packaged file.
`recorded_layout` maps today's `SimScenario` onto the layout the snapshot was written in
(the same values; only where they sit differs).

Rewrite the snapshot (only when a packaged file changes on purpose)::

    python -m tests.sim.smp.snapshot
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tamp import scenarios
from tests.sim.snapshot import normalise, write

SNAPSHOT = Path(__file__).with_name("data") / "packaged_scenarios.json"


def packaged_files() -> list[Path]:
    """Every packaged SMP-MRO scenario (``tamp/scenarios/sim``), in name order."""
    return sorted((scenarios.ROOT / "sim").glob("*.yaml"))


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
    # the run's noisy-detector level came with the camera cell's tracking: never recorded
    conditions = dict(out["conditions"])
    assert conditions.pop("detector") is None  # a loaded file draws nothing: exact
    out["conditions"] = conditions
    # what reads the camera's views came with the learned mast detector: the oracle, as
    # every packaged file was read when recorded
    assert out.pop("detector") == "oracle"
    return out


def snapshot() -> dict[str, Any]:
    """Every packaged scenario, normalised, in the recorded layout, by file name."""
    from tamp.sim.smp.scenario import load_scenario

    return {p.name: recorded_layout(normalise(load_scenario(p))) for p in packaged_files()}


if __name__ == "__main__":
    write(SNAPSHOT, snapshot())
