"""LOTS workcell scenario files (``tamp/scenarios/lots_sim/*.yaml``), loaded strictly.

A scenario says where the two workspaces W^A and W^B and the waste basket are, which
objects lie where at the start, and the plant, camera, control and grasp settings. Every
error names the file and the field (`tamp.fileio`); the CLI exits with status 2. No Drake
import here. Example (``tamp/scenarios/lots_sim/model_building.yaml``)::

    version: 1
    name: model_building
    plant: {time_step: 0.002, contact_model: hydroelastic_with_fallback}
    camera: {width: 320, height: 180, fov_y_deg: 42.5}
    control: {period: 0.01, perception_period: 0.02, speed: 0.35, look_height: 0.45}
    safety: {hand_distance: 0.05, min_command_rate: 1000}   # optional; defaults shown
    grasp: {network: hrgnet, view_heights: [0.34, 0.27, 0.2], attempts: 3}
    workspaces:
      A: {center: [0.5, 0.23], size: [0.3, 0.3]}
      B: {center: [0.5, -0.23], size: [0.3, 0.3]}
    waste_basket: [0.2, -0.56]
    objects:                       # xy relative to the workspace centre, yaw in degrees
      - {class: saw, workspace: A, xy: [-0.07, 0.08], yaw: 10}
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tamp import scenarios
from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.grasp.networks import DEFAULT_NETWORK, NETWORKS
from tamp.perturbation import NONE, Applied, Perturbation, check_seed, parse_perturbation
from tamp.sim.lots.catalogue import CLASSES

CONTACT_MODELS = ("point", "hydroelastic_with_fallback", "hydroelastic")
SIDES = ("A", "B")
#: Where each network's shipped weights are (relative to the repository's models/ folder).
DEFAULT_WEIGHTS = {name: net.weights for name, net in NETWORKS.items()}
#: The arm's comfortable reach on the table (Franka: 0.855 m from joint 2; keep a margin).
REACH = (0.25, 0.75)
BASKET_HALF = 0.12  # lots_waste_basket.sdf: 0.24 x 0.24 m
#: the ``perturbation`` fields this workcell simulates: start poses of the objects and their
#: friction (`perturbed`, `tamp.sim.lots.plant`), the camera's depth noise
#: (`tamp.sim.core.camera.DepthNoise`), the person's reaction times (`tamp.sim.lots.person`)
#: and chance failures of grasp attempts (`tamp.sim.lots.skills`)
PERTURBED = ("objects", "friction", "sensor", "timing", "skills")
#: the skills whose attempts ``perturbation.skills`` may make fail
CHANCE_SKILLS = ("Pick",)
#: how often a start offset that leaves the workspace or overlaps is redrawn
REDRAWS = 20


@dataclass(frozen=True)
class Workspace:
    """A rectangular workspace on the table (W^A or W^B): centre and size in metres."""

    name: str
    center: tuple[float, float]
    size: tuple[float, float]
    tray: bool = False  # Example 1's basket: a shallow tray welded on W^B

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        cx, cy = self.center
        return abs(x - cx) <= self.size[0] / 2 - margin and abs(y - cy) <= self.size[1] / 2 - margin


@dataclass(frozen=True)
class CellObject:
    """One object: unique id, class, workspace, position in the table frame, yaw, colour."""

    id: str
    cls: str
    workspace: str
    xy: tuple[float, float]
    yaw: float
    rgb: tuple[float, float, float]


@dataclass(frozen=True)
class CameraSettings:
    """The wrist camera (D435-like colour intrinsics). See docs/lots_workcell.md for why 320x180."""

    width: int = 320
    height: int = 180
    fov_y_deg: float = 42.5
    near: float = 0.03
    far: float = 2.0


@dataclass(frozen=True)
class ControlSettings:
    """Skill controller rate, perception update rate, TCP speed and the look height (camera)."""

    period: float = 0.01
    perception_period: float = 0.02
    speed: float = 0.35
    look_height: float = 0.45
    command_period: float = 0.001  # the arm command stream (`tamp.sim.lots.command`)


@dataclass(frozen=True)
class SafetySettings:
    """The safety monitor (Zhou et al. §IV-C, `tamp.sim.lots.safety`): stop while a hand is
    closer than ``hand_distance`` to the end effector; emergency stop when the arm command
    stream falls below ``min_command_rate`` or a joint speed/acceleration limit is exceeded,
    held at least ``recovery`` seconds. Limits are checked every ``check_period``; while a
    hand may be near, the camera is rendered every ``image_period`` for the monitor."""

    enabled: bool = True
    hand_distance: float = 0.05
    min_command_rate: float = 1000.0
    check_period: float = 0.01
    image_period: float = 0.1
    recovery: float = 1.0


@dataclass(frozen=True)
class GraspSettings:
    """Which network, its weights, the camera heights above the target of the descending
    views (the last is the paper's preset 0.2 m), attempts."""

    network: str = DEFAULT_NETWORK
    weights: str | None = None
    view_heights: tuple[float, ...] = (0.34, 0.27, 0.2)
    attempts: int = 3


@dataclass(frozen=True)
class CellScenario:
    """A loaded, validated LOTS workcell scenario."""

    name: str
    source: str
    time_step: float
    contact_model: str
    camera: CameraSettings
    control: ControlSettings
    grasp: GraspSettings
    workspaces: dict[str, Workspace]
    waste_basket: tuple[float, float]
    objects: tuple[CellObject, ...]
    max_sim_time: float = 600.0
    safety: SafetySettings = field(default_factory=SafetySettings)
    extra: dict = field(default_factory=dict)
    perturbation: Perturbation = NONE
    sample: Any = None  # the run's `PerturbationSample` (set by `perturbed`), else None

    def object(self, uid: str) -> CellObject:
        for o in self.objects:
            if o.id == uid:
                return o
        raise KeyError(uid)


def load_cell_scenario(path: str | Path) -> CellScenario:
    """Load and validate a workcell scenario; `InputError` names file and field."""
    path = scenarios.resolve(path, "lots_sim")  # packaged: tamp/scenarios/lots_sim
    data, file = load_yaml(path, kind="LOTS workcell scenario")
    f = Fields(data, file)
    f.check_keys(
        {
            "version",
            "name",
            "description",
            "plant",
            "camera",
            "control",
            "safety",
            "grasp",
            "workspaces",
            "waste_basket",
            "objects",
            "max_sim_time",
            "perturbation",
        }
    )
    name = f.str("name")
    if f.has("description"):
        f.str("description")

    plant = f.sub("plant", {})
    plant.check_keys({"time_step", "contact_model"})
    time_step = plant.float("time_step", 0.002, min=0.0005, max=0.01)
    contact = plant.str("contact_model", "hydroelastic_with_fallback", choices=CONTACT_MODELS)

    c = f.sub("camera", {})
    c.check_keys({"width", "height", "fov_y_deg", "near", "far"})
    camera = CameraSettings(
        width=_pixels(c, "width", 320),
        height=_pixels(c, "height", 180),
        fov_y_deg=c.float("fov_y_deg", 42.5, min=10.0, max=120.0),
        near=c.float("near", 0.03, min=0.005, max=0.2),
        far=c.float("far", 2.0, min=0.5, max=10.0),
    )

    k = f.sub("control", {})
    k.check_keys({"period", "perception_period", "speed", "look_height", "command_period"})
    period = k.float("period", 0.01, min=time_step, max=0.05)
    control = ControlSettings(
        period=period,
        perception_period=k.float("perception_period", 0.02, min=period, max=0.5),
        speed=k.float("speed", 0.35, min=0.0, max=1.0, strict_min=True),
        look_height=k.float("look_height", 0.45, min=0.3, max=0.6),
        command_period=k.float("command_period", 0.001, min=0.0001, max=period),
    )
    safety = _safety(f.sub("safety", {}), control)

    g = f.sub("grasp", {})
    g.check_keys({"network", "weights", "view_heights", "attempts"})
    network = g.str("network", DEFAULT_NETWORK, choices=NETWORKS)
    weights = g.str("weights") if g.has("weights") else None
    if weights is not None:
        local = Path(file).parent / weights
        weights = str(local if local.exists() else weights)
        if not Path(weights).is_file():
            raise g.error("weights", f"no weights file {weights!r}")
    elif network not in DEFAULT_WEIGHTS:
        raise g.error("network", f"no shipped weights for {network!r}: give grasp.weights")
    heights = g.items("view_heights", [0.34, 0.27, 0.2])
    view_heights = tuple(
        _number(h, file, f"grasp.view_heights[{i}]", 0.15, control.look_height)
        for i, h in enumerate(heights)
    )
    if not view_heights or list(view_heights) != sorted(view_heights, reverse=True):
        raise g.error("view_heights", "expected descending camera heights, e.g. [0.34, 0.27, 0.2]")
    grasp = GraspSettings(network, weights, view_heights, g.int("attempts", 3, min=1))

    ws = f.sub("workspaces")
    ws.check_keys(SIDES)
    workspaces = {}
    for side in SIDES:
        w = ws.sub(side)
        w.check_keys({"center", "size", "tray"})
        center = w.vector("center", 2)
        size = w.vector("size", 2)
        if not all(0.1 <= s <= 0.4 for s in size):
            raise w.error("size", f"workspace sides must be within [0.1, 0.4] m, got {list(size)}")
        _check_reach(w, "center", center)
        tray = w.bool("tray", False)
        if tray and side == "A":
            raise w.error("tray", "only W^B holds Example 1's basket")
        workspaces[side] = Workspace(side, center, size, tray)
    a, b = workspaces["A"], workspaces["B"]
    if abs(a.center[1] - b.center[1]) < (a.size[1] + b.size[1]) / 2 + 0.1:
        raise ws.error(
            "B.center",
            "W^A and W^B must lie side by side in y, at least 0.1 m apart (one view each)",
        )
    basket = f.vector("waste_basket", 2)
    _check_reach(f, "waste_basket", basket)
    for w in workspaces.values():
        if rectangles_overlap(_square(basket, BASKET_HALF), _square(w.center, *w.size), 0.03):
            raise f.error("waste_basket", f"the waste basket lies within 3 cm of W^{w.name}")

    objects = _objects(f, workspaces)
    max_sim_time = f.float("max_sim_time", 600.0, min=0.0, strict_min=True)
    perturbation = parse_perturbation(f)
    perturbation.require(PERTURBED, "LOTS")
    if perturbation.pose_noise > 0:  # nothing estimates poses here: the camera sees counts
        raise f.error(
            "perturbation.sensor.pose_noise",
            "the LOTS workcell estimates no object poses (use sensor.depth_noise)",
        )
    for name in perturbation.skill_failure:
        if name not in CHANCE_SKILLS:
            raise f.error(
                f"perturbation.skills.{name}",
                f"only {', '.join(CHANCE_SKILLS)} attempts can fail by chance in the LOTS workcell",
            )
    return CellScenario(
        name=name,
        source=file,
        time_step=time_step,
        contact_model=contact,
        camera=camera,
        control=control,
        grasp=grasp,
        workspaces=workspaces,
        waste_basket=basket,
        objects=objects,
        max_sim_time=max_sim_time,
        safety=safety,
        perturbation=perturbation,
    )


def _safety(s: Fields, control: ControlSettings) -> SafetySettings:
    s.check_keys(
        {"enabled", "hand_distance", "min_command_rate", "check_period", "image_period", "recovery"}
    )
    check = s.float("check_period", 0.01, min=control.command_period, max=0.1)
    ticks = control.perception_period / check
    if abs(ticks - round(ticks)) > 1e-6:  # the monitor reads perception's frames at its ticks
        raise s.error(
            "check_period",
            f"must divide control.perception_period ({control.perception_period:g} s)",
        )
    return SafetySettings(
        enabled=s.bool("enabled", True),
        hand_distance=s.float("hand_distance", 0.05, min=0.0, max=0.5, strict_min=True),
        min_command_rate=s.float("min_command_rate", 1000.0, min=0.0, max=1e5),
        check_period=check,
        image_period=s.float("image_period", 0.1, min=control.perception_period, max=2.0),
        recovery=s.float("recovery", 1.0, min=0.0, max=60.0),
    )


def perturbed(scenario: CellScenario, seed: int) -> tuple[CellScenario, Applied]:
    """``scenario`` as run ``seed`` sees it (`tamp.perturbation`): each object moved
    by its drawn offset inside its workspace (redrawn up to `REDRAWS` times when it would
    stick out or overlap another object, moved or still nominal, else kept nominal with a
    note: so the start stays valid), and the sample kept for what the diagram applies
    (friction, depth noise, the person's reaction times, grasp attempts that fail). The
    `Applied` record lists all of it but the person's times (`simulate_lots` adds those).
    Nothing is mutated."""
    seed = check_seed(seed)
    sample = scenario.perturbation.sample(seed)
    applied = Applied(seed=seed)
    placed: list[CellObject] = []
    for i, o in enumerate(scenario.objects):
        others = placed + list(scenario.objects[i + 1 :])  # moved ones and nominal ones
        moved, offset = o, (0.0, 0.0, 0.0)
        if scenario.perturbation.objects.active:
            w = scenario.workspaces[o.workspace]
            for attempt in range(REDRAWS):
                dx, dy, dyaw = sample.object_offset(o.id, attempt)
                c = dataclasses.replace(o, xy=(o.xy[0] + dx, o.xy[1] + dy), yaw=o.yaw + dyaw)
                corners = CLASSES[c.cls].footprint.corners(*c.xy, c.yaw)
                inside = all(w.contains(*p) for p in corners)
                if inside and not any(
                    rectangles_overlap(
                        corners, CLASSES[p.cls].footprint.corners(*p.xy, p.yaw), 0.01
                    )
                    for p in others
                ):
                    moved, offset = c, (dx, dy, dyaw)
                    break
            else:
                applied.notes.append(f"{o.id}: no free start in {REDRAWS} draws; nominal kept")
        applied.objects[o.id] = offset
        placed.append(moved)
    applied.friction = sample.friction
    applied.depth_noise = scenario.perturbation.depth_noise
    for name in scenario.perturbation.skill_failure:
        draws = sample.skill_failures(name)
        applied.skill_failures[name] = [i + 1 for i, fails in enumerate(draws) if fails]
    out = dataclasses.replace(scenario, objects=tuple(placed), sample=sample)
    return out, applied


def _pixels(f: Fields, key: str, default: int) -> int:
    value = f.int(key, default, min=32)
    if value > 1280:
        raise f.error(key, f"at most 1280 pixels, got {value}")
    return value


def _number(value, file: str, field: str, lo: float, hi: float) -> float:
    from tamp.fileio import check_number

    return check_number(value, file, field, lo, hi)


def _check_reach(f: Fields, key: str, xy: tuple[float, float]) -> None:
    r = math.hypot(*xy)
    if not REACH[0] <= r <= REACH[1]:
        raise f.error(key, f"{list(xy)} is {r:.2f} m from the arm; keep within {list(REACH)} m")


def _objects(f: Fields, workspaces: dict[str, Workspace]) -> tuple[CellObject, ...]:
    out: list[CellObject] = []
    per_class: dict[str, int] = {}
    for i, item in enumerate(f.items("objects", [])):
        if not isinstance(item, Fields):
            raise InputError("each object must be a mapping", file=f.file, field=f"objects[{i}]")
        item.check_keys({"id", "class", "workspace", "xy", "yaw", "color"})
        cls = item.str("class", choices=CLASSES)
        n = per_class.get(cls, 0)
        per_class[cls] = n + 1
        uid = item.str("id", f"{cls}_{n}")
        if any(o.id == uid for o in out):
            raise item.error("id", f"duplicate object id {uid!r}")
        side = item.str("workspace", choices=SIDES)
        w = workspaces[side]
        dx, dy = item.vector("xy", 2)
        x, y = w.center[0] + dx, w.center[1] + dy
        yaw = math.radians(item.float("yaw", 0.0, min=-360.0, max=360.0))
        if not all(w.contains(*c) for c in CLASSES[cls].footprint.corners(x, y, yaw)):
            raise item.error("xy", f"the {cls} at {[dx, dy]} sticks out of W^{side}")
        palette = CLASSES[cls].palette
        if item.has("color"):
            rgb = item.vector("color", 3)
            if not all(0.0 <= v <= 1.0 for v in rgb):
                raise item.error("color", f"RGB values must lie in [0, 1], got {list(rgb)}")
        else:
            rgb = palette[n % len(palette)]
        out.append(CellObject(uid, cls, side, (x, y), yaw, tuple(rgb)))
    for i, o in enumerate(out):
        corners = CLASSES[o.cls].footprint.corners(*o.xy, o.yaw)
        for p in out[:i]:
            other = CLASSES[p.cls].footprint.corners(*p.xy, p.yaw)
            if rectangles_overlap(corners, other, gap=0.01):
                raise InputError(
                    f"{o.id} and {p.id} overlap (footprints closer than 1 cm)",
                    file=f.file,
                    field=f"objects[{i}]",
                )
    return tuple(out)


def _square(center, sx: float, sy: float | None = None) -> np.ndarray:
    """Corners of an axis-aligned rectangle of half-sides (sx/2, sy/2) around ``center``;
    with one size, ``sx`` is the half-side itself."""
    hx, hy = (sx, sx) if sy is None else (sx / 2, sy / 2)
    x, y = center
    return np.array([[x - hx, y - hy], [x + hx, y - hy], [x + hx, y + hy], [x - hx, y + hy]])


def rectangles_overlap(a: np.ndarray, b: np.ndarray, gap: float = 0.0) -> bool:
    """Whether two convex polygons (corners N x 2, in order) come closer than ``gap``
    (separating-axis test on the edge normals of both)."""
    for poly in (a, b):
        for k in range(len(poly)):
            edge = poly[(k + 1) % len(poly)] - poly[k]
            n = np.array([-edge[1], edge[0]]) / np.linalg.norm(edge)
            pa, pb = a @ n, b @ n
            if pa.max() + gap <= pb.min() or pb.max() + gap <= pa.min():
                return False
    return True
