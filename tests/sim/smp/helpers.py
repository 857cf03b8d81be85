"""Shared pieces of the simulation tests: small scenario files and run records."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from tamp.sim.smp.scenario import SIM_DIR

# One bottle at robot-frame (1.0, 0.0), one goal at (1.0, 0.7): a short pick-and-place.
ONE_BOTTLE_DEMO = """\
version: 1
name: one_bottle
frame:
  robot_position: [0.4, 0.0, -1.2]
area_radius: 0.15
robot:
  start: [0, 0, 0]
objects:
  - {id: O0, position: [0.4, 0.0, -0.2]}
steps:
  - {object: O0, to: [-0.3, 0.0, -0.2]}
"""


def write_one_bottle(tmp: Path, extra: str = "") -> Path:
    """A demonstration + simulation scenario with one bottle; returns the scenario path."""
    (tmp / "one_bottle_demo.yaml").write_text(ONE_BOTTLE_DEMO)
    scenario = tmp / "one_bottle.yaml"
    scenario.write_text(
        "version: 1\n"
        "name: one_bottle\n"
        "demonstration: one_bottle_demo.yaml\n"
        "executor: {max_sim_time: 60}\n"
        "workspace: {x: [-1.0, 2.5], y: [-1.5, 2.0]}\n" + extra
    )
    return scenario


def packaged(name: str) -> Path:
    return SIM_DIR / name


@dataclass
class Track:
    """Per-chunk plant poses of every object, to check that nothing jumps."""

    times: list[float] = field(default_factory=list)
    poses: list[dict] = field(default_factory=list)

    def max_jump(self, skip: dict[str, float] | None = None) -> tuple[float, str, float]:
        """Largest displacement of one object between consecutive chunks (m), which, when.

        ``skip``: object -> time at which a person put it down (that instant is not a jump
        of the simulation).
        """
        skip = skip or {}
        worst = (0.0, "", 0.0)
        for k in range(1, len(self.poses)):
            for uid, p in self.poses[k].items():
                q = self.poses[k - 1][uid]
                if uid in skip and abs(self.times[k] - skip[uid]) < 1e-6:
                    continue
                d = math.dist((p.x, p.y, p.z), (q.x, q.y, q.z))
                if d > worst[0]:
                    worst = (d, uid, self.times[k])
        return worst


def verified_runner(path: Path):
    """(scenario, system, runner) for a scenario file: planned, verified, built, not run."""
    from tamp.sim.smp.runner import SimRunner
    from tamp.sim.smp.scenario import load_scenario
    from tamp.sim.smp.simulate import prepare
    from tamp.sim.smp.station import build_station

    scenario = load_scenario(path)
    system = build_station(scenario, prepare(scenario).policy)
    return scenario, system, SimRunner(system)
