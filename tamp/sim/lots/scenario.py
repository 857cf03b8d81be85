"""LOTS workcell scenario files (``tamp/scenarios/lots_sim/*.yaml``), loaded strictly.

A scenario says where the two workspaces W^A and W^B and the waste basket are, which
objects lie where at the start, and the plant, camera, control and grasp settings. Each
section is a dataclass read by the typed loader (`tamp.schema`): every field states its
default, bounds and unit once, here; relations between fields are the ``check`` methods.
Every error names the file and the field (``FILE: dotted.field: reason``); the CLI exits
with status 2. No Drake import here. Example (``tamp/scenarios/lots_sim/model_building.yaml``)::

    version: 1
    name: model_building
    plant: {time_step: 0.004, contact_model: hydroelastic_with_fallback}
    camera: {width: 320, height: 180, fov_y_deg: 42.5}
    control: {period: 0.01, perception_period: 0.02, speed: 0.35, look_height: 0.47}
    safety: {hand_distance: 0.05, min_command_rate: 1000}   # optional
    grasp: {network: hrgnet, attempts: 3, descent: {preset_height: 0.2}}
    workspaces:
      A: {center: [0.5, 0.25], size: [0.34, 0.34]}
      B: {center: [0.5, -0.25], size: [0.34, 0.34]}
    waste_basket: [0.2, -0.58]
    objects:                       # xy relative to the workspace centre, yaw in degrees
      - {class: saw, workspace: A, xy: [0.0, 0.11], yaw: 3}

A scenario may declare a stack (Zhou et al. Fig. 10's tower, `tamp.sim.lots.stack`): the
classes stacked in W^B, base first; placing an object of one of them in W^B puts it on the
object of the class before it, and the run is judged by the stack's height on the plant::

    stack: [bottom, body, peak]

A scenario may declare object classes of its own beside the packaged tools
(`tamp.sim.lots.catalogue.CLASSES`) and use them in ``objects`` (and a LOTS task's
propositions, a person's ``add`` events) like a packaged one::

    classes:
      widget:                      # a lower-case identifier, not a packaged class's name
        sdf: models/widget.sdf     # relative to this file, or package://tamp_models/...
        palette: [[0.9, 0.1, 0.1], [0.1, 0.2, 0.9]]   # instance colours (default: the SDF's)
    objects:
      - {class: widget, workspace: A, xy: [0.0, 0.0]}

The SDF holds one model of one link, its origin on the table under the object's centre, of
box, cylinder or sphere geometry (the footprint the placement checks and the person use is
read from it); its primary colour (the first visual's ``<diffuse>``) is replaced per
instance by the palette's colours, as on the packaged tools.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tamp import scenarios
from tamp.errors import InputError, short_repr
from tamp.fileio import Fields, load_yaml
from tamp.grasp.networks import DEFAULT_NETWORK, NETWORKS
from tamp.lots.task import CLASS_NAME
from tamp.perturbation import NONE, Applied, Perturbation, check_seed, parse_perturbation
from tamp.schema import load_dataclass, spec
from tamp.sim.core.models import DETECTORS, model_path
from tamp.sim.lots.catalogue import ARM, CLASSES, ObjectClass, read_object_class

CONTACT_MODELS = ("point", "hydroelastic_with_fallback", "hydroelastic")
SIDES = ("A", "B")
#: what reads the wrist camera's views (`CameraSettings.detector`)
#: Where each network's shipped weights are (relative to the repository's models/ folder).
DEFAULT_WEIGHTS = {name: net.weights for name, net in NETWORKS.items()}
#: The arm's comfortable reach on the table (Franka: 0.855 m from joint 2; keep a margin).
REACH = (0.25, 0.75)
BASKET_HALF = 0.12  # lots_waste_basket.sdf: 0.24 x 0.24 m
TRAY_FLOOR = 0.01  # lots_tray.sdf: its floor's top above the table (m)
TRAY_INSIDE = 0.24  # lots_tray.sdf: the sides of its floor between the walls (m)
TRAY_OUTSIDE = 0.26  # lots_tray.sdf: the sides of its outer walls (m)
#: the sides of a workspace (m): one wrist-camera view covers it
WORKSPACE_SIDES = (0.1, 0.4)
#: the ``perturbation`` fields this workcell simulates: start poses of the objects and their
#: friction (`perturbed`, `tamp.sim.lots.plant`), the camera's depth noise
#: (`tamp.sim.core.camera.DepthNoise`), the person's reaction times (`tamp.sim.lots.person`)
#: and chance failures of grasp attempts (`tamp.sim.lots.skills`)
PERTURBED = ("objects", "friction", "sensor", "timing", "skills")
#: the skills whose attempts ``perturbation.skills`` may make fail
CHANCE_SKILLS = ("Pick",)
#: how often a start offset that leaves the workspace or overlaps is redrawn
REDRAWS = 20


@dataclass(frozen=True, kw_only=True)
class Workspace:
    """A rectangular workspace on the table (W^A or W^B): centre and size in metres.

    ``name`` is the side (the key under ``workspaces``), not a field of the section."""

    name: str = ""
    center: tuple[float, float] = spec(unit="m", help="centre on the table (arm base frame)")
    size: tuple[float, float] = spec(unit="m", help="sides along x and y")
    tray: bool = spec(False, help="Example 1's basket: a shallow tray welded on W^B")

    @property
    def floor(self) -> float:
        """Where an object put down here rests: the table, or the tray's floor (1 cm up)."""
        return TRAY_FLOOR if self.tray else 0.0

    @property
    def floor_size(self) -> tuple[float, float]:
        """The sides of the floor an object is put down on (centred on the workspace): the
        whole workspace, or the tray's floor between its walls (an object reaching over a
        wall lands on it and tips out)."""
        if not self.tray:
            return self.size
        return (min(self.size[0], TRAY_INSIDE), min(self.size[1], TRAY_INSIDE))

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        cx, cy = self.center
        return abs(x - cx) <= self.size[0] / 2 - margin and abs(y - cy) <= self.size[1] / 2 - margin

    def on_floor(self, x: float, y: float) -> bool:
        """Whether (x, y) lies over the floor an object is put down on (`floor_size`)."""
        (cx, cy), (sx, sy) = self.center, self.floor_size
        return abs(x - cx) <= sx / 2 and abs(y - cy) <= sy / 2

    def check(self, f: Fields) -> None:
        lo, hi = WORKSPACE_SIDES
        if not all(lo <= s <= hi for s in self.size):
            raise f.error(
                "size", f"workspace sides must be within [{lo}, {hi}] m, got {list(self.size)}"
            )
        _check_reach(f, "center", self.center)


@dataclass(frozen=True)
class CellObject:
    """One object: unique id, class, workspace, position in the table frame, yaw, colour."""

    id: str
    cls: str
    workspace: str
    xy: tuple[float, float]
    yaw: float
    rgb: tuple[float, float, float]


@dataclass(frozen=True, kw_only=True)
class ObjectEntry:
    """One item of ``objects:`` as the file writes it (placed by `place_objects`)."""

    cls: str = spec(key="class", help="a packaged class or one of the scenario's ``classes``")
    id: str | None = spec(None, help="unique id (default: <class>_<n>, n counting from 0)")
    workspace: str = spec(choices=SIDES, help="the workspace it lies in")
    xy: tuple[float, float] = spec(unit="m", help="position relative to the workspace centre")
    yaw: float = spec(0.0, min=-360.0, max=360.0, unit="deg")
    color: tuple[float, float, float] | None = spec(
        None, help="RGB in [0, 1] (default: the next colour of the class's palette)"
    )

    def check(self, f: Fields) -> None:
        if self.color is not None and not all(0.0 <= v <= 1.0 for v in self.color):
            raise f.error("color", f"RGB values must lie in [0, 1], got {list(self.color)}")


@dataclass(frozen=True)
class ClassEntry:
    """One entry of ``classes:`` (module docstring): an object class the scenario declares."""

    sdf: str = spec(
        help="the SDFormat file: a path relative to the scenario file, or a "
        "package://tamp_models/... URL"
    )
    palette: tuple[tuple[float, float, float], ...] = spec(
        (),
        min=0.0,
        max=1.0,
        min_items=1,
        help="instance colours, RGB in [0, 1], used in turn (default: the SDF's own colour)",
    )


def _classes(raw: Any, f: Fields, key: str) -> dict[str, ObjectClass]:
    """``classes``: each entry's SDF read into an `ObjectClass` (`read_object_class`)."""
    section = f.sub(key)
    out = {}
    for name in section.data:
        if not isinstance(name, str) or not CLASS_NAME.match(name):
            where = short_repr(str(name), 40).strip("'")
            raise section.error(where, "class names are lower-case identifiers")
        if name in CLASSES:
            raise section.error(name, f"a packaged class is named {name!r}: choose another name")
        entry_f = section.sub(name)
        entry = load_dataclass(ClassEntry, entry_f)
        path = model_path(entry.sdf, Path(f.file).parent, entry_f)
        try:
            c = read_object_class(name, path, path.as_uri(), entry.palette)
        except ValueError as exc:
            raise entry_f.error("sdf", f"{path.name}: {exc}") from None
        fp, opening = c.footprint, 2 * ARM.finger_max
        if min(fp.xmax - fp.xmin, fp.ymax - fp.ymin) > opening:
            raise entry_f.error(
                "sdf",
                f"{path.name}: wider than the gripper opens ({opening:g} m) both ways: "
                f"{fp.xmax - fp.xmin:g} x {fp.ymax - fp.ymin:g} m",
            )
        out[name] = c
    return out


@dataclass(frozen=True)
class PlantSettings:
    """The fields of Drake's ``MultibodyPlantConfig`` this cell sets (discrete SAP plant,
    `tamp.sim.core.plant.add_sap_plant`)."""

    time_step: float = spec(0.002, min=0.0005, max=0.01, unit="s", help="discrete plant step")
    contact_model: str = spec("hydroelastic_with_fallback", choices=CONTACT_MODELS)


@dataclass(frozen=True)
class CameraSettings:
    """The wrist camera (D435-like colour intrinsics). See docs/lots_workcell.md for why 320x180."""

    width: int = spec(320, min=32, max=1280, unit="px")
    height: int = spec(180, min=32, max=1280, unit="px")
    fov_y_deg: float = spec(42.5, min=10.0, max=120.0, unit="deg", help="vertical field of view")
    near: float = spec(0.03, min=0.005, max=0.2, unit="m", help="nearest rendered depth")
    far: float = spec(2.0, min=0.5, max=10.0, unit="m", help="farthest rendered depth")
    detector: str = spec(
        "oracle",
        choices=DETECTORS,
        help="what reads the views: the renderer's labels as a perfect detector (oracle), or "
        "the learned detector on colour + depth (`tamp.sim.core.detector`, shipped weights)",
    )


@dataclass(frozen=True)
class ControlSettings:
    """Skill controller rate, perception update rate, TCP speed and the look height (camera)."""

    period: float = spec(0.01, min=0.0, strict_min=True, max=0.05, unit="s", help="skill tick")
    perception_period: float = spec(0.02, max=0.5, unit="s", help="perception update")
    speed: float = spec(0.35, min=0.0, strict_min=True, max=1.0, unit="m/s", help="TCP speed")
    look_height: float = spec(0.45, min=0.3, max=0.6, unit="m", help="camera over a workspace")
    command_period: float = spec(
        0.001, min=0.0001, unit="s", help="the arm command stream (`tamp.sim.lots.command`)"
    )

    def check(self, f: Fields) -> None:
        if self.perception_period < self.period:
            raise f.error(
                "perception_period",
                f"must be >= control.period ({self.period:g} s), got {self.perception_period}",
            )
        if self.command_period > self.period:
            raise f.error(
                "command_period",
                f"must be <= control.period ({self.period:g} s), got {self.command_period}",
            )


@dataclass(frozen=True)
class SafetySettings:
    """The safety monitor (Zhou et al. §IV-C, `tamp.sim.lots.safety`): stop while a foreign depth
    point (not the table, the arm or what it holds) is closer than ``hand_distance`` to the
    end effector; emergency stop when the arm command
    stream falls below ``min_command_rate`` or a joint speed/acceleration limit is exceeded,
    held at least ``recovery`` seconds. Limits are checked every ``check_period``; while a
    person is present, the monitor's depth camera renders every ``image_period``."""

    enabled: bool = spec(True)
    hand_distance: float = spec(0.05, min=0.0, strict_min=True, max=0.5, unit="m")
    min_command_rate: float = spec(1000.0, min=0.0, max=1e5, unit="Hz")
    check_period: float = spec(0.01, max=0.1, unit="s")
    #: 100 Hz: the person's hand at 1.2 m/s is caught before the arm reaches it
    #: (`tamp.sim.lots.depth_safety`)
    image_period: float = spec(0.01, max=2.0, unit="s")
    recovery: float = spec(1.0, min=0.0, max=60.0, unit="s")


#: where a pick's grasps come from: the grasp network, or no network (`tamp.sim.lots.grasping.
#: mask_axis_grasps`: closing across the target mask's principal axis, a control)
PREDICTORS = ("network", "mask_axis")
#: how the hand goes from the preset height to the grasp (`DescentSettings.approach`)
APPROACHES = ("closed", "open")


@dataclass(frozen=True)
class DescentSettings:
    """The closed-loop descent of a pick (Zhou et al. §IV-B, Fig. 6; `tamp.sim.lots.descent`):
    the hand moves down towards the target keeping it centred, takes a view every
    ``view_period`` and fuses the last ``window`` views' grasps; it explores (descends at
    ``explore_speed``, the camera shifted ``explore_shift`` sideways) while the fused grasp is
    uncertain and commits (descends at ``commit_speed``) once at least ``min_views`` views
    agree within ``max_spread`` and ``max_angle_spread`` with a mean quality of at least
    ``min_quality``; at ``preset_height`` it hovers at most ``hover`` seconds for confidence,
    else the attempt fails. The final approach from there to the grasp is ``closed`` loop
    (views go on while the hand comes down and the grasp moves with the target,
    `tamp.sim.lots.skills`) or ``open`` (fixed moves from the last view)."""

    preset_height: float = spec(
        0.2,
        min=0.15,
        max=0.3,  # below every control.look_height
        unit="m",
        help="camera above the target's top: the paper's 0.2 m",
    )
    view_period: float = spec(
        0.2, min=0.02, max=2.0, unit="s", help="sim time between frames of the descent"
    )
    explore_speed: float = spec(
        0.05, min=0.0, strict_min=True, max=0.5, unit="m/s", help="descent while uncertain"
    )
    commit_speed: float = spec(
        0.3, min=0.0, strict_min=True, max=1.0, unit="m/s", help="descent once confident"
    )
    accel: float = spec(0.8, min=0.05, max=5.0, unit="m/s^2", help="TCP acceleration bound")
    explore_shift: float = spec(
        0.03, min=0.0, max=0.08, unit="m", help="sideways camera offset while uncertain"
    )
    window: int = spec(6, min=1, max=20, help="views fused (the latest ones)")
    min_views: int = spec(3, min=1, max=20, help="views with a grasp needed for confidence")
    max_spread: float = spec(
        0.008, min=0.0, strict_min=True, unit="m", help="RMS spread of the fused grasp centres"
    )
    max_angle_spread: float = spec(
        15.0, min=0.0, strict_min=True, max=90.0, unit="deg", help="spread of closing angles"
    )
    min_quality: float = spec(0.3, min=0.0, max=2.0, help="mean quality of the fused grasps")
    hover: float = spec(
        1.5, min=0.0, max=30.0, unit="s", help="extra views at the lowest point before failing"
    )
    approach: str = spec(
        "closed",
        choices=APPROACHES,
        help="the final approach: closed (views on the way down, the grasp follows the target) "
        "or open (fixed moves from the last view)",
    )

    def check(self, f: Fields) -> None:
        if self.min_views > self.window:
            raise f.error("min_views", f"must be <= window ({self.window}), got {self.min_views}")
        if self.commit_speed < self.explore_speed:
            raise f.error(
                "commit_speed",
                f"must be >= explore_speed ({self.explore_speed:g} m/s), got {self.commit_speed}",
            )


@dataclass(frozen=True)
class GraspSettings:
    """Which network (`tamp.grasp.networks`) and weights (default: the shipped ones), or no
    network (``predictor: mask_axis``), whether the network's grasps are post-processed on the
    target's mask (`tamp.sim.lots.grasping`: ``snap_to_mask``, ``seated``,
    ``clear_of_others``), the closed-loop descent, attempts."""

    network: str = spec(DEFAULT_NETWORK, choices=tuple(NETWORKS))
    weights: str | None = spec(
        None, parse=lambda raw, f, key: _weights_file(f, key), help="weights file"
    )
    predictor: str = spec("network", choices=PREDICTORS, help="where the grasps come from")
    post_process: bool = spec(True, help="snap, seat and check the jaws' sweep on the mask")
    descent: DescentSettings = spec(DescentSettings)
    attempts: int = spec(3, min=1)

    def check(self, f: Fields) -> None:
        if self.weights is None and self.network not in DEFAULT_WEIGHTS:
            raise f.error("network", f"no shipped weights for {self.network!r}: give grasp.weights")


def _weights_file(f: Fields, key: str) -> str:
    """``grasp.weights``: a file relative to the scenario file (else to the working directory)."""
    weights = f.str(key)
    local = Path(f.file).parent / weights
    weights = str(local if local.exists() else weights)
    if not Path(weights).is_file():
        raise f.error(key, f"no weights file {weights!r}")
    return weights


def _workspaces(raw: Any, f: Fields, key: str) -> dict[str, Workspace]:
    """``workspaces``: W^A and W^B, each named by its side."""
    ws = f.sub(key)
    ws.check_keys(SIDES)
    return {
        side: dataclasses.replace(load_dataclass(Workspace, ws.sub(side)), name=side)
        for side in SIDES
    }


def _perturbation(raw: Any, f: Fields, key: str) -> Perturbation:
    """``perturbation`` (`tamp.perturbation`), limited to what this workcell simulates."""
    perturbation = parse_perturbation(f, key)
    perturbation.require(PERTURBED, "LOTS")
    if perturbation.pose_noise > 0:  # nothing estimates poses here: the camera sees counts
        raise f.error(
            f"{key}.sensor.pose_noise",
            "the LOTS workcell estimates no object poses (use sensor.depth_noise)",
        )
    for name in perturbation.skill_failure:
        if name not in CHANCE_SKILLS:
            raise f.error(
                f"{key}.skills.{name}",
                f"only {', '.join(CHANCE_SKILLS)} attempts can fail by chance in the LOTS workcell",
            )
    return perturbation


@dataclass(frozen=True, kw_only=True)
class CellScenario:
    """A loaded, validated LOTS workcell scenario (fields in file order; ``objects`` are
    placed in the table frame by `place_objects`, ``source`` is the file, ``sample`` the
    run's `PerturbationSample` once `perturbed` drew it)."""

    name: str = spec(help="the scenario's name (a task runs here by default when named alike)")
    description: str = spec("", help="what the scenario is for")
    plant: PlantSettings = spec(PlantSettings)
    camera: CameraSettings = spec(CameraSettings)
    control: ControlSettings = spec(ControlSettings)
    safety: SafetySettings = spec(SafetySettings)
    grasp: GraspSettings = spec(GraspSettings)
    classes: dict[str, ObjectClass] = spec(
        {}, parse=_classes, help="the scenario's own object classes (module docstring)"
    )
    workspaces: dict[str, Workspace] = spec(parse=_workspaces, help="W^A and W^B")
    waste_basket: tuple[float, float] = spec(unit="m", help="centre of the waste basket")
    stack: tuple[str, ...] = spec(
        (),
        help="classes stacked in W^B, base first (Zhou et al. Fig. 10's tower): a place in "
        "W^B puts each on the one before it (`tamp.sim.lots.stack`)",
    )
    max_sim_time: float = spec(600.0, min=0.0, strict_min=True, unit="s")
    perturbation: Perturbation = spec(NONE, parse=_perturbation, help="`tamp.perturbation`")
    objects: tuple[CellObject, ...] = ()
    source: str = ""
    sample: Any = None

    def object(self, uid: str) -> CellObject:
        for o in self.objects:
            if o.id == uid:
                return o
        raise KeyError(uid)

    def object_class(self, name: str) -> ObjectClass:
        """The object class ``name``: one of the scenario's own ``classes`` or a packaged
        one (`tamp.sim.lots.catalogue.CLASSES`)."""
        return self.classes[name] if name in self.classes else CLASSES[name]

    @property
    def class_names(self) -> tuple[str, ...]:
        """Every class an object of this scenario may have: the packaged ones, then its own."""
        return (*CLASSES, *self.classes)

    def check(self, f: Fields) -> None:
        """The relations between sections (the file's own reading order)."""
        time_step, control = self.plant.time_step, self.control
        if control.period < time_step:
            raise f.error(
                "control.period",
                f"must be >= plant.time_step ({time_step:g} s), got {control.period}",
            )
        self._check_safety(f)
        self._check_stack(f)
        if self.workspaces["A"].tray:
            raise f.error("workspaces.A.tray", "only W^B holds Example 1's basket")
        a, b = self.workspaces["A"], self.workspaces["B"]
        if abs(a.center[1] - b.center[1]) < (a.size[1] + b.size[1]) / 2 + 0.1:
            raise f.error(
                "workspaces.B.center",
                "W^A and W^B must lie side by side in y, at least 0.1 m apart (one view each)",
            )
        _check_reach(f, "waste_basket", self.waste_basket)
        for w in self.workspaces.values():
            basket = _square(self.waste_basket, BASKET_HALF)
            if rectangles_overlap(basket, _square(w.center, *w.size), 0.03):
                raise f.error("waste_basket", f"the waste basket lies within 3 cm of W^{w.name}")

    def _check_stack(self, f: Fields) -> None:
        """``stack``: two classes or more, each a class of the scenario, each once."""
        if not self.stack:
            return
        if len(self.stack) < 2:
            raise f.error("stack", f"a stack needs two classes or more, got {list(self.stack)}")
        for c in self.stack:
            if c not in self.class_names:
                raise f.error("stack", f"unknown class {c!r} (classes: {sorted(self.class_names)})")
            if self.stack.count(c) > 1:
                raise f.error("stack", f"{c!r} is named twice: each level is one class")

    def _check_safety(self, f: Fields) -> None:
        control, safety = self.control, self.safety
        if safety.check_period < control.command_period:
            raise f.error(
                "safety.check_period",
                f"must be >= control.command_period ({control.command_period:g} s), "
                f"got {safety.check_period}",
            )
        ticks = control.perception_period / safety.check_period
        if abs(ticks - round(ticks)) > 1e-6:  # the monitor reads perception's frames at its ticks
            raise f.error(
                "safety.check_period",
                f"must divide control.perception_period ({control.perception_period:g} s)",
            )
        if safety.image_period < safety.check_period:  # frames are taken at its ticks
            raise f.error(
                "safety.image_period",
                f"must be >= safety.check_period ({safety.check_period:g} s), "
                f"got {safety.image_period}",
            )


def load_cell_scenario(path: str | Path) -> CellScenario:
    """Load and validate a workcell scenario; `InputError` names file and field."""
    path = scenarios.resolve(path, "lots_sim")  # packaged: tamp/scenarios/lots_sim
    data, file = load_yaml(path, kind="LOTS workcell scenario")
    f = Fields(data, file)
    scenario = load_dataclass(CellScenario, f, extra_keys=("version", "objects"))
    scenario = dataclasses.replace(scenario, source=file)
    return dataclasses.replace(scenario, objects=place_objects(f, scenario))


def place_objects(f: Fields, scenario: CellScenario) -> tuple[CellObject, ...]:
    """The file's ``objects`` (`ObjectEntry`) in the table frame: inside their workspace,
    1 cm apart, ids unique, each instance of a class in the next colour of its palette."""
    out: list[CellObject] = []
    per_class: dict[str, int] = {}
    names = scenario.class_names
    for i, item in enumerate(f.items("objects", [])):
        if not isinstance(item, Fields):
            raise InputError("each object must be a mapping", file=f.file, field=f"objects[{i}]")
        entry = load_dataclass(ObjectEntry, item)
        if entry.cls not in names:
            raise item.error("class", f"expected one of {sorted(names)}, got {entry.cls!r}")
        c = scenario.object_class(entry.cls)
        n = per_class.get(entry.cls, 0)
        per_class[entry.cls] = n + 1
        uid = entry.id or f"{entry.cls}_{n}"
        if any(o.id == uid for o in out):
            raise item.error("id", f"duplicate object id {uid!r}")
        w = scenario.workspaces[entry.workspace]
        dx, dy = entry.xy
        x, y = w.center[0] + dx, w.center[1] + dy
        yaw = math.radians(entry.yaw)
        if not all(w.on_floor(*p) for p in c.footprint.corners(x, y, yaw)):
            where = "the tray in " if w.tray else ""
            raise item.error("xy", f"the {entry.cls} at {[dx, dy]} sticks out of {where}W^{w.name}")
        rgb = entry.color if entry.color is not None else c.palette[n % len(c.palette)]
        out.append(CellObject(uid, entry.cls, w.name, (x, y), yaw, tuple(rgb)))
    for i, o in enumerate(out):
        corners = footprint_corners(scenario, o)
        for p in out[:i]:
            if rectangles_overlap(corners, footprint_corners(scenario, p), gap=0.01):
                raise InputError(
                    f"{o.id} and {p.id} overlap (footprints closer than 1 cm)",
                    file=f.file,
                    field=f"objects[{i}]",
                )
    return tuple(out)


def footprint_corners(scenario: CellScenario, o: CellObject) -> np.ndarray:
    """The corners (4 x 2, table frame) of object ``o``'s footprint where it lies."""
    return scenario.object_class(o.cls).footprint.corners(*o.xy, o.yaw)


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
                corners = footprint_corners(scenario, c)
                inside = all(w.on_floor(*p) for p in corners)
                if inside and not any(
                    rectangles_overlap(corners, footprint_corners(scenario, p), 0.01)
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
    applied.detector = scenario.perturbation.detector
    for name in scenario.perturbation.skill_failure:
        draws = sample.skill_failures(name)
        applied.skill_failures[name] = [i + 1 for i, fails in enumerate(draws) if fails]
    out = dataclasses.replace(scenario, objects=tuple(placed), sample=sample)
    return out, applied


def _check_reach(f: Fields, key: str, xy: tuple[float, float]) -> None:
    r = math.hypot(*xy)
    if not REACH[0] <= r <= REACH[1]:
        raise f.error(key, f"{list(xy)} is {r:.2f} m from the arm; keep within {list(REACH)} m")


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
