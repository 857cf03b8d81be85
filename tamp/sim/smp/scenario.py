"""Simulation scenario files (``tamp/scenarios/sim/*.yaml``): which demonstration, models,
initial poses, plant and executor settings, objects that appear during execution, and
scripted skill failures. Loaded strictly (`tamp.fileio`): every error names the file and
the field and the CLI exits with status 2. No Drake import here.

Appearances and failures are written as the command-line flags write them
(`tamp.world.events`, the run vocabulary): ``appear`` lists ``OBJ@PLACE[@WHEN]`` strings
(PLACE an area name or ``x,y``; WHEN a tick, ``t=SECONDS`` or ``after:Action(args)``;
without WHEN the object appears when the robot first comes within reach of the place), and
``fail`` lists ``ACTION[(ARGS)][xTIMES]`` strings (the first TIMES attempts of the action
fail; only ``Pick`` is simulated, as a lost grasp). `SimScenario.with_events` adds the
same entries from flags. Example (``tamp/scenarios/sim/case3.yaml``)::

    version: 1
    name: case3
    demonstration: ../case3.yaml       # path relative to this file, or a packaged name
    planner: {cost: distance}
    plant: {time_step: 0.01}
    executor: {bt_period: 0.1, controller_period: 0.02, max_sim_time: 300}
    base: {max_speed: 0.5, max_accel: 0.6, max_yaw_rate: 1.2, max_yaw_accel: 2.0}
    workspace: {x: [-1.0, 4.0], y: [-2.0, 2.5]}
    objects:                           # demonstration objects are bottles unless listed
      - {id: Oa, model: obstacle}      # no pose: it appears (below)
    appear: ["Oa@L1@after:Pick(O1)"]   # as --appear; an object not listed is a bottle
    fail: []                           # as --fail, e.g. "Pick(O2)" or "Pick(O2)x2"
    grasp: weld                        # weld | friction (the fingers hold it, SAP contact)
    perception: truth                  # truth (plant poses) | camera (RGB-D on the robot)
    perturbation: {objects: {xy: 0.02}}   # tamp.perturbation, drawn per --seed
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from tamp import scenarios
from tamp.demo import Demonstration, load_demonstration
from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.perturbation import NONE, Perturbation, parse_perturbation
from tamp.sim.smp.placement import Body, blocker
from tamp.sim.smp.robot import OBJECT_KINDS, ROBOT, ObjectKind
from tamp.world.events import AfterAction, Appear, AtTick, AtTime, Fail, parse_appear, parse_fail
from tamp.world.geometry import Area, Point

COSTS = ("distance", "time", "success")
CONTACT_MODELS = ("point", "hydroelastic_with_fallback", "hydroelastic")
SIM_DIR = scenarios.ROOT / "sim"
#: The skills whose failure the simulation can script: a Pick whose weld is not switched on.
SIMULATED_FAILURES = ("Pick",)
GRASPS = ("weld", "friction")
PERCEPTIONS = ("truth", "camera")
#: the perturbation fields the SMP-MRO workcell simulates (`tamp.sim.smp.perturb`)
PERTURBED = ("objects", "robot", "friction", "sensor", "timing", "skills")


@dataclass(frozen=True)
class SimObject:
    """One object of the scene: id, model kind, initial planar pose, optional appearance.

    An object with ``appear`` waits, unseen, outside the workspace until its WHEN (a person
    puts it down at the place: Case 3's O_a at l_1); its ``xy`` is then NaN.
    """

    id: str
    kind: ObjectKind
    xy: tuple[float, float]
    yaw: float = 0.0
    appear: Appear | None = None


@dataclass(frozen=True)
class BaseLimits:
    """Velocity and acceleration limits of the base trajectories (MoveTo and approaches)."""

    max_speed: float = 0.5
    max_accel: float = 0.6
    max_yaw_rate: float = 1.2
    max_yaw_accel: float = 2.0


@dataclass(frozen=True)
class RunConditions:
    """What one seeded run draws beyond poses (`tamp.sim.smp.perturb.perturb`): the seed,
    the objects' friction coefficient (None: the SDFs'), the camera's depth noise and the
    perceived pose noise (m, sigma), and per action the attempts that fail by chance."""

    seed: int = 0
    friction: float | None = None
    depth_noise: float = 0.0
    pose_noise: float = 0.0
    chance_failures: tuple[tuple[str, tuple[bool, ...]], ...] = ()
    #: (id, x, y, yaw) where the robot was shown each object (its camera prior), when the run
    #: moved them; empty: the scenario's own poses
    nominal: tuple[tuple[str, float, float, float], ...] = ()


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
    failures: tuple[Fail, ...] = ()
    grasp: str = "weld"  # weld | friction
    perception: str = "truth"  # truth | camera
    perturbation: Perturbation = NONE
    conditions: RunConditions = RunConditions()

    def object(self, uid: str) -> SimObject:
        for o in self.objects:
            if o.id == uid:
                return o
        raise KeyError(uid)

    @property
    def areas(self) -> dict[str, Area]:
        """Goal areas L_k and free areas of the demonstration, by name."""
        areas = {g.area.name: g.area for g in self.demo.goals}
        areas.update({a.name: a for a in self.demo.free_areas})
        return areas

    def place_of(self, appear: Appear) -> Point:
        """Where an appearing object is put: its area's centre, or the point itself."""
        return self.areas[appear.place].pos if isinstance(appear.place, str) else appear.place

    def in_workspace(self, x: float, y: float, margin: float = 0.0) -> bool:
        xmin, xmax, ymin, ymax = self.workspace
        return xmin + margin <= x <= xmax - margin and ymin + margin <= y <= ymax - margin

    def parking(self, index: int) -> tuple[float, float]:
        """Where an object waits, unseen, before it appears (outside the workspace)."""
        xmin, xmax, ymin, _ = self.workspace
        return (xmax + 1.0 + 0.3 * index, ymin)

    def with_events(self, appear: Sequence[Appear] = (), fail: Sequence[Fail] = ()) -> SimScenario:
        """This scenario with ``--appear`` / ``--fail`` entries added (`tamp.world.events`).

        An ``--appear`` for an object replaces the file's pose or appearance of that object
        (an object the scenario does not know is a bottle); a ``--fail`` for an action
        replaces the file's entry for the same action. Errors name the flag.
        """
        objects = list(self.objects)
        index = {o.id: i for i, o in enumerate(objects)}
        for a in appear:
            _check_appear(self, a, field="--appear", file=None)
            if a.obj in index:
                old = objects[index[a.obj]]
                objects[index[a.obj]] = SimObject(a.obj, old.kind, (math.nan, math.nan), 0.0, a)
            else:
                index[a.obj] = len(objects)
                objects.append(
                    SimObject(a.obj, OBJECT_KINDS["bottle"], (math.nan, math.nan), 0.0, a)
                )
        out = dataclasses.replace(self, objects=tuple(objects))
        _check_start_places(out, {a.obj: ("--appear", None) for a in appear})
        flagged = {(f.action, f.args) for f in fail}
        kept = [f for f in self.failures if (f.action, f.args) not in flagged]
        for f in fail:
            _check_fail(out, f, field="--fail", file=None)
        return dataclasses.replace(out, failures=tuple(kept) + tuple(fail))


def scenario_path(name: str | Path) -> Path:
    """A user path if it exists, else ``tamp/scenarios/sim/<name>`` (``.yaml`` optional)."""
    return scenarios.resolve(name, "sim")


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
            "appear",
            "fail",
            "grasp",
            "perception",
            "perturbation",
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
    perturbation = parse_perturbation(f)
    perturbation.require(PERTURBED, "SMP-MRO")
    for action in perturbation.skill_failure:
        if action not in SIMULATED_FAILURES:
            raise f.error(
                f"perturbation.skills.{action}",
                f"only {', '.join(SIMULATED_FAILURES)} failures (lost grasps) are simulated",
            )
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
        grasp=f.str("grasp", "weld", choices=GRASPS),
        perception=f.str("perception", "truth", choices=PERCEPTIONS),
        perturbation=perturbation,
    )
    scenario = _appearances(scenario, f)
    scenario = dataclasses.replace(scenario, failures=_failures(scenario, f))
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
    """Demonstration objects (bottles at P unless listed) and listed ones; an object with
    no pose gets one from ``appear`` (`_appearances`), until then its ``xy`` is NaN."""
    listed: dict[str, Fields] = {}
    for i, item in enumerate(f.items("objects", [])):
        if not isinstance(item, Fields):
            raise InputError("each object must be a mapping", file=f.file, field=f"objects[{i}]")
        item.check_keys({"id", "model", "pose"})
        uid = item.str("id")
        if uid in listed:
            raise item.error("id", f"duplicate object {uid!r}")
        listed[uid] = item

    out: list[SimObject] = []
    for uid, p in demo.objects.items():
        kind, xy, yaw = OBJECT_KINDS["bottle"], (p.x, p.y), 0.0
        if uid in listed:
            item = listed.pop(uid)
            kind = _kind(item)
            if item.has("pose"):
                x, y, yaw = item.vector("pose", 3)
                xy = (x, y)
        out.append(SimObject(uid, kind, xy, yaw))
    for uid, item in listed.items():
        xy, yaw = (math.nan, math.nan), 0.0
        if item.has("pose"):
            x, y, yaw = item.vector("pose", 3)
            xy = (x, y)
        out.append(SimObject(uid, _kind(item), xy, yaw))
    return tuple(out)


def _kind(item: Fields) -> ObjectKind:
    model = item.str("model", "bottle")
    if model not in OBJECT_KINDS:
        raise item.error("model", f"unknown model {model!r} (known: {', '.join(OBJECT_KINDS)})")
    return OBJECT_KINDS[model]


def _appearances(s: SimScenario, f: Fields) -> SimScenario:
    """The file's ``appear`` entries on the objects; every object without a pose needs one."""
    objects = {o.id: o for o in s.objects}
    for i, text in enumerate(f.items("appear", [])):
        field = f"appear[{i}]"
        if not isinstance(text, str):
            raise InputError("expected OBJ@PLACE[@WHEN] as a string", file=f.file, field=field)
        a = parse_appear(text, field=field, file=f.file)
        _check_appear(s, a, field=field, file=f.file)
        old = objects.get(a.obj)
        if old is not None and old.appear is not None:
            raise InputError(f"{a.obj} already appears", file=f.file, field=field)
        if old is not None and not math.isnan(old.xy[0]):
            raise InputError(
                f"{a.obj} has a pose (objects); give either pose or appear",
                file=f.file,
                field=field,
            )
        kind = old.kind if old is not None else OBJECT_KINDS["bottle"]
        objects[a.obj] = SimObject(a.obj, kind, (math.nan, math.nan), 0.0, a)
    for j, item in enumerate(f.raw("objects", []) or []):
        uid = item.get("id")
        if objects[uid].appear is None and math.isnan(objects[uid].xy[0]):
            raise InputError(
                f"object {uid} is not in the demonstration: it needs a pose or an appear entry",
                file=f.file,
                field=f"objects[{j}].pose",
            )
    return dataclasses.replace(s, objects=tuple(objects.values()))


def _check_appear(s: SimScenario, a: Appear, *, field: str, file: str | None) -> None:
    """An appearance the simulation can stage: a new object, a known place, a known skill."""
    if a.obj in s.demo.objects:
        raise InputError(
            f"{a.obj} is a demonstration object, there from the start (moving it is not simulated)",
            file=file,
            field=field,
        )
    areas = s.areas
    if isinstance(a.place, str):
        if a.place not in areas:
            raise InputError(
                f"unknown area {a.place!r} (known: {', '.join(sorted(areas))})",
                file=file,
                field=field,
            )
    elif not s.in_workspace(a.place.x, a.place.y):
        raise InputError(
            f"({a.place.x:g}, {a.place.y:g}) lies outside the workspace", file=file, field=field
        )
    if isinstance(a.when, AfterAction):
        known = set(s.demo.domain().templates)
        if a.when.name not in known:
            raise InputError(
                f"after: unknown action {a.when.name!r} (known: {', '.join(sorted(known))})",
                file=file,
                field=field,
            )


def _failures(s: SimScenario, f: Fields) -> tuple[Fail, ...]:
    out: list[Fail] = []
    for i, text in enumerate(f.items("fail", [])):
        field = f"fail[{i}]"
        if not isinstance(text, str):
            raise InputError(
                "expected ACTION[(ARGS)][xTIMES] as a string", file=f.file, field=field
            )
        fail = parse_fail(text, field=field, file=f.file)
        _check_fail(s, fail, field=field, file=f.file)
        if any((g.action, g.args) == (fail.action, fail.args) for g in out):
            raise InputError(f"{fail.action} is listed twice", file=f.file, field=field)
        out.append(fail)
    return tuple(out)


def _check_fail(s: SimScenario, fail: Fail, *, field: str, file: str | None) -> None:
    """A failure the simulation can script: a lost grasp, ``Pick`` or ``Pick(<object>)``."""
    if fail.action not in SIMULATED_FAILURES:
        raise InputError(
            f"only Pick failures (lost grasps) are simulated, got {fail.action}",
            file=file,
            field=field,
        )
    if fail.args is not None:
        ids = {o.id for o in s.objects}
        if len(fail.args) != 1 or fail.args[0] not in ids:
            raise InputError(
                f"Pick takes one object of the scene ({', '.join(sorted(ids))}), got {fail}",
                file=file,
                field=field,
            )


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
    fields = {}
    for i, text in enumerate(f.raw("appear", []) or []):
        fields[parse_appear(text, field=f"appear[{i}]", file=s.source).obj] = (
            f"appear[{i}]",
            s.source,
        )
    _check_start_places(s, fields)


def at_start(appear: Appear) -> bool:
    """Whether an appearance happens at time 0 (tick 0 or ``t=0``), before anything moves."""
    when = appear.when
    return (isinstance(when, AtTick) and when.tick == 0) or (
        isinstance(when, AtTime) and when.seconds == 0.0
    )


def _check_start_places(s: SimScenario, fields: dict[str, tuple[str, str | None]]) -> None:
    """Refuse an appearance at time 0 onto a place that is certainly occupied then: by an
    object standing there from the start, an earlier appearance at time 0, or the robot.

    Later appearances can only be checked when they happen (the runner puts the object
    down on the nearest free spot instead, with a warning: `tamp.sim.smp.runner`).
    ``fields``: object id -> (field, file) that names its appearance in errors.
    """
    rx, ry, _ = s.robot_start
    standing = [
        Body(o.id, o.xy[0], o.xy[1], o.kind.half_height, o.kind)
        for o in s.objects
        if o.appear is None
    ]
    for o in s.objects:
        if o.appear is None or not at_start(o.appear):
            continue
        p = s.place_of(o.appear)
        who = blocker(p.x, p.y, o.kind, standing, (rx, ry, ROBOT.footprint_radius))
        if who is not None:
            field, file = fields.get(o.id) or fields.get(who) or ("appear", s.source)
            raise InputError(
                f"{o.appear}: the place is occupied by {who} at the start "
                f"(an object cannot appear inside another)",
                file=file,
                field=field,
            )
        standing.append(Body(o.id, p.x, p.y, o.kind.half_height, o.kind))
