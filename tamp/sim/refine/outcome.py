"""What a run did to the objects, read on the plant at its end (not from the program).

`measure` returns, for every object of the scene, the tilt of its first body (the angle
between its up axis and the world's, rad), how far that body's origin rose (m) and the
angle of each of its revolute joints (the chair's ``hinge``); `Outcome` holds them with the
scene's goals (`tamp.sim.refine.scene.GOALS`) judged against them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pydrake.multibody.tree import RevoluteJoint

from tamp.sim.refine.scene import GOALS, Goal


@dataclass(frozen=True)
class Outcome:
    """Measured quantities (name -> value) and the scene's goals."""

    values: dict[str, float] = field(default_factory=dict)
    goals: tuple[Goal, ...] = ()

    @property
    def achieved(self) -> bool:
        return all(g.met(self.values.get(g.quantity, -math.inf)) for g in self.goals)

    def failed(self) -> list[str]:
        """The goals not met, in words with the measured value."""
        return [
            f"{g.what}: {g.quantity} = {self.values.get(g.quantity, math.nan):.3f} < {g.at_least:g}"
            for g in self.goals
            if not g.met(self.values.get(g.quantity, -math.inf))
        ]

    def summary(self) -> str:
        """The goals' quantities as measured, e.g. ``folding_chair.hinge 0.61 (>= 0.35) met``."""
        parts = [
            f"{g.quantity} {self.values.get(g.quantity, math.nan):.3f} (>= {g.at_least:g})"
            for g in self.goals
        ]
        return ", ".join(parts) + (" met" if self.achieved else " NOT met") if parts else ""

    def to_json(self) -> dict:
        return {
            "values": {k: round(v, 4) for k, v in self.values.items()},
            "goals": [
                {"quantity": g.quantity, "at_least": g.at_least, "what": g.what} for g in self.goals
            ],
            "achieved": self.achieved,
        }


def measure(plant, context, objects: dict, start_heights: dict[str, float], scene: str):
    """The `Outcome` of ``plant`` in ``context`` (``objects``: model name -> instance;
    ``start_heights``: model name -> its first body's height at the start)."""
    values: dict[str, float] = {}
    for name, m in objects.items():
        body = plant.get_body(plant.GetBodyIndices(m)[0])
        X = plant.EvalBodyPoseInWorld(context, body)
        up = float(X.rotation().matrix()[2, 2])
        values[f"{name}.tilt"] = math.acos(max(-1.0, min(1.0, up)))
        values[f"{name}.rise"] = float(X.translation()[2]) - start_heights[name]
        for index in plant.GetJointIndices(m):
            joint = plant.get_joint(index)
            if isinstance(joint, RevoluteJoint):
                values[f"{name}.{joint.name()}"] = float(joint.get_angle(context))
    return Outcome(values, GOALS.get(scene, ()))


def start_heights(plant, context, objects: dict) -> dict[str, float]:
    """Each object's first body's height in ``context`` (the run's start)."""
    out = {}
    for name, m in objects.items():
        body = plant.get_body(plant.GetBodyIndices(m)[0])
        out[name] = float(plant.EvalBodyPoseInWorld(context, body).translation()[2])
    return out
