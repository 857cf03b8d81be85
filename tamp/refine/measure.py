"""What the refinement reads from a simulation: the measuring function and its record.

The refinement (`tamp.refine.refinement`, Figueroa Heredia et al. 2018 §3) times every
phase's program by *executing* it (Fig. 3: the durations of Step 1 and Step 2 and the
delays of Fig. 5 are measured, not computed). It is given a `Measure`: a function that runs
a program under a communication architecture and returns a `Run`. The Drake workcell
provides one (`tamp.sim.refine.simulate.simulate`); tests give a model of their own. No
Drake here.

A `Run` holds the `Timeline` (when each behavior started and its event fired), the
collisions seen in the plant with the first time of each (Step 2 reverts a parallelization
that causes one), the rate searches of a tuning run (Fig. 5), the longest sensor wait per
robot, the sim, wall and CPU time it took, and the `Outcome`: what the run did to the
objects, judged against the scene's `Goal`s.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from tamp.fileio import Fields
from tamp.refine.architecture import Architecture
from tamp.refine.program import Program
from tamp.refine.steps import RateSearch
from tamp.refine.timeline import Timeline
from tamp.schema import spec

_QUANTITY = re.compile(r"^[A-Za-z][A-Za-z0-9_]*\.[A-Za-z0-9_]+$")


@dataclass(frozen=True)
class Goal:
    """What a scene's task must achieve, read on the plant at the end of a run: the measured
    ``quantity`` (``<object>.tilt``: rad between the object's up axis and the world's,
    ``<object>.rise``: m its origin rose, ``<object>.<joint>``: a revolute joint's angle) lies
    within [``at_least``, ``at_most``] (``at_most`` None: no upper bound); ``what`` says it
    in words. A scene file's ``goals`` entries are read into it (`tamp.schema`)."""

    quantity: str = spec(help="<object>.<joint>, <object>.tilt or <object>.rise")
    at_least: float = spec(help="the lowest value that meets the goal (rad or m)")
    what: str = spec(help="the goal in words")
    at_most: float | None = spec(None, help="the highest value that meets it (default: none)")

    def check(self, f: Fields) -> None:
        if not _QUANTITY.match(self.quantity):
            raise f.error("quantity", f"expected <object>.<joint|tilt|rise>, got {self.quantity!r}")
        if self.at_most is not None and self.at_most < self.at_least:
            raise f.error(
                "at_most", f"must be >= at_least ({self.at_least:g}), got {self.at_most:g}"
            )

    def met(self, value: float) -> bool:
        return value >= self.at_least and (self.at_most is None or value <= self.at_most)

    def bounds(self) -> str:
        """``>= 0.35`` or ``in [0.35, 1.2]``."""
        if self.at_most is None:
            return f">= {self.at_least:g}"
        return f"in [{self.at_least:g}, {self.at_most:g}]"

    def to_json(self) -> dict:
        out: dict = {"quantity": self.quantity, "at_least": self.at_least, "what": self.what}
        if self.at_most is not None:
            out["at_most"] = self.at_most
        return out


@dataclass(frozen=True)
class Outcome:
    """Measured quantities (name -> value) and the scene's goals judged against them."""

    values: dict[str, float] = field(default_factory=dict)
    goals: tuple[Goal, ...] = ()

    def _value(self, g: Goal) -> float:
        return self.values.get(g.quantity, math.nan)

    @property
    def achieved(self) -> bool:
        return all(g.met(self._value(g)) for g in self.goals)

    def failed(self) -> list[str]:
        """The goals not met, in words with the measured value."""
        out = []
        for g in self.goals:
            v = self._value(g)
            if g.met(v):
                continue
            if g.at_most is None or v < g.at_least or math.isnan(v):
                out.append(f"{g.what}: {g.quantity} = {v:.3f} < {g.at_least:g}")
            else:
                out.append(f"{g.what}: {g.quantity} = {v:.3f} > {g.at_most:g}")
        return out

    def summary(self) -> str:
        """The goals' quantities as measured, e.g. ``folding_chair.hinge 0.61 (>= 0.35) met``."""
        parts = [f"{g.quantity} {self._value(g):.3f} ({g.bounds()})" for g in self.goals]
        return ", ".join(parts) + (" met" if self.achieved else " NOT met") if parts else ""

    def to_json(self) -> dict:
        return {
            "values": {k: round(v, 4) for k, v in self.values.items()},
            "goals": [g.to_json() for g in self.goals],
            "achieved": self.achieved,
        }


@dataclass
class Run:
    """One measured execution of a program (module docstring)."""

    program: Program
    timeline: Timeline
    collisions: dict[tuple[str, str], float] = field(default_factory=dict)
    # the rate searches of a tuning run, keyed ``ROBOT.SENSOR`` (or ``ROBOT``: one per robot)
    searches: dict[str, RateSearch | None] = field(default_factory=dict)
    max_wait: dict[str, float] = field(default_factory=dict)  # robot -> longest sensor wait
    # ``ROBOT.SENSOR`` -> the longest wait of that trigger sensor's samples (s)
    sensor_waits: dict[str, float] = field(default_factory=dict)
    sim_time: float = 0.0
    wall_time: float = 0.0
    cpu_time: float = 0.0
    recording: str | None = None
    outcome: Outcome = field(default_factory=Outcome)  # what the objects did (the plant's)
    # robot -> (first time its gripper touched a task object, the object's body)
    touches: dict[str, tuple[float, str]] = field(default_factory=dict)
    diverged: str | None = None  # why the simulation stopped early (the solver failed)

    @property
    def finished(self) -> bool:
        return self.diverged is None and self.timeline.finished

    @property
    def task_time(self) -> float:
        return self.timeline.task_time

    @property
    def realtime_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    def found_rates(self) -> dict[str, float]:
        """Robot -> the lowest rate its searches found (Fig. 5), for the robots whose
        searches all ended."""
        out: dict[str, float] = {}
        unfinished: set[str] = set()
        for key, s in self.searches.items():
            robot = key.partition(".")[0]
            if s is None or not s.done or s.found is None:
                unfinished.add(robot)
            else:
                out[robot] = min(out.get(robot, s.found), s.found)
        return {r: v for r, v in out.items() if r not in unfinished}

    def sensor_rates(self) -> dict[str, float]:
        """``ROBOT.SENSOR`` -> the rate found watching that sensor (searches that ended)."""
        return {
            k: s.found
            for k, s in self.searches.items()
            if s is not None and s.done and s.found is not None
        }


class Measure(Protocol):
    """Executes ``program`` under ``architecture`` and measures it.

    ``tune``: the rate search of Fig. 5 runs online (each robot's command rate is raised
    probe by probe until its triggering sensors' samples are delayed; the `Run`'s
    ``searches`` hold the result). ``max_sim_time``: stop there (default: the measuring
    function's own limit). ``record``: write an animation of the run to this file (the
    `Run`'s ``recording``).

    A measuring function that already knows Fig. 5's result (a log's rates,
    `tamp.refine.predict.Predicting`) may also have ``rate_searches(program,
    architecture) -> dict[str, RateSearch]``; the refinement uses it instead of the
    architecture's queue model.
    """

    def __call__(
        self,
        program: Program,
        architecture: Architecture,
        *,
        tune: bool = False,
        max_sim_time: float | None = None,
        record: str | Path | None = None,
    ) -> Run: ...
