"""Training and test data of the object detector: Drake renders of the workcells' objects.

Zhou et al. (IEEE T-ASE 2023, §IV-V) detect the workcell's objects with a network trained on
camera images; here the images are Drake renders (`tamp.grasp.synthetic.SceneRenderer`, the
renderer of the grasp data) and the targets are the renders' label images turned into
per-pixel classes:

- ``background`` (nothing, or the gripper: the wrist camera sits 6.5 cm beside the approach
  axis and its field of view misses the fingers, and the arm's kinematics knows where they
  are anyway; the detector never has to report it),
- ``table`` (the table top and the coloured mats on it),
- one class per catalogue object (the cell hands the catalogue in: `SegClass`),
- ``unknown``: objects of shapes the catalogue does not have (boxes, standing cylinders,
  balls, mugs, knobs, bars, compounds of primitives; lying cylinders, plates and L-shapes in
  the test scenes only), so that an object the detector was not trained on is reported as
  ``unknown`` rather than as the nearest task class,
- ``hand``: the person's hand and forearm, its own class, so that a hand reaching into a
  workspace is never counted as an object (safety does not need the class: it is decided
  from depth; the class keeps the hand out of the counts and lets a recording show it).

Scenes (`sample_scene`): one to six catalogue objects at random positions, yaws and colours
(a class's palette, jittered, or any colour in one of five), clutter that touches (half of
the objects are pushed against one already placed until their footprints touch), zero to two
unknown objects, coloured mats, the person's hand in one scene of three (hovering 2-25 cm
above the table), one or two directional lights of random direction, intensity and tint.
The scenes the LOTS narratives show besides (`DataConfig` sets their shares; a scene's kinds
are its `Scene.tags`):

- ``stack`` (Fig. 10's tower, `tamp.sim.lots.stack`): two or three of the tower's classes
  (`STACK_CLASSES`) stacked, each level's underside on the top of the one below, centred
  within 1.5 cm and turned by up to 45 degrees; one tower in four carries another object on
  top (the person's interference adds and moves tower parts);
- ``tray`` (Example 1's basket in W^B): the tray (`Tray`, read from its SDF; labelled
  ``table``, never an instance) with one to three objects on its floor, touching each other
  or its walls; the detector is given what the cell gives it there (its floor as the support
  plane, its walls' pixels left out: `view_fixtures`);
- ``across``: a long object (a hammer, a saw, a screwdriver ...) lying across a lower one,
  one end on the surface, tilted until it rests on the other's edge (`lying_across`).

Views (`sample_cameras`): the wrist camera above a random object (a stack or the object lying
across, in two views of three, when the scene has one) at 0.2-0.5 m (and at least 12 cm
above the tallest object), tilted up to 20 degrees, at a random roll about its axis; in one
scene of four the first view also shows an object held in the gripper (the gripper at the
camera's mount, the object between the fingers, as the arm carries it).

Object-wise split: scenes are assigned to train or test by their index (`split_of`); the
unknown objects of test scenes are of shapes never rendered in training
(`UNKNOWN_TEST_KINDS`), and the split is recorded in ``dataset.json`` and, by training, in
the weights file. Everything of scene ``i`` is drawn from ``default_rng((seed, i))``.

Layout: ``OUT/dataset.json`` (classes, configuration, split) and ``OUT/scene_NNNNN.npz``
with the scene's views stacked: ``rgb`` (V, H, W, 3) uint8, ``depth`` (V, H, W) float32
metres (0 = no return), ``cls`` (V, H, W) uint8 class indices, ``inst`` (V, H, W) uint8
instance ids (0 = none; an id per object body), ``inst_cls`` (V, 256) int16 class of each
instance id (-1 = none), ``K`` (3, 3) and ``X_WC`` (V, 4, 4), and ``tags`` (the scene's
kinds) and ``tray`` (where its tray stands: `scene_record`).
"""

from __future__ import annotations

import colorsys
import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from tamp.grasp.objects import make_object
from tamp.grasp.synthetic import (
    Mat,
    SceneRenderer,
    SynthConfig,
    Visual,
    VisualBody,
    tilted_camera,
)

BACKGROUND = "background"
TABLE = "table"
UNKNOWN = "unknown"
HAND = "hand"
#: classes that are not objects: no instances are made of them
STUFF = (BACKGROUND, TABLE)
#: unknown shapes rendered in training scenes, and the ones kept for the test scenes
UNKNOWN_TRAIN_KINDS = ("box", "cylinder_standing", "ball", "mug", "mushroom", "bar", "compound")
UNKNOWN_TEST_KINDS = ("cylinder_lying", "plate", "ell")
#: the LOTS tower's classes, base first (the cell's ``stack`` order, `tamp.sim.lots.stack`)
STACK_CLASSES = ("bottom", "body", "peak")
#: a stack level's centre lies at most this far (m) from the centre of the one below
STACK_OFFSET = 0.015
#: an object lies across another at most this steeply (rad)
MAX_ACROSS_TILT = math.radians(35.0)
#: scene kinds (`Scene.tags`): a stack of tower parts, the tray, an object lying across another
STACK, TRAY, ACROSS = "stack", "tray", "across"
#: Drake's label of pixels that show nothing (RenderLabel.kEmpty)
EMPTY_LABEL = 32766
#: the LOTS wrist camera (the scenario's default `CameraSettings`), rendered at half its size
DEFAULT_WIDTH, DEFAULT_HEIGHT, DEFAULT_FOV_Y = 160, 90, 42.5
DATASET_FILE = "dataset.json"


@dataclass(frozen=True)
class SegClass:
    """A catalogue class as the renderer draws it: its visuals in the object's frame (the
    lowest point on the table, z up), the primary colour an instance replaces, and the
    palette it draws from."""

    name: str
    visuals: tuple[Visual, ...]
    primary: tuple[float, float, float] | None
    palette: tuple[tuple[float, float, float], ...]

    @property
    def radius(self) -> float:
        """Half the diagonal of the footprint (m): placement and camera aiming."""
        lo, hi = footprint(self.visuals)
        return float(math.hypot(*(hi[:2] - lo[:2])) / 2)


@dataclass(frozen=True)
class DataConfig:
    """What `generate` renders: image size and field of view, views per scene, seed, the
    camera heights, and the share of test scenes."""

    width: int = DEFAULT_WIDTH
    height: int = DEFAULT_HEIGHT
    fov_y_deg: float = DEFAULT_FOV_Y
    views: int = 4
    seed: int = 0
    min_height: float = 0.2
    max_height: float = 0.5
    max_tilt_deg: float = 20.0
    max_objects: int = 6
    test_fraction: float = 0.15
    near: float = 0.03
    #: shares of the scenes with the tray (its objects inside it), of the other scenes with a
    #: stack of tower parts, and of all scenes with an object lying across another
    tray_share: float = 0.2
    stack_share: float = 0.3
    across_share: float = 0.25


# --- reading primitive visuals from SDF files -------------------------------------------


def _pose(text: str | None) -> np.ndarray:
    from pydrake.math import RigidTransform, RollPitchYaw

    v = [float(x) for x in (text or "0 0 0 0 0 0").split()]
    return RigidTransform(RollPitchYaw(*v[3:6]), v[:3]).GetAsMatrix4()


def link_visuals(link: ET.Element, X_BL: np.ndarray | None = None) -> list[Visual]:
    """The box, cylinder and sphere visuals of one SDF ``<link>``, posed in a body frame B
    (``X_BL``: the link's pose in B; identity by default). Other geometry is skipped."""
    X_BL = np.eye(4) if X_BL is None else X_BL
    out = []
    for vis in link.iter("visual"):
        rgba = [float(x) for x in (vis.findtext("material/diffuse") or "0.6 0.6 0.6 1").split()]
        rgba = (rgba + [1.0])[:4]
        geo = vis.find("geometry")
        if geo is None:
            continue
        X = X_BL @ _pose(vis.findtext("pose"))
        if (box := geo.findtext("box/size")) is not None:
            size = tuple(float(x) for x in box.split())
            out.append(Visual("box", size, X, tuple(rgba)))
        elif geo.find("cylinder") is not None:
            size = (float(geo.findtext("cylinder/radius")), float(geo.findtext("cylinder/length")))
            out.append(Visual("cylinder", size, X, tuple(rgba)))
        elif geo.find("sphere") is not None:
            out.append(Visual("sphere", (float(geo.findtext("sphere/radius")),), X, tuple(rgba)))
    return out


def _root(sdf: Path) -> ET.Element:
    """An SDF file's XML root; a ``drake:`` prefix without its namespace declaration (Drake's
    parser accepts it) gets one."""
    text = Path(sdf).read_text()
    if "drake:" in text and "xmlns:drake" not in text:
        text = text.replace("<sdf ", '<sdf xmlns:drake="http://drake.mit.edu" ', 1)
    return ET.fromstring(text)


def _links(sdf: Path) -> dict[str, ET.Element]:
    return {link.get("name"): link for link in _root(sdf).iter("link")}


def footprint(visuals: Sequence[Visual]) -> tuple[np.ndarray, np.ndarray]:
    """(lowest corner, highest corner) of the box around the visuals (each shape's box)."""
    pts = []
    for v in visuals:
        if v.shape == "box":
            half = np.array(v.size) / 2
        elif v.shape == "cylinder":
            half = np.array([v.size[0], v.size[0], v.size[1] / 2])
        else:
            half = np.full(3, v.size[0])
        for corner in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T:
            pts.append(v.X_BG[:3, :3] @ (corner * half) + v.X_BG[:3, 3])
    p = np.array(pts)
    return p.min(axis=0), p.max(axis=0)


def _on_table(visuals: list[Visual]) -> tuple[Visual, ...]:
    """The visuals moved so that their lowest point is at z = 0 and centred in x, y."""
    lo, hi = footprint(visuals)
    shift = np.eye(4)
    shift[:3, 3] = [-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]]
    return tuple(Visual(v.shape, v.size, shift @ v.X_BG, v.rgba) for v in visuals)


def object_class(
    name: str,
    sdf: Path,
    palette: Sequence[Sequence[float]] = (),
    primary: Sequence[float] | None = None,
    link: str | None = None,
) -> SegClass:
    """The `SegClass` of an object SDF (its one link, or ``link``): visuals on the table,
    ``primary`` colour (default: the first visual's) and ``palette`` (default: that one)."""
    links = _links(sdf)
    element = links[link] if link else next(iter(links.values()))
    visuals = _on_table(link_visuals(element))
    if primary is None:
        primary = visuals[0].rgba[:3]
    pal = tuple(tuple(float(c) for c in p[:3]) for p in palette) or (tuple(primary[:3]),)
    return SegClass(name, visuals, tuple(float(c) for c in primary[:3]), pal)


@dataclass(frozen=True)
class Fixtures:
    """What the scenes show besides objects: the gripper's visuals in the camera frame (the
    hand's and fingers' links posed by the camera mount, fingers open ``opening`` each), the
    pose ``X_CT`` (4x4) of the gripper's TCP frame in the camera frame (where a held object
    hangs), and the person's hand visuals in its own frame."""

    gripper: tuple[Visual, ...] = ()
    hand: tuple[Visual, ...] = ()
    X_CT: np.ndarray = field(default_factory=lambda: np.eye(4))
    tray: Tray | None = None


@dataclass(frozen=True)
class Tray:
    """A tray fixture (LOTS Example 1's basket in W^B): its visuals (origin at the middle of
    its bottom), the height of its floor's top, the side of the floor between the walls and
    the side of the outer walls (m), all read from its SDF (`tray_of`)."""

    visuals: tuple[Visual, ...]
    floor: float
    inside: float
    outside: float


def tray_of(sdf: Path, link: str | None = None) -> Tray:
    """The `Tray` of a square tray's SDF: the floor is the visual of lowest top, the walls
    the others; the inside is the outer side less two walls' thickness."""
    links = _links(sdf)
    visuals = tuple(link_visuals(links[link] if link else next(iter(links.values()))))
    tops = [footprint([v])[1][2] for v in visuals]
    floor = visuals[int(np.argmin(tops))]
    walls = [v for v in visuals if v is not floor]
    lo, hi = footprint(visuals)
    outside = float(min(hi[:2] - lo[:2]))
    thickness = min(float(min(footprint([w])[1][:2] - footprint([w])[0][:2])) for w in walls)
    return Tray(visuals, float(min(tops)), outside - 2 * thickness, outside)


def read_fixtures(
    arm_sdf: Path,
    hand_sdf: Path,
    *,
    hand_link: str = "hand",
    finger_links: tuple[str, ...] = ("finger_left", "finger_right"),
    camera_frame: str = "camera",
    tcp_frame: str = "tcp",
    person_link: str = "person_hand",
    opening: float = 0.03,
    tray_sdf: Path | None = None,
) -> Fixtures:
    """The `Fixtures` read from the arm's SDF (hand link, finger links at their poses in the
    hand frame moved apart by ``opening`` along their joint axes, all re-expressed in the
    camera frame), the person's hand SDF (its hand link) and the tray's SDF (`tray_of`),
    when given."""
    root = _root(arm_sdf)
    links = {link.get("name"): link for link in root.iter("link")}
    frames = {f.get("name"): f for f in root.iter("frame")}
    X_HC = _pose(frames[camera_frame].findtext("pose"))
    X_CH = np.linalg.inv(X_HC)
    visuals = link_visuals(links[hand_link], X_CH)
    axes = {
        j.findtext("child"): [float(x) for x in j.findtext("axis/xyz").split()]
        for j in root.iter("joint")
        if j.findtext("child") in finger_links
    }
    for name in finger_links:
        X_HF = _pose(links[name].findtext("pose"))
        X_HF[:3, 3] += opening * np.array(axes.get(name, [0.0, 0.0, 0.0]))
        visuals += link_visuals(links[name], X_CH @ X_HF)
    person = link_visuals(_links(hand_sdf)[person_link])
    X_HT = _pose(frames[tcp_frame].findtext("pose"))
    tray = tray_of(tray_sdf) if tray_sdf is not None else None
    return Fixtures(tuple(visuals), tuple(person), X_CH @ X_HT, tray)


# --- scenes -----------------------------------------------------------------------------


def unknown_visuals(kind: str, rng: np.random.Generator) -> tuple[Visual, ...]:
    """An object of a shape the catalogue does not have (`UNKNOWN_TRAIN_KINDS`,
    `UNKNOWN_TEST_KINDS`), in a random colour, on the table: boxes, standing cylinders,
    balls, mugs, mushrooms (a post under a ball), bars and compounds of two to four
    primitives in training; lying cylinders, plates and L-shapes only in the test scenes."""
    rgba = (*(float(c) for c in rng.uniform(0.15, 0.95, 3)), 1.0)

    def at(x=0.0, y=0.0, z=0.0, yaw=0.0, pitch=0.0) -> np.ndarray:
        from pydrake.math import RigidTransform, RollPitchYaw

        return RigidTransform(RollPitchYaw(0.0, pitch, yaw), [x, y, z]).GetAsMatrix4()

    if kind in ("box", "cylinder_standing", "cylinder_lying"):
        obj = make_object(kind, rng)
        out = []
        for part in obj.parts:
            if part.shape == "box":
                out.append(Visual("box", part.size, at(*part.xyz, yaw=part.yaw), rgba))
            else:
                pitch = math.pi / 2 if part.lying else 0.0
                out.append(
                    Visual("cylinder", part.size, at(*part.xyz, yaw=part.yaw, pitch=pitch), rgba)
                )
        return _on_table(out)
    if kind == "ball":
        r = float(rng.uniform(0.018, 0.04))
        return _on_table([Visual("sphere", (r,), at(z=r), rgba)])
    if kind == "plate":
        r, h = float(rng.uniform(0.035, 0.07)), float(rng.uniform(0.006, 0.015))
        return _on_table([Visual("cylinder", (r, h), at(z=h / 2), rgba)])
    if kind == "ell":
        a, b = rng.uniform(0.06, 0.12, 2)
        w, h = float(rng.uniform(0.015, 0.03)), float(rng.uniform(0.015, 0.04))
        return _on_table(
            [
                Visual("box", (float(a), w, h), at(x=a / 2, z=h / 2), rgba),
                Visual("box", (w, float(b), h), at(y=b / 2, z=h / 2), rgba),
            ]
        )
    if kind == "mug":  # a standing cylinder with a handle on its side
        r, h = float(rng.uniform(0.025, 0.045)), float(rng.uniform(0.05, 0.11))
        t = float(rng.uniform(0.008, 0.014))
        return _on_table(
            [
                Visual("cylinder", (r, h), at(z=h / 2), rgba),
                Visual("box", (0.03, t, 0.6 * h), at(x=r + 0.012, z=h / 2), rgba),
            ]
        )
    if kind == "mushroom":  # a short post under a ball (a knob, a bollard)
        r, h = float(rng.uniform(0.008, 0.018)), float(rng.uniform(0.02, 0.06))
        cap = float(rng.uniform(1.5, 2.6) * r)
        return _on_table(
            [
                Visual("cylinder", (r, h), at(z=h / 2), rgba),
                Visual("sphere", (cap,), at(z=h + 0.6 * cap), rgba),
            ]
        )
    if kind == "bar":  # a long flat strip (a ruler, a slat)
        size = (float(rng.uniform(0.12, 0.3)), float(rng.uniform(0.012, 0.03)),
                float(rng.uniform(0.004, 0.02)))  # fmt: skip
        return _on_table([Visual("box", size, at(z=size[2] / 2), rgba)])
    if kind == "compound":  # two to four boxes, posts and balls fused at random
        parts = []
        for _ in range(int(rng.integers(2, 5))):
            x, y = (float(v) for v in rng.uniform(-0.03, 0.03, 2))
            shape = str(rng.choice(["box", "cylinder", "sphere"]))
            part_rgba = rgba if rng.random() < 0.5 else (*rng.uniform(0.15, 0.95, 3), 1.0)
            if shape == "box":
                lo, hi = [0.015, 0.015, 0.01], [0.06, 0.05, 0.05]
                size = tuple(float(v) for v in rng.uniform(lo, hi))
                X = at(x, y, size[2] / 2, yaw=rng.uniform(0, 3))
                parts.append(Visual("box", size, X, part_rgba))
            elif shape == "cylinder":
                r, h = float(rng.uniform(0.008, 0.025)), float(rng.uniform(0.01, 0.06))
                parts.append(Visual("cylinder", (r, h), at(x, y, h / 2), part_rgba))
            else:
                r = float(rng.uniform(0.01, 0.025))
                parts.append(Visual("sphere", (r,), at(x, y, r), part_rgba))
        return _on_table(parts)
    raise ValueError(f"unknown shape kind {kind!r}")


@dataclass(frozen=True)
class Item:
    """One object of a scene: its class (a catalogue name or ``unknown``), visuals in its
    frame (the lowest point at z = 0), and its pose: (x, y) on the table, ``yaw``, ``z`` the
    height its underside rests at (0 on the table, a tray's floor, the top of the level below
    in a stack) and ``pitch``, a tilt about its own y axis (an object lying across another).
    ``kind``: the shape it was drawn as (its class, or an unknown shape's kind)."""

    cls: str
    visuals: tuple[Visual, ...]
    x: float
    y: float
    yaw: float
    z: float = 0.0
    pitch: float = 0.0
    kind: str = ""

    @cached_property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """`footprint` of the visuals (computed once)."""
        return footprint(self.visuals)

    def _tilted(self) -> np.ndarray:
        """The box's eight corners turned by ``pitch`` (object frame, unshifted; 8 x 3)."""
        lo, hi = self.box
        c = np.array(np.meshgrid(*zip(lo, hi, strict=True))).reshape(3, -1).T
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        return c @ np.array([[cp, 0.0, -sp], [0.0, 1.0, 0.0], [sp, 0.0, cp]])

    def corners(self, margin: float = 0.0) -> np.ndarray:
        """The footprint's corners in the table plane (4 x 2), grown by ``margin``: the box
        (tilted by ``pitch``) seen from above."""
        t = self._tilted()
        lo, hi = t.min(axis=0), t.max(axis=0)
        pts = np.array(
            [[lo[0] - margin, lo[1] - margin], [hi[0] + margin, lo[1] - margin],
             [hi[0] + margin, hi[1] + margin], [lo[0] - margin, hi[1] + margin]]
        )  # fmt: skip
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return pts @ np.array([[c, s], [-s, c]]) + [self.x, self.y]

    @property
    def top(self) -> float:
        """World height of its highest point (m)."""
        return float(self._tilted()[:, 2].max() + self.z)

    def X_WO(self) -> np.ndarray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        X = np.eye(4)
        X[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
            [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]]
        )
        X[:3, 3] = [self.x, self.y, self.z]
        return X


def overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two convex polygons (N x 2 corners in order) overlap (separating axes)."""
    for poly in (a, b):
        for i in range(len(poly)):
            edge = poly[(i + 1) % len(poly)] - poly[i]
            axis = np.array([-edge[1], edge[0]])
            pa, pb = a @ axis, b @ axis
            if pa.max() <= pb.min() or pb.max() <= pa.min():
                return False
    return True


def _free(item: Item, placed: list[Item], margin: float) -> bool:
    return not any(overlap(item.corners(margin), q.corners()) for q in placed)


def _touching(item: Item, other: Item, rng: np.random.Generator) -> Item | None:
    """``item`` moved along a random direction from ``other`` until their footprints just
    touch (bisection on the distance, to 1 mm)."""
    d = rng.uniform(-math.pi, math.pi)
    u = np.array([math.cos(d), math.sin(d)])
    lo, hi = 0.0, 0.6
    for _ in range(12):
        mid = (lo + hi) / 2
        p = np.array([other.x, other.y]) + mid * u
        moved = replace(item, x=float(p[0]), y=float(p[1]))
        if overlap(moved.corners(), other.corners()):
            lo = mid
        else:
            hi = mid
    p = np.array([other.x, other.y]) + (hi + 0.0005) * u
    return replace(item, x=float(p[0]), y=float(p[1]))


def instance_colour(cls: SegClass, rng: np.random.Generator) -> tuple[float, float, float]:
    """A colour of the class's palette, jittered by up to 0.08 per channel, or (one in five)
    any colour: colour alone never tells a class."""
    if rng.random() < 0.2:
        r, g, b = colorsys.hsv_to_rgb(
            rng.uniform(0, 1), rng.uniform(0.2, 0.9), rng.uniform(0.3, 0.95)
        )
        return (r, g, b)
    base = np.array(cls.palette[int(rng.integers(len(cls.palette)))])
    return tuple(float(c) for c in np.clip(base + rng.uniform(-0.08, 0.08, 3), 0.0, 1.0))


def recoloured(cls: SegClass, rgb: tuple[float, float, float]) -> tuple[Visual, ...]:
    """The class's visuals with its primary colour replaced by ``rgb`` (as the cells do)."""
    out = []
    for v in cls.visuals:
        primary = cls.primary is not None and np.allclose(v.rgba[:3], cls.primary, atol=1e-3)
        out.append(Visual(v.shape, v.size, v.X_BG, (*rgb, v.rgba[3]) if primary else v.rgba))
    return tuple(out)


@dataclass(frozen=True)
class Scene:
    """One sampled scene: objects, mats, table colour, lights, the person's hand pose (4x4 or
    None), cameras (4x4 X_WC each), the optional held object of the first view, the split,
    the scene's kinds (`STACK`, `TRAY`, `ACROSS`) and where the tray stands ((x, y), or
    None without one)."""

    items: tuple[Item, ...]
    mats: tuple[Mat, ...]
    table_rgba: tuple[float, float, float, float]
    lights: tuple[dict, ...]
    hand: np.ndarray | None
    cameras: tuple[np.ndarray, ...]
    held: Item | None = None
    split: str = "train"
    tags: tuple[str, ...] = ()
    tray_at: tuple[float, float] | None = None


def split_of(scene: int, seed: int, test_fraction: float) -> str:
    """``"test"`` or ``"train"`` for scene index ``scene`` (drawn from the seed alone)."""
    u = np.random.default_rng((seed, scene, 7919)).random()
    return "test" if u < test_fraction else "train"


def _catalogue_item(c: SegClass, rng: np.random.Generator, **pose) -> Item:
    """An instance of class ``c`` in a colour of its own (`instance_colour`)."""
    pose = {"x": 0.0, "y": 0.0, "yaw": float(rng.uniform(-math.pi, math.pi))} | pose
    return Item(c.name, recoloured(c, instance_colour(c, rng)), kind=c.name, **pose)


def _unknown_item(kinds: Sequence[str], rng: np.random.Generator) -> Item:
    kind = str(kinds[int(rng.integers(len(kinds)))])
    yaw = float(rng.uniform(-math.pi, math.pi))
    return Item(UNKNOWN, unknown_visuals(kind, rng), 0.0, 0.0, yaw, kind=kind)


def _scatter(
    wanted: Sequence[Item],
    placed: list[Item],
    rng: np.random.Generator,
    inside: Callable[[Item], bool],
    spot: Callable[[Item], Item],
    walls: Callable[[Item], Item] | None = None,
) -> None:
    """Place each of ``wanted`` (forty tries each, dropped when none fits) where ``inside``
    allows it and it overlaps nothing placed: half the time pushed against a placed object
    until their footprints touch, else at ``spot`` (or, given ``walls``, a third of those
    against a wall)."""
    for it in wanted:
        for _ in range(40):
            if placed and rng.random() < 0.5:
                cand = _touching(it, placed[int(rng.integers(len(placed)))], rng)
            elif walls is not None and rng.random() < 1 / 3:
                cand = walls(spot(it))
            else:
                cand = spot(it)
            if cand is not None and inside(cand) and _free(cand, placed, 0.0):
                placed.append(cand)
                break


def stacked(below: Item, c: SegClass, rng: np.random.Generator) -> Item:
    """An instance of ``c`` on top of ``below``: centred on it within `STACK_OFFSET`, turned
    by up to 45 degrees, its underside on the top of ``below`` (as the cell's ``Place(B)``
    stacks one level on the next, `tamp.sim.lots.stack`)."""
    r, a = STACK_OFFSET * math.sqrt(rng.random()), rng.uniform(-math.pi, math.pi)
    return _catalogue_item(
        c, rng, x=below.x + r * math.cos(a), y=below.y + r * math.sin(a),
        yaw=below.yaw + float(rng.uniform(-math.pi / 4, math.pi / 4)), z=below.top,
    )  # fmt: skip


def _near_edge(poly: np.ndarray, start: np.ndarray, u: np.ndarray, half: float) -> float | None:
    """How far along ``u`` from ``start`` the strip of half-width ``half`` about that line
    first meets the convex polygon ``poly`` (N x 2 corners in order); None if it misses it.
    The nearest point of polygon and strip is a corner inside the strip or where an edge
    crosses a side of the strip."""
    n = np.array([-u[1], u[0]])
    side = (poly - start) @ n
    points = [c for c, w in zip(poly, side, strict=True) if abs(w) <= half]
    for i in range(len(poly)):
        j = (i + 1) % len(poly)
        for b in (-half, half):
            if (side[i] - b) * (side[j] - b) < 0:
                t = (b - side[i]) / (side[j] - side[i])
                points.append(poly[i] + t * (poly[j] - poly[i]))
    if not points:
        return None
    return float(min((np.asarray(points) - start) @ u))


def lying_across(long: Item, lower: Item, rng: np.random.Generator) -> Item | None:
    """``long`` (its length along its x axis) lying across ``lower``: one end on the surface
    ``lower`` stands on, the body tilted about its y axis until its underside rests on the
    near edge of ``lower``'s top (where its own width first meets it), that edge 55-80 % of
    its length from the end (so it rests on both); None when that would be steeper than
    `MAX_ACROSS_TILT`."""
    lo, hi = long.box
    length = float(hi[0] - lo[0])
    yaw = float(rng.uniform(-math.pi, math.pi))
    u = np.array([math.cos(yaw), math.sin(yaw)])
    through = np.array([lower.x, lower.y]) + float(rng.uniform(-0.01, 0.01)) * np.array(
        [-u[1], u[0]]
    )
    near = _near_edge(lower.corners(), through, u, float(hi[1] - lo[1]) / 2)
    edge = float(rng.uniform(0.55, 0.8)) * length
    theta = math.atan2(lower.top - lower.z, edge)
    if near is None or theta > MAX_ACROSS_TILT:
        return None
    end = through + (near - edge) * u
    cp, sp = math.cos(-theta), math.sin(-theta)
    R = np.array([[u[0], -u[1], 0.0], [u[1], u[0], 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]]
    )
    origin = np.array([end[0], end[1], lower.z]) - R @ np.array([lo[0], 0.0, 0.0])
    return replace(
        long, x=float(origin[0]), y=float(origin[1]), z=float(origin[2]), yaw=yaw, pitch=-theta
    )


def _long(c: SegClass) -> bool:
    """Whether instances of ``c`` are long enough to lie across another (12 cm or more along
    their x axis, 1.5 times their width)."""
    lo, hi = footprint(c.visuals)
    return hi[0] - lo[0] >= 0.12 and hi[0] - lo[0] >= 1.5 * (hi[1] - lo[1])


def _add_across(
    placed: list[Item],
    classes: Sequence[SegClass],
    rng: np.random.Generator,
    inside: Callable[[Item], bool],
) -> bool:
    """Put a long catalogue object across one of the low objects ``placed`` on the support
    (`lying_across`), where it overlaps nothing else; whether one was put."""
    longs = [c for c in classes if _long(c)]
    base = min((it.z for it in placed), default=0.0)
    low = [it for it in placed if it.pitch == 0.0 and it.z <= base + 1e-9]
    low = [it for it in low if 0.008 <= it.top - it.z <= 0.07 and not any(
        q.z > it.z and overlap(q.corners(), it.corners()) for q in placed)]  # fmt: skip
    if not longs or not low:
        return False
    for _ in range(30):
        lower = low[int(rng.integers(len(low)))]
        item = lying_across(_catalogue_item(longs[int(rng.integers(len(longs)))], rng), lower, rng)
        if (
            item is not None
            and inside(item)
            and _free(item, [q for q in placed if q is not lower], 0.0)
        ):
            placed.append(item)
            return True
    return False


def _stack(
    classes: Sequence[SegClass], rng: np.random.Generator, inside: Callable[[Item], bool]
) -> list[Item]:
    """Two or three of the tower's classes (`STACK_CLASSES`, in their order, any two of
    them or all three) stacked (`stacked`) on a base placed at random, and one time in four
    another catalogue object (not a bottle or an obstacle: they stand too tall) on top (the
    person's interference adds and moves tower parts)."""
    by_name = {c.name: c for c in classes}
    tower = [by_name[n] for n in STACK_CLASSES if n in by_name]
    if len(tower) < 2:
        return []
    k = 3 if len(tower) >= 3 and rng.random() < 0.5 else 2
    any_k = rng.random() < 0.3
    picked = sorted(rng.choice(len(tower), size=k, replace=False)) if any_k else range(k)
    levels = [tower[int(i)] for i in picked]
    if rng.random() < 0.25:
        extra = [c for c in classes if c.name not in ("bottle", "obstacle")]
        levels.append(extra[int(rng.integers(len(extra)))])
    for _ in range(40):
        x, y = rng.uniform(-0.18, 0.18, 2)
        out = [_catalogue_item(levels[0], rng, x=float(x), y=float(y))]
        if inside(out[0]):
            break
    else:
        return []
    for c in levels[1:]:
        out.append(stacked(out[-1], c, rng))
    return out


def sample_scene(
    rng: np.random.Generator,
    classes: Sequence[SegClass],
    cfg: DataConfig,
    split: str,
    tray: Tray | None = None,
) -> Scene:
    """A random scene of the catalogue's ``classes`` (module docstring); with ``tray``, a
    share of the scenes (`DataConfig.tray_share`) show it with one to three objects inside."""
    kinds = UNKNOWN_TEST_KINDS if split == "test" else UNKNOWN_TRAIN_KINDS
    placed: list[Item] = []
    focus: list[Item] = []  # what most views aim at: a stack, an object lying across
    tags: list[str] = []
    tray_at = None
    if tray is not None and rng.random() < cfg.tray_share:
        tags.append(TRAY)
        tray_at = (float(rng.uniform(-0.08, 0.08)), float(rng.uniform(-0.08, 0.08)))
        half = tray.inside / 2

        def inside(it: Item) -> bool:
            c = it.corners() - tray_at
            return bool(np.abs(c).max() <= half)

        def spot(it: Item) -> Item:
            x, y = rng.uniform(-half, half, 2) * 0.7 + tray_at
            return replace(it, x=float(x), y=float(y), z=tray.floor)

        def walls(it: Item) -> Item:
            axis, sign = int(rng.integers(2)), float(rng.choice([-1.0, 1.0]))
            reach = float((sign * (it.corners()[:, axis] - tray_at[axis])).max())
            p = [it.x, it.y]
            p[axis] += sign * (half - 0.0005 - reach)
            return replace(it, x=float(p[0]), y=float(p[1]))

        wanted = [
            replace(_catalogue_item(classes[int(rng.integers(len(classes)))], rng), z=tray.floor)
            for _ in range(int(rng.integers(1, 4)))
        ]
        if rng.random() < 0.25:
            wanted.append(replace(_unknown_item(kinds, rng), z=tray.floor))
        _scatter(wanted, placed, rng, inside, spot, walls)
    else:

        def inside(it: Item) -> bool:
            return max(abs(it.x), abs(it.y)) < 0.4

        def spot(it: Item) -> Item:
            x, y = rng.uniform(-0.22, 0.22, 2)
            return replace(it, x=float(x), y=float(y))

        if rng.random() < cfg.stack_share and (tower := _stack(classes, rng, inside)):
            tags.append(STACK)
            placed.extend(tower)
            focus.append(tower[0])
        wanted = [
            _catalogue_item(classes[int(rng.integers(len(classes)))], rng)
            for _ in range(int(rng.integers(1, cfg.max_objects + 1)) - len(placed) // 2)
        ]
        wanted += [_unknown_item(kinds, rng) for _ in range(int(rng.choice([0, 1, 1, 2])))]
        _scatter([wanted[int(k)] for k in rng.permutation(len(wanted))], placed, rng, inside, spot)
    if rng.random() < cfg.across_share and _add_across(placed, classes, rng, inside):
        tags.append(ACROSS)
        focus.append(placed[-1])
    mats = []
    for _ in range(int(rng.choice([0, 1, 1, 2]))):
        r, g, b = colorsys.hsv_to_rgb(
            rng.uniform(0, 1), rng.uniform(0.15, 0.5), rng.uniform(0.5, 0.9)
        )
        size = (float(rng.uniform(0.2, 0.5)), float(rng.uniform(0.2, 0.5)))
        center = (float(rng.uniform(-0.2, 0.2)), float(rng.uniform(-0.2, 0.2)))
        mats.append(Mat(size, center, float(rng.uniform(-math.pi, math.pi)), (r, g, b, 1.0)))
    shade = rng.uniform(0.35, 0.85)
    table = (shade, shade * rng.uniform(0.8, 1.0), shade * rng.uniform(0.6, 1.0), 1.0)
    lights = []
    for _ in range(int(rng.integers(1, 3))):
        az, el = rng.uniform(-math.pi, math.pi), rng.uniform(math.radians(35), math.radians(90))
        direction = [-math.cos(el) * math.cos(az), -math.cos(el) * math.sin(az), -math.sin(el)]
        tint = rng.uniform(0.85, 1.0, 3)
        lights.append({"direction": direction, "intensity": float(rng.uniform(0.5, 1.1)),
                       "color": [float(c) for c in tint]})  # fmt: skip
    hand = None
    if rng.random() < 1 / 3 and placed:
        anchor = placed[int(rng.integers(len(placed)))]
        c = rng.uniform(-math.pi, math.pi)
        hand = np.eye(4)
        hand[:2, :2] = [[math.cos(c), -math.sin(c)], [math.sin(c), math.cos(c)]]
        hand[:3, 3] = [anchor.x + rng.uniform(-0.1, 0.1), anchor.y + rng.uniform(-0.1, 0.1),
                       anchor.top + rng.uniform(0.02, 0.25)]  # fmt: skip
    tallest = max((i.top for i in placed), default=0.0)
    if tray_at is not None:
        tallest = max(tallest, footprint(tray.visuals)[1][2])
    cameras = sample_cameras(rng, placed, cfg, tallest, focus)
    held = None
    if rng.random() < 0.25:
        held = _catalogue_item(classes[int(rng.integers(len(classes)))], rng, yaw=0.0)
    return Scene(
        tuple(placed), tuple(mats), table, tuple(lights), hand, tuple(cameras), held, split,
        tuple(tags), tray_at,
    )  # fmt: skip


def sample_cameras(
    rng: np.random.Generator,
    placed: Sequence[Item],
    cfg: DataConfig,
    tallest: float,
    focus: Sequence[Item] = (),
) -> list[np.ndarray]:
    """Wrist views: above a random object (of ``focus``, when given, in two views of three)
    at ``min_height``-``max_height`` (and 12 cm above the tallest object), tilted up to
    ``max_tilt_deg``, at a random roll."""
    cams = []
    for _ in range(cfg.views):
        if focus and rng.random() < 2 / 3:
            it = focus[int(rng.integers(len(focus)))]
            target = np.array([it.x, it.y, 0.0])
        elif placed:
            it = placed[int(rng.integers(len(placed)))]
            target = np.array([it.x, it.y, 0.0])
        else:
            target = np.zeros(3)
        target[:2] += rng.uniform(-0.05, 0.05, 2)
        h = max(rng.uniform(cfg.min_height, cfg.max_height), tallest + 0.12)
        cams.append(tilted_camera(rng, target, h, cfg.max_tilt_deg))
    return cams


# --- rendering --------------------------------------------------------------------------


@dataclass(frozen=True)
class View:
    """One rendered view: images, targets and camera."""

    rgb: np.ndarray
    depth: np.ndarray
    cls: np.ndarray
    inst: np.ndarray
    inst_cls: np.ndarray
    K: np.ndarray
    X_WC: np.ndarray


def class_names(classes: Sequence[SegClass]) -> tuple[str, ...]:
    """The network's output classes, in order: background, table, the catalogue, unknown,
    hand."""
    return (BACKGROUND, TABLE, *(c.name for c in classes), UNKNOWN, HAND)


def _lights(specs: Sequence[dict]) -> tuple:
    from pydrake.geometry import LightParameter, Rgba

    return tuple(
        LightParameter(type="directional", frame="world", direction=s["direction"],
                       intensity=s["intensity"], color=Rgba(*s["color"], 1.0))
        for s in specs
    )  # fmt: skip


def render_scene(
    scene: Scene, classes: Sequence[SegClass], fixtures: Fixtures, cfg: DataConfig
) -> list[View]:
    """Render every view of ``scene``; the first view with the held object and the gripper
    when the scene has one (its own diagram: they hang under that camera only)."""
    names = class_names(classes)
    index = {n: i for i, n in enumerate(names)}
    bodies = [
        VisualBody(f"obj{k}_{it.cls}", it.X_WO(), it.visuals) for k, it in enumerate(scene.items)
    ]
    body_cls = [index[it.cls] for it in scene.items]
    for k, mat in enumerate(scene.mats):  # 1 mm proud of the table, labelled table
        X = np.eye(4)
        c, s = math.cos(mat.yaw), math.sin(mat.yaw)
        X[:2, :2] = [[c, -s], [s, c]]
        X[:3, 3] = [*mat.center, 0.0]
        bodies.append(
            VisualBody(f"mat{k}", X, (Visual("box", (*mat.size, 0.002), np.eye(4), mat.rgba),))
        )
        body_cls.append(index[TABLE])
    if scene.tray_at is not None and fixtures.tray is not None:  # a fixture: labelled table
        X = np.eye(4)
        X[:2, 3] = scene.tray_at
        bodies.append(VisualBody("tray", X, fixtures.tray.visuals))
        body_cls.append(index[TABLE])
    if scene.hand is not None and fixtures.hand:
        bodies.append(VisualBody("person_hand", scene.hand, fixtures.hand))
        body_cls.append(index[HAND])
    synth = SynthConfig(fov_y_deg=cfg.fov_y_deg)
    common = dict(image=(cfg.width, cfg.height), lights=_lights(scene.lights), near=cfg.near)
    cams = list(scene.cameras)
    first_special = scene.held is not None and bool(cams)
    views: list[View] = []
    groups = []
    if first_special:
        X_WC = cams[0]
        # the held object between the fingers, upright (its z against the TCP's approach
        # axis), its middle 1 cm beyond the TCP, its length along the hand's x (towards the
        # camera's side), as a top grasp holds it
        lo, hi = footprint(scene.held.visuals)
        X_TO = np.eye(4)
        X_TO[:3, :3] = np.diag([1.0, -1.0, -1.0])
        X_TO[:3, 3] = [0.0, 0.0, 0.01 + (hi[2] - lo[2]) / 2]
        extra = [
            VisualBody("gripper", X_WC, fixtures.gripper),
            VisualBody("held", X_WC @ fixtures.X_CT @ X_TO, scene.held.visuals),
        ]
        groups.append(([X_WC], extra, [0, index[scene.held.cls]]))
        cams = cams[1:]
    if cams:
        groups.append((cams, [], []))
    for group_cams, extra, extra_cls in groups:
        allb = tuple(bodies + extra)
        renderer = SceneRenderer(
            [], group_cams, synth, scene.table_rgba, None, bodies=allb, **common
        )
        lut = {int(b): c for b, c in zip(renderer.body_of_extra, body_cls + extra_cls, strict=True)}
        table_body = renderer.table_body
        for v, X_WC in enumerate(group_cams):
            rgb, depth, label = renderer.render(v)
            views.append(view_targets(rgb, depth, label, lut, table_body, renderer.K, X_WC))
    return views


def view_targets(rgb, depth, label, lut, table_body, K, X_WC) -> View:
    """One view's targets from its label image: per-pixel classes (``lut``: render label ->
    class index; the table body is ``table``; a stuff class sets the class only) and one
    instance id per object body (its class in ``inst_cls``)."""
    cls = np.zeros(label.shape, np.uint8)
    inst = np.zeros(label.shape, np.uint8)
    inst_cls = np.full(256, -1, np.int16)
    cls[label == table_body] = 1
    for k, (body, c) in enumerate(sorted(lut.items()), start=1):
        if c < len(STUFF):
            cls[label == body] = c  # the gripper: background; a mat: table
            continue
        m = label == body
        cls[m] = c
        inst[m] = k
        inst_cls[k] = c
    return View(rgb, depth.astype(np.float32), cls, inst, inst_cls, np.asarray(K), np.asarray(X_WC))


# --- the data set -----------------------------------------------------------------------


def scene_file(out: Path, i: int) -> Path:
    return Path(out) / f"scene_{i:05d}.npz"


def write_scene(path: Path, views: Sequence[View], scene: Scene | None = None,
                tray: Tray | None = None,
                plane: tuple[float, float] | None = None) -> None:  # fmt: skip
    """One scene's views stacked in one compressed ``.npz`` (module docstring), with the
    scene's kinds and its tray (`scene_record`), and ``plane``, the support's height and how
    far over it an object's pixels are when the cell knows them (the SMP-MRO floor:
    `tamp.sim.smp.mast_data`)."""
    np.savez_compressed(
        path,
        **scene_record(scene, tray),
        plane=np.zeros(0) if plane is None else np.array([float(x) for x in plane]),
        rgb=np.stack([v.rgb for v in views]),
        depth=np.stack([v.depth for v in views]),
        cls=np.stack([v.cls for v in views]),
        inst=np.stack([v.inst for v in views]),
        inst_cls=np.stack([v.inst_cls for v in views]),
        K=views[0].K,
        X_WC=np.stack([v.X_WC for v in views]),
    )


def scene_record(scene: Scene | None, tray: Tray | None) -> dict[str, np.ndarray]:
    """What a scene file keeps of the scene besides its views: ``tags``, its kinds (strings),
    and ``tray``: (x, y, floor, inside, outside) of its tray, empty without one."""
    tags = np.array(scene.tags if scene is not None else (), dtype="U8")
    at = None if scene is None or tray is None else scene.tray_at
    record = np.zeros(0) if at is None else np.array([*at, tray.floor, tray.inside, tray.outside])
    return {"tags": tags, "tray": record}


def view_fixtures(record: dict[str, np.ndarray], depth: np.ndarray, intrinsics, X_WC) -> dict:
    """The fixtures a view of a scene file shows, as the cell gives them to the detector at
    run time (`tamp.sim.core.perception.Region.fixtures`: the tray's floor as ``plane``, the
    pixels on its walls as ``exclude``; the support's recorded height and threshold as
    ``plane`` and ``above``); empty without either (and for the files rendered before they
    were recorded)."""
    plane = record.get("plane")
    known = {}
    if plane is not None and len(plane) == 2:
        known = {"plane": float(plane[0]), "above": float(plane[1])}
    tray = record.get("tray")
    if tray is None or len(tray) == 0:
        return known
    from pydrake.math import RigidTransform

    from tamp.sim.core.perception import Region

    x, y, floor, inside, outside = (float(v) for v in tray)
    region = Region((x, y), (inside, inside), floor=floor, rim=(inside, outside))
    return region.fixtures(depth, intrinsics, RigidTransform(np.asarray(X_WC, float)))


def read_scene(path: Path) -> dict[str, np.ndarray]:
    with np.load(path) as f:
        return {k: f[k] for k in f.files}


@dataclass(frozen=True)
class DatasetInfo:
    """``dataset.json``: classes, configuration, scenes and their split."""

    classes: tuple[str, ...]
    config: dict
    scenes: int
    train: tuple[int, ...]
    test: tuple[int, ...]
    unknown_train_kinds: tuple[str, ...] = UNKNOWN_TRAIN_KINDS
    unknown_test_kinds: tuple[str, ...] = UNKNOWN_TEST_KINDS
    views: int = 0
    extra: dict = field(default_factory=dict)

    def split_record(self) -> dict:
        """What a weights file records of its training split (with fingerprints of the scene
        ids of each part, `tamp.grasp.splits.fingerprint`)."""
        from tamp.grasp.splits import fingerprint

        return {
            "kind": "object",
            "seed": self.config["seed"],
            "test_fraction": self.config["test_fraction"],
            "scenes": self.scenes,
            "train_scenes": len(self.train),
            "test_scenes": len(self.test),
            "unknown_train_kinds": list(self.unknown_train_kinds),
            "unknown_test_kinds": list(self.unknown_test_kinds),
            "fingerprint": fingerprint([f"scene_{i:05d}" for i in self.train + self.test]),
            "test_fingerprint": fingerprint([f"scene_{i:05d}" for i in self.test]),
        }


def read_info(folder: str | Path) -> DatasetInfo:
    """The ``dataset.json`` of a rendered set (`InputError` naming the file otherwise)."""
    from tamp.errors import InputError

    path = Path(folder) / DATASET_FILE
    try:
        d = json.loads(path.read_text())
        return DatasetInfo(
            tuple(d["classes"]), d["config"], int(d["scenes"]), tuple(d["train"]),
            tuple(d["test"]), tuple(d["unknown_train_kinds"]), tuple(d["unknown_test_kinds"]),
            int(d.get("views", 0)),
        )  # fmt: skip
    except FileNotFoundError:
        raise InputError(
            "no detector data set here (dataset.json missing)", file=str(path)
        ) from None
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"not a detector data set: {exc}", file=str(path)) from None


def _render_range(out: Path, first: int, count: int, classes, fixtures, cfg: DataConfig) -> int:
    views = 0
    for i in range(first, first + count):
        split = split_of(i, cfg.seed, cfg.test_fraction)
        rng = np.random.default_rng((cfg.seed, i))
        scene = sample_scene(rng, classes, cfg, split, fixtures.tray)
        rendered = render_scene(scene, classes, fixtures, cfg)
        write_scene(scene_file(out, i), rendered, scene, fixtures.tray)
        views += len(rendered)
    return views


def generate(
    out: str | Path,
    scenes: int,
    classes: Sequence[SegClass],
    fixtures: Fixtures,
    cfg: DataConfig = DataConfig(),
    *,
    jobs: int = 1,
    progress: bool = True,
    on_scene: Callable[[int], None] | None = None,
) -> DatasetInfo:
    """Render ``scenes`` scenes into ``out`` (module docstring) and write ``dataset.json``.
    Scene ``i`` depends on ``(cfg.seed, i)`` alone, so ``jobs`` processes (spawned: a forked
    EGL context is unsafe) write the same files as one."""
    from tqdm import tqdm

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    size = max(1, min(10, math.ceil(scenes / (4 * max(1, jobs)))))
    chunks = [(s, min(size, scenes - s)) for s in range(0, scenes, size)]
    views = 0
    with tqdm(total=scenes, desc="render", unit="scene", disable=not progress) as bar:
        if jobs <= 1:
            for s, n in chunks:
                views += _render_range(out, s, n, classes, fixtures, cfg)
                bar.update(n)
                for i in range(s, s + n) if on_scene else ():
                    on_scene(i)
        else:
            from concurrent.futures import ProcessPoolExecutor, as_completed
            from multiprocessing import get_context

            with ProcessPoolExecutor(jobs, mp_context=get_context("spawn")) as pool:
                futures = {
                    pool.submit(_render_range, out, s, n, tuple(classes), fixtures, cfg): (s, n)
                    for s, n in chunks
                }
                for future in as_completed(futures):
                    views += future.result()
                    s, n = futures[future]
                    bar.update(n)
                    for i in range(s, s + n) if on_scene else ():
                        on_scene(i)
    return write_info(out, class_names(classes), asdict(cfg), scenes, views)


def write_info(out: Path, classes: Sequence[str], config: dict, scenes: int, views: int):
    """Write ``OUT/dataset.json`` of a rendered set of ``scenes`` scenes (their split drawn
    from the ``config``'s seed and test share: `split_of`) and return it."""
    parts = {s: split_of(s, config["seed"], config["test_fraction"]) for s in range(scenes)}
    info = DatasetInfo(
        tuple(classes),
        config,
        scenes,
        tuple(i for i in range(scenes) if parts[i] == "train"),
        tuple(i for i in range(scenes) if parts[i] == "test"),
        views=views,
    )
    (out / DATASET_FILE).write_text(json.dumps(asdict(info), indent=1))
    return info
