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
- ``unknown``: objects of shapes the catalogue does not have (boxes, cylinders, balls,
  plates, L-shapes), so that an object the detector was not trained on is reported as
  ``unknown`` rather than as the nearest task class,
- ``hand``: the person's hand and forearm, its own class, so that a hand reaching into a
  workspace is never counted as an object (safety does not need the class: it is decided
  from depth; the class keeps the hand out of the counts and lets a recording show it).

Scenes (`sample_scene`): one to six catalogue objects at random positions, yaws and colours
(a class's palette, jittered, or any colour in one of five), clutter that touches (half of
the objects are pushed against one already placed until their footprints touch), zero to two
unknown objects, coloured mats, the person's hand in one scene of three (hovering 2-25 cm
above the table), one or two directional lights of random direction, intensity and tint.
Views (`sample_cameras`): the wrist camera above a random object at 0.2-0.5 m (and at least
12 cm above the tallest object), tilted up to 20 degrees, at a random roll about its axis;
in one scene of four the first view also shows an object held in the gripper (the gripper
at the camera's mount, the object between the fingers, as the arm carries it).

Object-wise split: scenes are assigned to train or test by their index (`split_of`); the
unknown objects of test scenes are of shapes never rendered in training
(`UNKNOWN_TEST_KINDS`), and the split is recorded in ``dataset.json`` and, by training, in
the weights file. Everything of scene ``i`` is drawn from ``default_rng((seed, i))``.

Layout: ``OUT/dataset.json`` (classes, configuration, split) and ``OUT/scene_NNNNN.npz``
with the scene's views stacked: ``rgb`` (V, H, W, 3) uint8, ``depth`` (V, H, W) float32
metres (0 = no return), ``cls`` (V, H, W) uint8 class indices, ``inst`` (V, H, W) uint8
instance ids (0 = none; an id per object body), ``inst_cls`` (V, 256) int16 class of each
instance id (-1 = none), ``K`` (3, 3) and ``X_WC`` (V, 4, 4).
"""

from __future__ import annotations

import colorsys
import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
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
UNKNOWN_TRAIN_KINDS = ("box", "cylinder_standing", "ball")
UNKNOWN_TEST_KINDS = ("cylinder_lying", "plate", "ell")
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
) -> Fixtures:
    """The `Fixtures` read from the arm's SDF (hand link, finger links at their poses in the
    hand frame moved apart by ``opening`` along their joint axes, all re-expressed in the
    camera frame) and the person's hand SDF (its hand link)."""
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
    return Fixtures(tuple(visuals), tuple(person), X_CH @ X_HT)


# --- scenes -----------------------------------------------------------------------------


def unknown_visuals(kind: str, rng: np.random.Generator) -> tuple[Visual, ...]:
    """An object of a shape the catalogue does not have (`UNKNOWN_TRAIN_KINDS`,
    `UNKNOWN_TEST_KINDS`), in a random colour, on the table."""
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
    raise ValueError(f"unknown shape kind {kind!r}")


@dataclass(frozen=True)
class Item:
    """One object of a scene: its class (a catalogue name or ``unknown``), visuals in its
    frame, and its pose on the table (x, y, yaw)."""

    cls: str
    visuals: tuple[Visual, ...]
    x: float
    y: float
    yaw: float

    @cached_property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """`footprint` of the visuals (computed once)."""
        return footprint(self.visuals)

    def corners(self, margin: float = 0.0) -> np.ndarray:
        """The footprint's corners in the table plane (4 x 2), grown by ``margin``."""
        lo, hi = self.box
        pts = np.array(
            [[lo[0] - margin, lo[1] - margin], [hi[0] + margin, lo[1] - margin],
             [hi[0] + margin, hi[1] + margin], [lo[0] - margin, hi[1] + margin]]
        )  # fmt: skip
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return pts @ np.array([[c, s], [-s, c]]) + [self.x, self.y]

    @property
    def top(self) -> float:
        return float(self.box[1][2])

    def X_WO(self) -> np.ndarray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        X = np.eye(4)
        X[:2, :2] = [[c, -s], [s, c]]
        X[:2, 3] = [self.x, self.y]
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
        moved = Item(item.cls, item.visuals, float(p[0]), float(p[1]), item.yaw)
        if overlap(moved.corners(), other.corners()):
            lo = mid
        else:
            hi = mid
    p = np.array([other.x, other.y]) + (hi + 0.0005) * u
    return Item(item.cls, item.visuals, float(p[0]), float(p[1]), item.yaw)


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
    None), cameras (4x4 X_WC each) and the optional held object of the first view."""

    items: tuple[Item, ...]
    mats: tuple[Mat, ...]
    table_rgba: tuple[float, float, float, float]
    lights: tuple[dict, ...]
    hand: np.ndarray | None
    cameras: tuple[np.ndarray, ...]
    held: Item | None = None
    split: str = "train"


def split_of(scene: int, seed: int, test_fraction: float) -> str:
    """``"test"`` or ``"train"`` for scene index ``scene`` (drawn from the seed alone)."""
    u = np.random.default_rng((seed, scene, 7919)).random()
    return "test" if u < test_fraction else "train"


def sample_scene(
    rng: np.random.Generator, classes: Sequence[SegClass], cfg: DataConfig, split: str
) -> Scene:
    """A random scene of the catalogue's ``classes`` (module docstring)."""
    kinds = UNKNOWN_TEST_KINDS if split == "test" else UNKNOWN_TRAIN_KINDS
    wanted: list[tuple[str, tuple[Visual, ...]]] = []
    for _ in range(int(rng.integers(1, cfg.max_objects + 1))):
        c = classes[int(rng.integers(len(classes)))]
        wanted.append((c.name, recoloured(c, instance_colour(c, rng))))
    for _ in range(int(rng.choice([0, 0, 1, 2]))):
        kind = str(kinds[int(rng.integers(len(kinds)))])
        wanted.append((UNKNOWN, unknown_visuals(kind, rng)))
    order = rng.permutation(len(wanted))
    placed: list[Item] = []
    for k in order:
        name, visuals = wanted[int(k)]
        yaw = float(rng.uniform(-math.pi, math.pi))
        for _ in range(40):
            if placed and rng.random() < 0.5:
                other = placed[int(rng.integers(len(placed)))]
                item = _touching(Item(name, visuals, 0.0, 0.0, yaw), other, rng)
            else:
                x, y = rng.uniform(-0.22, 0.22, 2)
                item = Item(name, visuals, float(x), float(y), yaw)
            if (
                item is not None
                and _free(item, placed, 0.0)
                and max(abs(item.x), abs(item.y)) < 0.4
            ):
                placed.append(item)
                break
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
    cameras = sample_cameras(rng, placed, cfg, tallest)
    held = None
    if rng.random() < 0.25:
        c = classes[int(rng.integers(len(classes)))]
        held = Item(c.name, recoloured(c, instance_colour(c, rng)), 0.0, 0.0, 0.0)
    return Scene(
        tuple(placed), tuple(mats), table, tuple(lights), hand, tuple(cameras), held, split
    )


def sample_cameras(
    rng: np.random.Generator, placed: Sequence[Item], cfg: DataConfig, tallest: float
) -> list[np.ndarray]:
    """Wrist views: above a random object at ``min_height``-``max_height`` (and 12 cm above
    the tallest object), tilted up to ``max_tilt_deg``, at a random roll."""
    cams = []
    for _ in range(cfg.views):
        if placed:
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
            views.append(_targets(rgb, depth, label, lut, table_body, renderer.K, X_WC))
    return views


def _targets(rgb, depth, label, lut, table_body, K, X_WC) -> View:
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


def write_scene(path: Path, views: Sequence[View]) -> None:
    """One scene's views stacked in one compressed ``.npz`` (module docstring)."""
    np.savez_compressed(
        path,
        rgb=np.stack([v.rgb for v in views]),
        depth=np.stack([v.depth for v in views]),
        cls=np.stack([v.cls for v in views]),
        inst=np.stack([v.inst for v in views]),
        inst_cls=np.stack([v.inst_cls for v in views]),
        K=views[0].K,
        X_WC=np.stack([v.X_WC for v in views]),
    )


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
        scene = sample_scene(np.random.default_rng((cfg.seed, i)), classes, cfg, split)
        rendered = render_scene(scene, classes, fixtures, cfg)
        write_scene(scene_file(out, i), rendered)
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
    parts = {s: split_of(s, cfg.seed, cfg.test_fraction) for s in range(scenes)}
    info = DatasetInfo(
        class_names(classes),
        asdict(cfg),
        scenes,
        tuple(i for i in range(scenes) if parts[i] == "train"),
        tuple(i for i in range(scenes) if parts[i] == "test"),
        views=views,
    )
    (out / DATASET_FILE).write_text(json.dumps(asdict(info), indent=1))
    return info
