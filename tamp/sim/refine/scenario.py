"""What the refinement workcell holds: the Pioneer-like robots' joints and the scenes' objects.

No Drake import: the numbers here are read by the builder (`tamp.sim.refine.builder`) and
by the executor, which turns a program's section motions into joint setpoints.

Robots (``models/sdf/pioneer_lift.sdf``, ``pioneer_parallel.sdf``, Fig. 7): the base moves
on planar joints (x, y, yaw) driven along its heading or about the vertical axis, the lift
lever pitches (``arm_pitch``, up positive) and two prismatic paddles/fingers open and close
(each 0 .. 0.08 m from the centre line; a program's gripper motion changes the *opening*,
the sum of both). Every joint is a PD-controlled actuator of the plant (SAP, implicit).

Scenes (Fig. 9): Robot 1 starts on the -x side facing +x, Robot 2 on the +x side facing -x
(the programs' ``start``), the object between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

JOINTS = (
    "base_x",
    "base_y",
    "base_yaw",
    "arm_pitch",
    "finger_left_joint",
    "finger_right_joint",
)
#: (kp, kd) of each joint's PD actuator
GAINS = {
    "base_x": (6000.0, 1200.0),
    "base_y": (6000.0, 1200.0),
    "base_yaw": (800.0, 150.0),
    "arm_pitch": (400.0, 30.0),
    "finger_left_joint": (600.0, 10.0),
    "finger_right_joint": (600.0, 10.0),
}
FINGER_MAX = 0.08  # m from the centre line, per finger
OPENING_START = 2 * FINGER_MAX  # both grippers start fully open
#: bodies whose contact with anything is a collision (the gripper's contacts are intended)
CHASSIS_BODIES = ("base_link", "arm_link")
GRIPPER_MOUNT = "gripper_mount"  # the welded joint whose reaction force is the force sensor


@dataclass(frozen=True)
class Placement:
    """One object of a scene: model ``model`` at ``(x, y, z, yaw)``; ``fixed`` welds it."""

    model: str
    x: float
    y: float
    z: float
    yaw: float = 0.0
    fixed: bool = False


#: Scene name -> its objects (the names the loader accepts, `tamp.refine.loader.SCENES`).
SCENES: dict[str, tuple[Placement, ...]] = {
    # briefcase lying flat, its 0.35 m side along the robots' line, its handle towards Robot 1
    "flip_briefcase": (Placement("briefcase", 0.0, 0.0, 0.06, math.pi / 2),),
    # the scale's carrying grip towards Robot 1
    "flip_scale": (Placement("scale", 0.0, 0.0, 0.025, math.pi / 2),),
    # the table is fixed; the scale lies on its top (0.28 m), overhanging its -x edge by
    # 0.10 m on Robot 1's side (the fork gets under it there)
    "lift_scale": (
        Placement("table", 0.10, 0.0, 0.0, fixed=True),
        Placement("scale", 0.0, 0.0, 0.305),
    ),
    # the lift scene's table alone (`table_collision.yaml`: Step 2's collision check)
    "table": (Placement("table", 0.10, 0.0, 0.0, fixed=True),),
    # the folded chair, free on the floor, its frames across the robots' line; Robot 1's
    # fork hooks the latch under frame_b's handle bar (models/sdf/folding_chair.sdf)
    "open_chair": (Placement("folding_chair", 0.0, 0.0, 0.0),),
}


@dataclass(frozen=True)
class Goal:
    """What a scene's task must achieve, read on the plant at the end of a run: the measured
    ``quantity`` (`Outcome` names: ``<model>.tilt`` rad between the object's up axis and the
    world's, ``<model>.rise`` m its origin rose, ``<model>.<joint>`` a joint's angle) is at
    least ``at_least``."""

    quantity: str
    at_least: float
    what: str

    def met(self, value: float) -> bool:
        return value >= self.at_least


#: Scene name -> its goals (all must hold for the task to succeed).
GOALS: dict[str, tuple[Goal, ...]] = {
    # a flip: turned about a horizontal axis past its balance point over the far edge
    # (briefcase 1.24 rad, scale 1.41 rad): standing on its side (pi / 2) or on its other face
    "flip_briefcase": (Goal("briefcase.tilt", 1.45, "the briefcase turned over"),),
    "flip_scale": (Goal("scale.tilt", 1.45, "the scale turned over"),),
    "lift_scale": (
        Goal("scale.tilt", 0.15, "the scale tilted up off the table"),
        Goal("scale.rise", 0.02, "the scale's centre rose"),
    ),
    "open_chair": (Goal("folding_chair.hinge", 0.35, "the chair opened at its hinge"),),
}
