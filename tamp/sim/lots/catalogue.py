"""What the LOTS workcell is made of: the arm's numbers and the object classes (no Drake here).

The SDF files are in ``tamp/models/sdf`` (``package://tamp_models/sdf/lots_*.sdf``). The arm is a
Panda-like 7-DoF arm built from Franka's published kinematics (``lots_arm.sdf`` states the
numbers); the classes are the tools of Zhou et al. §V (model building, tower, Example 1) plus
the "new tools" a person brings in Fig. 9-10 (wrench, toy car).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.sim.core.models import model_url, sdf_path


@dataclass(frozen=True)
class ArmSpec:
    """Joint names, limits and controller gains of ``lots_arm.sdf``."""

    url: str = model_url("lots_arm")
    arm_joints: tuple[str, ...] = tuple(f"joint{i}" for i in range(1, 8))
    finger_joints: tuple[str, ...] = ("finger_left_joint", "finger_right_joint")
    base_frame: str = "link0"
    hand_body: str = "hand"
    tcp_frame: str = "tcp"
    camera_frame: str = "camera"
    finger_bodies: tuple[str, ...] = ("finger_left", "finger_right")
    #: Franka's datasheet limits (rad, rad/s); the SDF carries the same values.
    lower: tuple[float, ...] = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
    upper: tuple[float, ...] = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
    max_velocity: tuple[float, ...] = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
    #: Franka's acceleration limits (rad/s^2), used by differential IK.
    max_acceleration: tuple[float, ...] = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)
    finger_max: float = 0.04  # per finger: 8 cm opening
    #: joint-space PD of the plant's actuators (implicit in SAP), (kp, kd)
    arm_gains: tuple[float, float] = (1500.0, 80.0)
    wrist_gains: tuple[float, float] = (300.0, 15.0)  # joints 5-7 carry less inertia
    finger_gains: tuple[float, float] = (2000.0, 20.0)

    @property
    def joints(self) -> tuple[str, ...]:
        return self.arm_joints + self.finger_joints

    def gains(self, joint: str) -> tuple[float, float]:
        if joint in self.finger_joints:
            return self.finger_gains
        return self.wrist_gains if joint in ("joint5", "joint6", "joint7") else self.arm_gains


ARM = ArmSpec()

#: Franka's "ready" configuration: TCP 0.307 m ahead of the base, 0.487 m up, pointing down.
READY = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)


@dataclass(frozen=True)
class Footprint:
    """The axis-aligned box around an object's collision boxes, in the object's frame."""

    xmin: float
    xmax: float
    ymin: float
    ymax: float
    top: float

    @property
    def span(self) -> float:
        """The footprint's diagonal (m): no two points of the object lie farther apart on
        the table."""
        return math.hypot(self.xmax - self.xmin, self.ymax - self.ymin)

    def corners(self, x: float, y: float, yaw: float) -> np.ndarray:
        """The footprint's four corners (4 x 2) for the object at (x, y, yaw) on the table."""
        c, s = math.cos(yaw), math.sin(yaw)
        pts = np.array(
            [
                [self.xmin, self.ymin],
                [self.xmax, self.ymin],
                [self.xmax, self.ymax],
                [self.xmin, self.ymax],
            ]
        )
        return pts @ np.array([[c, s], [-s, c]]) + [x, y]


def read_footprint(path: Path) -> Footprint:
    """The box around all geometry (visual and collision) of an object SDF, in its frame;
    a cylinder or sphere counts as its bounding box. ValueError for other geometry (a mesh:
    its extent is not in the SDF) or no geometry at all."""
    return _footprint(ET.parse(path).getroot())


def _footprint(root: ET.Element) -> Footprint:
    pts = []
    for geo_parent in [*root.iter("visual"), *root.iter("collision")]:
        pose = [float(v) for v in (geo_parent.findtext("pose") or "0 0 0 0 0 0").split()]
        half = _half_extent(geo_parent)
        R = _rpy(*pose[3:])
        for corner in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T:
            pts.append(R @ (corner * half) + pose[:3])
    if not pts:
        raise ValueError("the model has no visual or collision geometry")
    p = np.array(pts)
    lo, hi = p.min(axis=0), p.max(axis=0)
    return Footprint(*(round(float(v), 6) for v in (lo[0], hi[0], lo[1], hi[1], hi[2])))


def _half_extent(geo_parent: ET.Element) -> np.ndarray:
    """Half the sides of the box around one visual's or collision's geometry."""
    box = geo_parent.findtext("geometry/box/size")
    if box is not None:
        return np.array([float(v) for v in box.split()]) / 2
    r = geo_parent.findtext("geometry/cylinder/radius")
    if r is not None:
        length = float(geo_parent.findtext("geometry/cylinder/length") or "nan")
        return np.array([float(r), float(r), length / 2])
    r = geo_parent.findtext("geometry/sphere/radius")
    if r is not None:
        return np.full(3, float(r))
    kinds = [g.tag for g in geo_parent.findall("geometry/*")] or ["none"]
    raise ValueError(
        f"{geo_parent.tag} {geo_parent.get('name')!r}: {kinds[0]} geometry has no footprint "
        "here (use boxes, cylinders and spheres)"
    )


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


#: the colour of an object whose SDF gives none
DEFAULT_RGB = (0.6, 0.6, 0.6)


@dataclass(frozen=True)
class ObjectClass:
    """A class of graspable objects: its SDF and what perception and skills need to know.

    The object's origin is on the table under its centre; ``footprint`` is read from its SDF
    (one source of truth), ``body`` is the SDF's one link. ``colour`` is the SDF's primary
    colour (the text of its ``<diffuse>``), which each instance replaces with one of
    ``palette`` so that instances of a class look different. ``sdf`` is the file (its text
    is what the plant parses, `tamp.sim.lots.plant.object_sdf`), ``url`` how Drake names it.
    The packaged classes are `CLASSES`; a scenario may declare more (`read_object_class`).
    """

    name: str
    colour: str
    palette: tuple[tuple[float, float, float], ...]
    footprint: Footprint
    sdf: Path
    url: str
    body: str

    @property
    def height(self) -> float:
        return self.footprint.top


def read_object_class(
    name: str,
    sdf: Path,
    url: str,
    palette: tuple[tuple[float, float, float], ...] = (),
    colour: str | None = None,
) -> ObjectClass:
    """The class of the objects of SDF file ``sdf``: its one model's one link, footprint and
    primary colour (``colour``, else the first visual's ``<diffuse>``); ``palette`` (empty:
    that colour alone). ValueError saying what the file lacks."""
    try:
        root = ET.parse(sdf).getroot()
    except (ET.ParseError, UnicodeDecodeError) as exc:
        raise ValueError(f"not an SDFormat file: {exc}") from None
    models = root.findall("model") if root.tag == "sdf" else []
    if len(models) != 1:
        raise ValueError(f"expected an <sdf> file with one <model>, found {len(models)}")
    links = [link.get("name") or "" for link in models[0].findall("link")]
    if len(links) != 1:
        raise ValueError(f"an object is one rigid body: the model has {len(links)} links")
    if colour is None:
        colour = (models[0].findtext("link/visual/material/diffuse") or "").strip()
    if not palette:
        rgb = [float(v) for v in colour.split()[:3]] if colour else []
        palette = (tuple(rgb) if len(rgb) == 3 else DEFAULT_RGB,)
    return ObjectClass(name, colour, tuple(palette), _footprint(models[0]), sdf, url, links[0])


def _cls(name: str, colour: str, *palette: tuple[float, float, float]) -> ObjectClass:
    file = f"lots_{name}"
    return read_object_class(name, sdf_path(file), model_url(file), palette, colour)


CLASSES: dict[str, ObjectClass] = {
    c.name: c
    for c in (
        _cls("hammer", "0.80 0.55 0.25 1", (0.8, 0.55, 0.25), (0.55, 0.35, 0.2), (0.9, 0.7, 0.45)),
        _cls("saw", "0.85 0.20 0.15 1", (0.85, 0.2, 0.15), (0.2, 0.2, 0.2), (0.95, 0.5, 0.1)),
        _cls(
            "scissors", "0.20 0.45 0.85 1", (0.2, 0.45, 0.85), (0.1, 0.75, 0.8), (0.45, 0.25, 0.8)
        ),
        _cls("toy_car", "0.95 0.75 0.10 1", (0.95, 0.75, 0.1), (0.85, 0.1, 0.5), (0.3, 0.8, 0.3)),
        _cls("wrench", "0.55 0.55 0.60 1", (0.55, 0.55, 0.6), (0.3, 0.35, 0.5), (0.6, 0.4, 0.4)),
        _cls("screw", "0.70 0.70 0.20 1", (0.7, 0.7, 0.2), (0.75, 0.5, 0.2), (0.5, 0.6, 0.3)),
        _cls(
            "screwdriver", "0.20 0.70 0.30 1", (0.2, 0.7, 0.3), (0.85, 0.25, 0.25), (0.2, 0.3, 0.8)
        ),
        _cls("bottom", "0.60 0.25 0.70 1", (0.6, 0.25, 0.7), (0.35, 0.2, 0.55), (0.8, 0.45, 0.85)),
        _cls("body", "0.25 0.70 0.70 1", (0.25, 0.7, 0.7), (0.15, 0.5, 0.55), (0.5, 0.85, 0.8)),
        _cls("peak", "0.90 0.40 0.60 1", (0.9, 0.4, 0.6), (0.95, 0.6, 0.3), (0.7, 0.2, 0.4)),
    )
}

TABLE_URL = model_url("lots_table")
WASTE_BASKET_URL = model_url("lots_waste_basket")
TRAY_URL = model_url("lots_tray")

#: The label image value of the scripted person's hand (``lots_person_hand.sdf``): every
#: pixel that shows the hand carries it. Object pixels carry their body index (always far
#: below this), so the hand is never taken for an object, and a safety monitor finds the hand
#: in the wrist camera's label image by this one value.
HAND_LABEL = 1000


@dataclass(frozen=True)
class PersonSpec:
    """The scripted person's hand (``lots_person_hand.sdf``) and where it works from.

    The hand moves on three prismatic joints (world x, y, z) driven by PD actuators; it parks
    at ``park`` (beyond the table's far edge, out of every camera view) and takes the objects
    it brings in from the staging shelf beside the table (``shelf_center``, ``shelf_size``;
    its top is level with the table), where it also puts the objects it takes away.
    """

    url: str = model_url("lots_person_hand")
    joints: tuple[str, ...] = ("person_x_joint", "person_y_joint", "person_z_joint")
    hand_body: str = "person_hand"
    gains: tuple[float, float] = (4000.0, 200.0)  # (kp N/m, kd N s/m), implicit in SAP
    park: tuple[float, float, float] = (1.3, 0.0, 0.35)
    shelf_center: tuple[float, float] = (1.1, 0.0)
    shelf_size: tuple[float, float] = (0.26, 1.2)
    #: the light curtain between the robot's side of the table and the shelf: a hand nearer
    #: the robot than this x (m) is inside the workcell (the shelf's inner edge is 0.97 m)
    curtain_x: float = 0.92
    speed: float = 1.2  # mean hand speed of a move (m/s)
    transit: float = 0.24  # height of the hand over the table between workspaces (m)


PERSON = PersonSpec()
