"""What the SMP-MRO workcell knows about its models: the youBot-like robot and the objects.

Numbers that skills, IK and the scenario checks need (joint names, PD gains, footprints,
grasp heights), next to the SDFs they describe (``tamp/models/sdf/youbot.sdf``, ``bottle.sdf``,
``obstacle.sdf``). A scenario may declare object models of its own
(`tamp.sim.smp.object_models`); they are `ObjectKind` s too. No Drake import here, so
scenario validation runs without Drake.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

from tamp.sim.core.models import model_url, sdf_path


@dataclass(frozen=True)
class ObjectKind:
    """A graspable object model: its SDF, body name and the numbers skills need.

    ``grasp_height`` is where the fingers close, above the object's centre (a top grasp:
    the palm stays clear of the object's top). ``radius`` is the footprint radius used for
    overlap checks and base path planning; ``half_width`` is what the fingers close on.
    ``path``: the SDF of a model a scenario declares (None: the packaged
    ``tamp/models/sdf/<name>.sdf``); ``colour``: the RGBA its visuals get (None: the SDF's).
    """

    name: str
    body: str
    half_height: float
    radius: float
    half_width: float
    grasp_height: float
    mass: float
    path: Path | None = None
    colour: tuple[float, float, float, float] | None = None

    @property
    def sdf(self) -> Path:
        """The model's SDF file."""
        return sdf_path(self.name) if self.path is None else self.path

    @property
    def url(self) -> str:
        """The model's URL for Drake's parser (``package://`` or ``file://``)."""
        return model_url(self.name) if self.path is None else self.path.as_uri()


#: friction grasps hold an object this much lower than welds (m): both finger pads
#: (``youbot.sdf``) then press on its side, and the palm still clears its top by 5 mm
FRICTION_GRASP_DROP = 0.005


def grasped_kinds(kinds: dict[str, ObjectKind], grasp: str) -> dict[str, ObjectKind]:
    """The object kinds as the skills grasp them: friction grasps hold them lower."""
    if grasp != "friction":
        return dict(kinds)
    return {
        k: dataclasses.replace(v, grasp_height=v.grasp_height - FRICTION_GRASP_DROP)
        for k, v in kinds.items()
    }


OBJECT_KINDS: dict[str, ObjectKind] = {
    "bottle": ObjectKind("bottle", "bottle", 0.10, 0.035, 0.035, 0.06, 0.3),
    "obstacle": ObjectKind("obstacle", "obstacle", 0.075, 0.035 * math.sqrt(2), 0.035, 0.035, 0.4),
}


@dataclass(frozen=True)
class RobotSpec:
    """The youBot-like robot of ``tamp/models/sdf/youbot.sdf`` (SMP-MRO §V: KUKA youBot)."""

    url: str = model_url("youbot")
    base_joints: tuple[str, ...] = ("base_x", "base_y", "base_yaw")
    arm_joints: tuple[str, ...] = (
        "arm_joint_1",
        "arm_joint_2",
        "arm_joint_3",
        "arm_joint_4",
        "arm_joint_5",
    )
    finger_joints: tuple[str, ...] = ("finger_left_joint", "finger_right_joint")
    base_body: str = "base_link"
    palm_body: str = "gripper_palm"
    grasp_offset: float = 0.10  # grasp point on the palm's z axis (SDF frame grasp_frame)
    footprint_radius: float = 0.345  # half-diagonal of the 0.58 x 0.38 m base
    planning_radius: float = 0.45  # base + the arm's ready pose / a carried object 0.4 m ahead
    finger_open: float = 0.048
    # PD gains of the plant's PD-controlled actuators (SAP, implicit): (kp, kd) per joint kind
    base_gains: tuple[float, float] = (8000.0, 1500.0)
    yaw_gains: tuple[float, float] = (1500.0, 300.0)
    arm_gains: tuple[float, float] = (600.0, 40.0)
    finger_gains: tuple[float, float] = (400.0, 10.0)

    @property
    def joints(self) -> tuple[str, ...]:
        return self.base_joints + self.arm_joints + self.finger_joints

    def gains(self, joint: str) -> tuple[float, float]:
        if joint in ("base_x", "base_y"):
            return self.base_gains
        if joint == "base_yaw":
            return self.yaw_gains
        if joint in self.finger_joints:
            return self.finger_gains
        return self.arm_gains


ROBOT = RobotSpec()

#: The ready pose the robot drives in: palm down, grasp point 0.36 m ahead of the base
#: centre and 0.27 m up (from `ArmIK.solve`), a short move from any pre-grasp pose.
HOME_ARM = (0.0, 0.342, 1.111, 1.689, 0.0)


@dataclass(frozen=True)
class CameraSpec:
    """The youBot's RGB-D camera (``perception: camera``): on a mast at the back of the base,
    looking ahead and down over the arm, wide enough to see an area it drives to from
    1-2 m away and the object below the gripper at the stand-off distance. Renders one label
    + depth view per ``period`` (the budget: ~10 ms per image kind at this size)."""

    position: tuple[float, float, float] = (-0.20, 0.0, 1.10)  # in base_link's frame, m
    target: tuple[float, float, float] = (1.0, 0.0, 0.0)  # the point it looks at, base frame
    width: int = 256
    height: int = 192
    fov_y_deg: float = 70.0
    period: float = 0.2


CAMERA = CameraSpec()
