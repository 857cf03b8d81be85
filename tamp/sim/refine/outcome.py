"""What a run did to the objects, read on the plant at its end (not from the program).

`measure` returns, for every object of the scene, the tilt of its first body (the angle
between its up axis and the world's, rad), how far that body's origin rose (m) and the
angle of each of its revolute joints (the chair's ``hinge``), as a
`tamp.refine.measure.Outcome` that judges the scene's goals against them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from pydrake.multibody.tree import RevoluteJoint

from tamp.refine.measure import Goal, Outcome


def measure(
    plant, context, objects: dict, start_heights: dict[str, float], goals: Sequence[Goal]
) -> Outcome:
    """The `Outcome` of ``plant`` in ``context`` (``objects``: object name -> instance;
    ``start_heights``: object name -> its first body's height at the start), judged by
    ``goals``."""
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
    return Outcome(values, tuple(goals))


def start_heights(plant, context, objects: dict) -> dict[str, float]:
    """Each object's first body's height in ``context`` (the run's start)."""
    out = {}
    for name, m in objects.items():
        body = plant.get_body(plant.GetBodyIndices(m)[0])
        out[name] = float(plant.EvalBodyPoseInWorld(context, body).translation()[2])
    return out
