"""Simulation scenario files (``tamp/scenarios/sim/*.yaml``): which demonstration, models,
initial poses, plant and executor settings, objects that appear during execution, and
scripted skill failures. Loaded strictly (`tamp.fileio`): every error names the file and
the field and the CLI exits with status 2. No Drake import here.

Example (``tamp/scenarios/sim/case3.yaml``)::

    version: 1
    name: case3
    demonstration: ../case3.yaml       # path relative to this file, or a packaged name
    planner: {cost: distance}
    plant: {time_step: 0.01}
    executor: {bt_period: 0.1, controller_period: 0.02, max_sim_time: 300}
    base: {max_speed: 0.5, max_accel: 0.6, max_yaw_rate: 1.2, max_yaw_accel: 2.0}
    workspace: {x: [-1.0, 4.0], y: [-2.0, 2.5]}
    objects:                           # demonstration objects are bottles unless listed
      - {id: Oa, model: obstacle, appear: {area: L1, after: "Pick(O1)"}}
    failures: []                       # e.g. {action: "Pick(O0)", attempts: [1]}
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from tamp import scenarios
from tamp.demo import Demonstration, load_demonstration
from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.sim.smp.robot import OBJECT_KINDS, ROBOT, ObjectKind

COSTS = ("distance", "time", "success")
CONTACT_MODELS = ("point", "hydroelastic_with_fallback", "hydroelastic")
SIM_DIR = scenarios.ROOT / "sim"
_ACTION = re.compile(r"^\s*(MoveTo|Pick|Place)\s*\(\s*([^()]*)\)\s*$")


def parse_action(text: str) -> tuple[str, tuple[str, ...]] | None:
    """``"Pick(O1)"`` -> ``("Pick", ("O1",))``; None when it is not an action of the domain."""
    m = _ACTION.match(str(text))
    if not m:
        return None
    return m.group(1), tuple(a.strip() for a in m.group(2).split(",") if a.strip())


@dataclass(frozen=True)
class Appearance:
    """An object a person puts down during execution (Case 3's O_a at l_1).

    It appears at sim ``time``, or when the skill ``after`` (e.g. ``Pick(O1)``) succeeds,
    centred on area ``area``. Until then it rests outside the workspace, unseen.
    """

    area: str
    time: float | None = None
    after: tuple[str, tuple[str, ...]] | None = None


@dataclass(frozen=True)
class SimObject:
    """One object of the scene: id, model kind, initial planar pose, optional appearance."""

    id: str
    kind: ObjectKind
    xy: tuple[float, float]
    yaw: float = 0.0
    appear: Appearance | None = None


@dataclass(frozen=True)
class InjectedFailure:
    """Scripted skill failure: the listed attempts (1-based) of ``action`` lose their grasp."""

    action: tuple[str, tuple[str, ...]]
    attempts: tuple[int, ...]


@dataclass(frozen=True)
class BaseLimits:
    """Velocity and acceleration limits of the base trajectories (MoveTo and approaches)."""

    max_speed: float = 0.5
    max_accel: float = 0.6
    max_yaw_rate: float = 1.2
    max_yaw_accel: float = 2.0


@dataclass(frozen=True)
class SimScenario:
    """A loaded, validated simulation scenario."""

    name: str
    source: str
    demo: Demonstration
    cost: str
    time_step: float
    contact_model: str
    bt_period: float
    controller_period: float
    max_sim_time: float
    base: BaseLimits
    workspace: tuple[float, float, float, float]  # xmin, xmax, ymin, ymax
    robot_start: tuple[float, float, float]
    objects: tuple[SimObject, ...]
    failures: tuple[InjectedFailure, ...] = ()

    def object(self, uid: str) -> SimObject:
        for o in self.objects:
            if o.id == uid:
                return o
        raise KeyError(uid)

    def in_workspace(self, x: float, y: float, margin: float = 0.0) -> bool:
        xmin, xmax, ymin, ymax = self.workspace
        return xmin + margin <= x <= xmax - margin and ymin + margin <= y <= ymax - margin

    def parking(self, index: int) -> tuple[float, float]:
        """Where an object waits, unseen, before it appears (outside the workspace)."""
        xmin, xmax, ymin, _ = self.workspace
        return (xmax + 1.0 + 0.3 * index, ymin)


def scenario_path(name: str | Path) -> Path:
    """A user path if it exists, else ``tamp/scenarios/sim/<name>`` (``.yaml`` optional)."""
    p = Path(name)
    if p.exists():
        return p
    for cand in (SIM_DIR / str(name), SIM_DIR / f"{name}.yaml"):
        if cand.exists():
            return cand
    return p


def load_scenario(path: str | Path) -> SimScenario:
    """Load and validate a simulation scenario; `InputError` names file and field."""
    data, file = load_yaml(scenario_path(path), kind="simulation scenario")
    f = Fields(data, file)
    f.check_keys(
        {
            "version",
            "name",
            "demonstration",
            "planner",
            "plant",
            "executor",
            "base",
            "workspace",
            "robot",
            "objects",
            "failures",
        }
    )
    name = f.str("name")
    demo = _demonstration(f, Path(file))

    planner = f.sub("planner", {})
    planner.check_keys({"cost"})
    cost = planner.str("cost", "distance", choices=COSTS)

    plant = f.sub("plant", {})
    plant.check_keys({"time_step", "contact_model"})
    time_step = plant.float("time_step", 0.01, min=0.0005, max=0.02)
    contact = plant.str("contact_model", "point", choices=CONTACT_MODELS)

    ex = f.sub("executor", {})
    ex.check_keys({"bt_period", "controller_period", "max_sim_time"})
    controller_period = ex.float("controller_period", 0.02, min=time_step, max=0.1)
    bt_period = ex.float("bt_period", 0.1, min=controller_period, max=1.0)
    max_sim_time = ex.float("max_sim_time", 300.0, min=0.0, strict_min=True)

    b = f.sub("base", {})
    b.check_keys({"max_speed", "max_accel", "max_yaw_rate", "max_yaw_accel"})
    base = BaseLimits(
        max_speed=b.float("max_speed", 0.5, min=0.0, strict_min=True, max=2.0),
        max_accel=b.float("max_accel", 0.6, min=0.0, strict_min=True, max=5.0),
        max_yaw_rate=b.float("max_yaw_rate", 1.2, min=0.0, strict_min=True, max=5.0),
        max_yaw_accel=b.float("max_yaw_accel", 2.0, min=0.0, strict_min=True, max=10.0),
    )

    workspace = _workspace(f, demo)

    robot = f.sub("robot", {})
    robot.check_keys({"start"})
    if robot.has("start"):
        robot_start = robot.vector("start", 3)
    else:
        rs = demo.robot_start
        robot_start = (rs.pos.x, rs.pos.y, rs.orientation.yaw())

    objects = _objects(f, demo, workspace)
    scenario = SimScenario(
        name=name,
        source=file,
        demo=demo,
        cost=cost,
        time_step=time_step,
        contact_model=contact,
        bt_period=bt_period,
        controller_period=controller_period,
        max_sim_time=max_sim_time,
        base=base,
        workspace=workspace,
        robot_start=robot_start,
        objects=objects,
        failures=_failures(f),
    )
    _check_geometry(scenario, f)
    return scenario


def _demonstration(f: Fields, file: Path) -> Demonstration:
    ref = f.str("demonstration")
    local = file.parent / ref
    path = local if local.exists() else scenarios.resolve(ref)
    if not Path(path).exists():
        raise f.error("demonstration", f"no demonstration file {ref!r}")
    return load_demonstration(path)


def _workspace(f: Fields, demo: Demonstration) -> tuple[float, float, float, float]:
    w = f.sub("workspace")
    w.check_keys({"x", "y"})
    x = w.vector("x", 2)
    y = w.vector("y", 2)
    for key, (lo, hi) in (("x", x), ("y", y)):
        if hi - lo < 1.0:
            raise w.error(key, f"workspace must span at least 1 m, got [{lo}, {hi}]")
        if lo < -9.0 or hi > 9.0:
            raise w.error(key, "workspace must lie within [-9, 9] m (the floor)")
    return (x[0], x[1], y[0], y[1])


def _objects(
    f: Fields, demo: Demonstration, workspace: tuple[float, float, float, float]
) -> tuple[SimObject, ...]:
    listed: dict[str, tuple[Fields, int]] = {}
    for i, item in enumerate(f.items("objects", [])):
        if not isinstance(item, Fields):
            raise InputError("each object must be a mapping", file=f.file, field=f"objects[{i}]")
        item.check_keys({"id", "model", "pose", "appear"})
        uid = item.str("id")
        if uid in listed:
            raise item.error("id", f"duplicate object {uid!r}")
        listed[uid] = (item, i)

    areas = {g.area.name for g in demo.goals} | {a.name for a in demo.free_areas}
    out: list[SimObject] = []
    for uid, p in demo.objects.items():
        kind, xy, yaw = OBJECT_KINDS["bottle"], (p.x, p.y), 0.0
        if uid in listed:
            item, _ = listed.pop(uid)
            kind = _kind(item)
            if item.has("pose"):
                x, y, yaw = item.vector("pose", 3)
                xy = (x, y)
            if item.has("appear"):
                raise item.error("appear", "a demonstration object is there from the start")
        out.append(SimObject(uid, kind, xy, yaw))
    for uid, (item, _) in listed.items():
        kind = _kind(item)
        appear = None
        if item.has("appear"):
            appear = _appearance(item.sub("appear"), areas)
        if item.has("pose"):
            if appear is not None:
                raise item.error("pose", "give either pose or appear, not both")
            x, y, yaw = item.vector("pose", 3)
            out.append(SimObject(uid, kind, (x, y), yaw))
        elif appear is not None:
            out.append(SimObject(uid, kind, (math.nan, math.nan), 0.0, appear))
        else:
            raise item.error("pose", "an object not in the demonstration needs pose or appear")
    return tuple(out)


def _kind(item: Fields) -> ObjectKind:
    model = item.str("model", "bottle")
    if model not in OBJECT_KINDS:
        raise item.error("model", f"unknown model {model!r} (known: {', '.join(OBJECT_KINDS)})")
    return OBJECT_KINDS[model]


def _appearance(a: Fields, areas: set[str]) -> Appearance:
    a.check_keys({"area", "time", "after"})
    area = a.str("area")
    if area not in areas:
        raise a.error("area", f"unknown area {area!r} (known: {', '.join(sorted(areas))})")
    has_time, has_after = a.has("time"), a.has("after")
    if has_time == has_after:
        raise a.error("time", "give exactly one of time and after")
    if has_time:
        return Appearance(area, time=a.float("time", min=0.0))
    after = parse_action(a.str("after"))
    if after is None:
        raise a.error("after", "expected an action such as Pick(O1), Place(O1, L1), MoveTo(L1)")
    return Appearance(area, after=after)


def _failures(f: Fields) -> tuple[InjectedFailure, ...]:
    out = []
    for i, item in enumerate(f.items("failures", [])):
        if not isinstance(item, Fields):
            raise InputError("each failure must be a mapping", file=f.file, field=f"failures[{i}]")
        item.check_keys({"action", "attempts"})
        action = parse_action(item.str("action"))
        if action is None or action[0] != "Pick":
            raise item.error("action", "only Pick(<object>) failures (lost grasps) are scripted")
        attempts = []
        for j, a in enumerate(item.items("attempts", [1])):
            if isinstance(a, bool) or not isinstance(a, int) or a < 1:
                raise item.error(f"attempts[{j}]", f"expected an attempt number >= 1, got {a!r}")
            attempts.append(a)
        out.append(InjectedFailure(action, tuple(sorted(set(attempts)))))
    return tuple(out)


def _check_geometry(s: SimScenario, f: Fields) -> None:
    """Objects inside the workspace and apart, goals reachable, the robot clear of objects."""
    index = {o.id: i for i, o in enumerate(s.objects)}

    def field(uid: str) -> str:
        listed = [it for it in f.raw("objects", []) or [] if isinstance(it, dict)]
        for j, it in enumerate(listed):
            if it.get("id") == uid:
                return f"objects[{j}]"
        return f"demonstration (object {uid})"

    placed = [o for o in s.objects if o.appear is None]
    for o in placed:
        if not s.in_workspace(*o.xy, margin=o.kind.radius):
            raise InputError(
                f"object {o.id} at ({o.xy[0]:.2f}, {o.xy[1]:.2f}) lies outside the workspace",
                file=s.source,
                field=field(o.id),
            )
    for a in range(len(placed)):
        for b in range(a + 1, len(placed)):
            oa, ob = placed[a], placed[b]
            d = math.dist(oa.xy, ob.xy)
            if d < oa.kind.radius + ob.kind.radius + 0.005:
                late = oa if index[oa.id] > index[ob.id] else ob
                raise InputError(
                    f"objects {oa.id} and {ob.id} overlap at the start (centres {d:.3f} m apart)",
                    file=s.source,
                    field=field(late.id),
                )
    areas = [(g.id, g.area) for g in s.demo.goals] + [(a.name, a) for a in s.demo.free_areas]
    for gid, area in areas:
        p = area.pos
        if not s.in_workspace(p.x, p.y, margin=area.radius):
            what = f"goal {gid}" if gid.startswith("G") else f"free area {gid}"
            raise InputError(
                f"{what} (area {area.name} at ({p.x:.2f}, {p.y:.2f})) lies outside the "
                f"workspace: unreachable",
                file=s.source,
                field="workspace",
            )
    rx, ry, _ = s.robot_start
    if not s.in_workspace(rx, ry):
        raise InputError("robot start lies outside the workspace", file=s.source, field="robot")
    for o in placed:
        if math.dist((rx, ry), o.xy) < ROBOT.footprint_radius + o.kind.radius:
            raise InputError(
                f"robot start overlaps object {o.id}", file=s.source, field="robot.start"
            )
