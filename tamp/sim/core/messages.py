"""Values that travel on the abstract ports between the LeafSystems (no Drake import).

Skills (every workcell):

    BtExecutor --SkillCommand--> skill controller --SkillStatus--> BtExecutor
    skill controller --GraspRequest--> grasp switch (weld constraints) and WorldStateEstimator

A command carries an id; the controller reports the status of the id it is working on,
so the executor never mistakes the result of an earlier skill for the current one.

Views (the cells with a camera, `tamp.sim.core.perception`):

    skills or pose estimator --ViewRequest--> Perception --Observation--> skills, controller

An `Observation` holds what a detector would give (per-class counts, `Detection`s, the
`TargetCrop` a grasp network reads, remembered instances hidden now as `Seen`), never a
plant pose. Every message is frozen; the port values return themselves from
``__deepcopy__``, so Drake's copies of port values and state cost nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from tamp.world.geometry import Area
from tamp.world.interface import Status

if TYPE_CHECKING:
    from pydrake.math import RigidTransform


@dataclass(frozen=True)
class SkillCommand:
    """Run ``name(args)`` (MoveTo, Pick, Place); ``cancel`` halts skill ``id``. id 0 = none.

    ``areas`` carries areas the tree found at run time (not in the demonstration) that the
    arguments name, so the controller knows where they are.
    """

    id: int = 0
    name: str = ""
    args: tuple[str, ...] = ()
    cancel: bool = False
    areas: tuple[Area, ...] = ()

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.args)})" if self.name else "<none>"

    def __deepcopy__(self, memo: dict) -> SkillCommand:
        return self  # immutable: Drake's copies of port values and state cost nothing


@dataclass(frozen=True)
class SkillStatus:
    """What the controller reports for command ``id`` (RUNNING until it ends, then sticky).

    ``cause``: on FAILURE, why, as one of `tamp.sim.core.outcome.CAUSES`, set by the skill
    where it fails (a run's cause is read from it, never parsed from ``detail``)."""

    id: int = 0
    status: Status = Status.SUCCESS
    detail: str = ""
    cause: str | None = None

    def __deepcopy__(self, memo: dict) -> SkillStatus:
        return self


@dataclass(frozen=True)
class GraspRequest:
    """The gripper's state: the weld it asks for and what it reports holding.

    ``obj``/``variant``: the weld to switch on (object ``obj``, weld 0 or 1), or none. Two
    welds exist per object (the object turned by 0 or pi about its axis relative to the
    fingers), so the wrist never turns more than 90 degrees to match the object.
    ``holding``: the object the gripper reports as held (the robot's grasp sensor): set once
    a pick has lifted the object and checked it on the plant, cleared once a place has put
    it down, let go and checked it. So ``IsGraspedObject``/``IsObjectAt`` change when the
    skill ends, not half-way through it (the reactive tree would otherwise halt the skill).
    """

    obj: str | None = None
    variant: int = 0
    holding: str | None = None

    def __deepcopy__(self, memo: dict) -> GraspRequest:
        return self


@dataclass(frozen=True)
class ViewRequest:
    """Ask for one view: id (0 = none), the workspace looked at (``side``: a name the cell
    chooses; perception remembers what it saw per name), what to find in it, and where the
    camera is (the robot's own kinematics of its measured joints, never a plant pose).
    Without ``camera_pose`` perception counts what it sees and remembers nothing."""

    id: int = 0
    side: str = ""
    target: str | None = None  # class to find for a grasp (then the colour image is rendered)
    #: with ``target``: the instance followed so far (perception's track id; None: choose
    #: one); without: the track a grasp just picked (the lift's view: is it in the gripper?)
    track: int | None = None
    camera_pose: RigidTransform | None = None  # X_WC when the view was asked for

    def __deepcopy__(self, memo: dict) -> ViewRequest:
        return self


@dataclass(frozen=True)
class Detection:
    """One instance in view: perception's track id (`tamp.sim.core.tracks`: the same
    instance keeps it across views; 0 when the view was not placed in the world), class,
    pixel area, centroid pixel, median depth."""

    track: int
    cls: str
    pixels: int
    u: float
    v: float
    depth: float


@dataclass(frozen=True)
class Seen:
    """An instance as perception last saw it: its track id, class, its world centroid (the
    median of its pixels back-projected through their depth: about the middle of its top),
    and where it lay on the table: the world x, y of its points, one per square of
    `tamp.sim.core.perception.FOOTPRINT_CELL` (empty when not known), which a place keeps
    clear of while it is hidden; ``misses``: the views of its workspace since then that
    showed its place plainly without it (`tamp.sim.core.perception.FORGET_VIEWS`)."""

    track: int
    cls: str
    position: tuple[float, float, float]
    footprint: tuple[tuple[float, float], ...] = ()
    misses: int = 0


@dataclass(frozen=True)
class TargetCrop:
    """The grasp network's input around the target: square crop (``origin`` = its top-left
    pixel in the full image) of colour, depth and the target's mask."""

    detection: Detection
    origin: tuple[int, int]
    rgb: np.ndarray
    depth: np.ndarray
    mask: np.ndarray


@dataclass(frozen=True)
class Observation:
    """The answer to view request ``id`` (rendered at sim ``time``)."""

    id: int = 0
    time: float = 0.0
    side: str = ""
    counts: dict[str, int] = field(default_factory=dict)
    detections: tuple[Detection, ...] = ()
    #: what is in the gripper (something nearer than hand_depth): the class of the track the
    #: grasp picked, or ``unknown``
    in_hand: tuple[str, ...] = ()
    target: TargetCrop | None = None
    #: object pixels on the table (full image, bool): the detections' masks and, in a
    #: place's views, every pixel above the floor that is not the gripper's (detected or not)
    occupied: np.ndarray | None = None
    #: remembered instances of this workspace not seen now because something hides them
    #: (counted in ``counts``, not in ``detections``)
    occluded: tuple[Seen, ...] = ()
    #: share of the image the held object covers (it hangs 6.5 cm beside the camera's axis
    #: and hides a patch of the workspace behind it)
    hand_cover: float = 0.0
    #: pixels that show the workspace's floor bare (full image, bool; from depth and the
    #: camera pose): where the view saw room for a place. None for a grasp's view (the
    #: descent's many views need none) and a view that was not placed
    floor: np.ndarray | None = None
    #: pixels the gripper's region covers (nearer than the hand depth: the held object)
    hidden: np.ndarray | None = None

    def __deepcopy__(self, memo: dict) -> Observation:
        return self  # immutable (arrays are read-only): Drake's state copies cost nothing
