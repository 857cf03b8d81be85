"""Simulation scenario files (``tamp/scenarios/sim/*.yaml``): which demonstration, models,
initial poses, plant and executor settings, objects that appear during execution, and
scripted skill failures. No Drake import here.

The file is read by the typed loader (`tamp.schema`) into `ScenarioFile`, whose sections
are dataclasses that state each field's default, bounds and unit once; relations between
fields are their ``check`` methods. `load_scenario` then resolves it into a `SimScenario`
(the demonstration loaded, its objects placed, appearances and failures checked against the
scene, the start geometry checked). Every error names the file and the field
(``FILE: field: reason``, `InputError`) and the CLI exits with status 2.

Appearances and failures are written as the command-line flags write them
(`tamp.world.events`): ``appear`` lists ``OBJ@PLACE[@WHEN]`` strings (PLACE an area name or
``x,y``; WHEN a tick, ``t=SECONDS`` or ``after:Action(args)``; without WHEN the object
appears when the robot first comes within reach of the place), and ``fail`` lists
``ACTION[(ARGS)][xTIMES]`` strings (the first TIMES attempts of the action fail; only
``Pick`` is simulated, as a lost grasp). `SimScenario.with_events` adds the same entries
from flags. An object's ``model`` is a packaged one (``bottle``, ``obstacle``:
`tamp.sim.smp.robot.OBJECT_KINDS`) or one the file declares under ``models:``
(`tamp.sim.smp.object_models`). Example (``tamp/scenarios/sim/case3.yaml``)::

    version: 1
    name: case3
    demonstration: ../case3.yaml       # path relative to this file, or a packaged name
    planner: {cost: distance}
    plant: {time_step: 0.01}
    executor: {bt_period: 0.1, controller_period: 0.02, max_sim_time: 300}
    base: {max_speed: 0.5, max_accel: 0.6, max_yaw_rate: 1.2, max_yaw_accel: 2.0}
    workspace: {x: [-1.0, 4.0], y: [-2.2, 2.8]}
    objects:                           # demonstration objects are bottles unless listed
      - {id: Oa, model: obstacle}      # no pose: it appears (below)
    appear: ["Oa@L1@after:Pick(O1)"]   # as --appear; an object not listed is a bottle
    fail: []                           # as --fail, e.g. "Pick(O2)" or "Pick(O2)x2"
    grasp: weld                        # weld | friction (the fingers hold it, SAP contact)
    perception: truth                  # truth (plant poses) | camera (RGB-D on the robot)
    detector: oracle                   # camera: oracle (label image) | learned (colour + depth)
    perturbation: {objects: {xy: 0.02}}   # tamp.perturbation, drawn per --seed
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tamp import scenarios
from tamp.demo import Demonstration, load_demonstration
from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.perturbation import NONE, Perturbation, parse_perturbation
from tamp.rg.costs import COST_MODELS
from tamp.schema import load_dataclass, spec
from tamp.sim.core.models import DETECTORS
from tamp.sim.smp.object_models import ObjectModel, declared_kinds
from tamp.sim.smp.placement import Body, blocker
from tamp.sim.smp.robot import OBJECT_KINDS, ROBOT, ObjectKind
from tamp.world.events import AfterAction, Appear, AtTick, AtTime, Fail, parse_appear, parse_fail
from tamp.world.geometry import Area, Point

CONTACT_MODELS = ("point", "hydroelastic_with_fallback", "hydroelastic")
SIM_DIR = scenarios.ROOT / "sim"
#: The skills whose failure the simulation can script: a Pick whose weld is not switched on.
SIMULATED_FAILURES = ("Pick",)
GRASPS = ("weld", "friction")
PERCEPTIONS = ("truth", "camera")
#: the perturbation fields the SMP-MRO workcell simulates (`tamp.sim.smp.perturb`)
PERTURBED = ("objects", "robot", "friction", "sensor", "timing", "skills")
#: the model of an object the file does not list (the demonstration's, an appearing one)
DEFAULT_MODEL = "bottle"
#: the shortest plant step, and so the shortest tick of the controller and the tree (s)
MIN_TIME_STEP = 0.0005
#: how far from the origin a workspace may reach, per axis (m)
FLOOR_HALF = 9.0


@dataclass(frozen=True)
class Planner:
    """``planner:``: the RG search's edge cost (SMP-MRO §IV-B2, `tamp.rg.costs`)."""

    cost: str = spec("distance", choices=COST_MODELS, help="edge weight of the RG search")


@dataclass(frozen=True)
class PlantSettings:
    """``plant:``: the MultibodyPlant's discrete step and contact model (SAP solver,
    `tamp.sim.core.plant.add_sap_plant`)."""

    time_step: float = spec(0.01, min=MIN_TIME_STEP, max=0.02, unit="s", help="plant time step")
    contact_model: str = spec("point", choices=CONTACT_MODELS, help="Drake contact model")


@dataclass(frozen=True)
class ExecutorSettings:
    """``executor:``: how often the behaviour tree and the skill controller tick, and how
    long a run may last."""

    bt_period: float = spec(
        0.1, min=MIN_TIME_STEP, max=1.0, unit="s", help="BT tick (>= controller_period)"
    )
    controller_period: float = spec(
        0.02, min=MIN_TIME_STEP, max=0.1, unit="s", help="skill tick (>= plant.time_step)"
    )
    max_sim_time: float = spec(
        300.0, min=0.0, strict_min=True, unit="s", help="simulated time before TIMEOUT"
    )

    def check(self, f: Fields) -> None:
        if self.bt_period < self.controller_period:
            raise f.error("bt_period", f"must be >= {self.controller_period}, got {self.bt_period}")


@dataclass(frozen=True)
class BaseLimits:
    """``base:``: velocity and acceleration limits of the base trajectories (MoveTo and
    approaches, `tamp.sim.smp.motion`)."""

    max_speed: float = spec(0.5, min=0.0, strict_min=True, max=2.0, unit="m/s")
    max_accel: float = spec(0.6, min=0.0, strict_min=True, max=5.0, unit="m/s^2")
    max_yaw_rate: float = spec(1.2, min=0.0, strict_min=True, max=5.0, unit="rad/s")
    max_yaw_accel: float = spec(2.0, min=0.0, strict_min=True, max=10.0, unit="rad/s^2")


@dataclass(frozen=True)
class Workspace:
    """``workspace:``: the floor rectangle the robot and the objects stay in (robot frame)."""

    x: tuple[float, float] = spec(unit="m", help="[xmin, xmax], at least 1 m apart")
    y: tuple[float, float] = spec(unit="m", help="[ymin, ymax], at least 1 m apart")

    def check(self, f: Fields) -> None:
        for key, (lo, hi) in (("x", self.x), ("y", self.y)):
            if hi - lo < 1.0:
                raise f.error(key, f"workspace must span at least 1 m, got [{lo}, {hi}]")
            if lo < -FLOOR_HALF or hi > FLOOR_HALF:
                raise f.error(
                    key,
                    f"workspace must lie within [-{FLOOR_HALF:g}, {FLOOR_HALF:g}] m (the floor)",
                )

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax)."""
        return (self.x[0], self.x[1], self.y[0], self.y[1])


@dataclass(frozen=True)
class RobotSettings:
    """``robot:``: where the robot starts (default: the demonstration's start)."""

    start: tuple[float, float, float] | None = spec(None, unit="m, m, rad", help="x, y, yaw")


@dataclass(frozen=True)
class ObjectEntry:
    """One entry of ``objects:``: a demonstration object's model or pose, or a new object
    (with a pose, or without one when it appears: ``appear``)."""

    id: str = spec(help="object id (a demonstration object's, or a new one)")
    model: str = spec(DEFAULT_MODEL, help="a packaged model or one declared under models:")
    pose: tuple[float, float, float] | None = spec(None, unit="m, m, rad", help="x, y, yaw")


def _entries(parse: Callable[..., Any], what: str) -> Callable[[Any, Fields, str], tuple]:
    """A ``spec(parse=...)`` reader of a list of flag strings (``appear``, ``fail``) with
    the flags' own grammar; each error names ``key[i]``."""

    def read(raw: Any, f: Fields, key: str) -> tuple:
        out = []
        for i, text in enumerate(f.items(key)):
            field = f"{f.path}.{key}[{i}]" if f.path else f"{key}[{i}]"
            if not isinstance(text, str):
                raise InputError(f"expected {what} as a string", file=f.file, field=field)
            out.append(parse(text, field=field, file=f.file))
        return tuple(out)

    return read


def _perturbation(raw: Any, f: Fields, key: str) -> Perturbation:
    return parse_perturbation(f, key)


#: the learned detector needs the camera
NO_CAMERA = "the learned detector reads the camera: set 'perception: camera'"


def unlearned(model: str) -> str | None:
    """Why ``detector: learned`` cannot find an object of ``model`` (None: it can): it names
    only the packaged models it was trained on (`OBJECT_KINDS`); a model a file declares
    would be ``unknown`` to it and never found."""
    if model in OBJECT_KINDS:
        return None
    return (
        f"the learned detector was not trained on model {model!r} (it knows "
        f"{', '.join(OBJECT_KINDS)}): use 'detector: oracle'"
    )


def check_learned(sf: ScenarioFile, f: Fields) -> None:
    """``detector: learned`` needs ``perception: camera`` and objects of the models it knows
    (`unlearned`; `InputError` naming the field)."""
    if sf.perception != "camera":
        raise f.error("detector", NO_CAMERA)
    for entry, where in zip(sf.objects, f.items("objects", []), strict=True):
        if (why := unlearned(entry.model)) is not None:
            raise where.error("model", why)


def with_detector(scenario: SimScenario, detector: str) -> SimScenario:
    """``scenario`` read by ``detector`` (the ``--detector`` flag; checked as the file's
    field is: `InputError` naming the flag)."""
    if detector == "learned":
        if scenario.perception != "camera":
            raise InputError(NO_CAMERA, file=scenario.source or None, field="--detector")
        for o in scenario.objects:
            if (why := unlearned(o.kind.name)) is not None:
                raise InputError(why, file=scenario.source or None, field="--detector")
    return dataclasses.replace(scenario, detector=detector)


@dataclass(frozen=True, kw_only=True)
class ScenarioFile:
    """A scenario file as written (module docstring), before it is resolved against its
    demonstration (`load_scenario`)."""

    name: str = spec(help="the scenario's name")
    demonstration: str = spec(help="demonstration file: relative to this file, or packaged")
    planner: Planner = spec(Planner)
    plant: PlantSettings = spec(PlantSettings)
    executor: ExecutorSettings = spec(ExecutorSettings)
    base: BaseLimits = spec(BaseLimits)
    workspace: Workspace = spec()
    robot: RobotSettings = spec(RobotSettings)
    models: dict[str, ObjectModel] = spec({}, help="object models of this file, by name")
    objects: tuple[ObjectEntry, ...] = spec(())
    appear: tuple[Appear, ...] = spec(
        (), parse=_entries(parse_appear, "OBJ@PLACE[@WHEN]"), help="as --appear"
    )
    fail: tuple[Fail, ...] = spec(
        (), parse=_entries(parse_fail, "ACTION[(ARGS)][xTIMES]"), help="as --fail"
    )
    grasp: str = spec("weld", choices=GRASPS, help="weld | friction (the fingers hold it)")
    perception: str = spec(
        "truth", choices=PERCEPTIONS, help="truth (plant poses) | camera (RGB-D on the robot)"
    )
    detector: str = spec(
        "oracle",
        choices=DETECTORS,
        help="what reads the mast camera's views (perception: camera): the renderer's labels "
        "as a perfect detector (oracle), or the learned detector on colour + depth "
        "(`tamp.sim.core.detector`, the mast camera's shipped weights)",
    )
    perturbation: Perturbation = spec(NONE, parse=_perturbation, help="tamp.perturbation")

    def check(self, f: Fields) -> None:
        """Relations across sections: periods no shorter than the plant step, unique
        object ids of known models (a declared model's name not a packaged one's),
        simulated failures only, each failure listed once."""
        if self.executor.controller_period < self.plant.time_step:
            raise f.sub("executor").error(
                "controller_period",
                f"must be >= {self.plant.time_step}, got {self.executor.controller_period}",
            )
        for name in self.models:
            if name in OBJECT_KINDS:
                raise f.sub("models").error(
                    name,
                    f"a packaged model has this name (packaged: {', '.join(OBJECT_KINDS)}): "
                    "choose another",
                )
        known = list(OBJECT_KINDS) + list(self.models)
        seen: set[str] = set()
        for entry, where in zip(self.objects, f.items("objects", []), strict=True):
            if entry.id in seen:
                raise where.error("id", f"duplicate object {entry.id!r}")
            seen.add(entry.id)
            if entry.model not in known:
                raise where.error(
                    "model", f"unknown model {entry.model!r} (known: {', '.join(known)})"
                )
        self.perturbation.require(PERTURBED, "SMP-MRO")
        if self.detector == "learned":
            check_learned(self, f)
        if self.perturbation.detector is not None and self.perception != "camera":
            raise f.error(
                "perturbation.sensor.detector",
                "a noisy detector needs a detector: set 'perception: camera'",
            )
        for action in self.perturbation.skill_failure:
            if action not in SIMULATED_FAILURES:
                raise f.error(
                    f"perturbation.skills.{action}",
                    f"only {', '.join(SIMULATED_FAILURES)} failures (lost grasps) are simulated",
                )
        for i, fail in enumerate(self.fail):
            if any((g.action, g.args) == (fail.action, fail.args) for g in self.fail[:i]):
                raise InputError(f"{fail.action} is listed twice", file=f.file, field=f"fail[{i}]")


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
class RunConditions:
    """What one seeded run draws beyond poses (`tamp.sim.smp.perturb.perturb`): the seed,
    the objects' friction coefficient (None: the SDFs'), the camera's depth noise and the
    perceived pose noise (m, sigma), the noisy detector's level, and per action the attempts
    that fail by chance."""

    seed: int = 0
    friction: float | None = None
    depth_noise: float = 0.0
    pose_noise: float = 0.0
    detector: str | None = None  # the seeded noisy detector's level (None: exact)
    chance_failures: tuple[tuple[str, tuple[bool, ...]], ...] = ()
    #: (id, x, y, yaw) where the robot was shown each object (its camera prior), when the run
    #: moved them; empty: the scenario's own poses
    nominal: tuple[tuple[str, float, float, float], ...] = ()


@dataclass(frozen=True)
class SimScenario:
    """A loaded, validated simulation scenario: the file's sections as loaded, and what
    they resolve to against the demonstration (objects, robot start, failures)."""

    name: str
    source: str
    demo: Demonstration
    planner: Planner
    plant: PlantSettings
    executor: ExecutorSettings
    base: BaseLimits
    workspace: tuple[float, float, float, float]  # xmin, xmax, ymin, ymax
    robot_start: tuple[float, float, float]
    objects: tuple[SimObject, ...]
    failures: tuple[Fail, ...]
    grasp: str  # weld | friction
    perception: str  # truth | camera
    perturbation: Perturbation
    detector: str = "oracle"  # what reads the camera's views (perception: camera)
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
                    SimObject(a.obj, OBJECT_KINDS[DEFAULT_MODEL], (math.nan, math.nan), 0.0, a)
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
    sf = load_dataclass(ScenarioFile, f, extra_keys={"version"})
    demo = _demonstration(f, sf.demonstration)
    kinds = {**OBJECT_KINDS, **declared_kinds(sf.models, f)}
    if sf.robot.start is not None:
        robot_start = sf.robot.start
    else:
        rs = demo.robot_start
        robot_start = (rs.pos.x, rs.pos.y, rs.orientation.yaw())
    scenario = SimScenario(
        name=sf.name,
        source=file,
        demo=demo,
        planner=sf.planner,
        plant=sf.plant,
        executor=sf.executor,
        base=sf.base,
        workspace=sf.workspace.bounds,
        robot_start=robot_start,
        objects=_objects(sf, demo, kinds),
        failures=(),
        grasp=sf.grasp,
        perception=sf.perception,
        perturbation=sf.perturbation,
        detector=sf.detector,
    )
    scenario = _appearances(scenario, sf, file)
    for i, fail in enumerate(sf.fail):
        _check_fail(scenario, fail, field=f"fail[{i}]", file=file)
    scenario = dataclasses.replace(scenario, failures=sf.fail)
    _check_geometry(scenario, sf)
    return scenario


def _demonstration(f: Fields, ref: str) -> Demonstration:
    """The demonstration ``ref`` names: beside the scenario file, else a packaged one."""
    local = Path(f.file).parent / ref
    path = local if local.exists() else scenarios.resolve(ref)
    if not Path(path).exists():
        raise f.error("demonstration", f"no demonstration file {ref!r}")
    return load_demonstration(path)


def _objects(
    sf: ScenarioFile, demo: Demonstration, kinds: dict[str, ObjectKind]
) -> tuple[SimObject, ...]:
    """Demonstration objects (bottles at P unless listed) and listed ones; an object with
    no pose gets one from ``appear`` (`_appearances`), until then its ``xy`` is NaN."""
    listed = {entry.id: entry for entry in sf.objects}
    out: list[SimObject] = []
    for uid, p in demo.objects.items():
        kind, xy, yaw = kinds[DEFAULT_MODEL], (p.x, p.y), 0.0
        entry = listed.pop(uid, None)
        if entry is not None:
            kind = kinds[entry.model]
            if entry.pose is not None:
                xy, yaw = entry.pose[:2], entry.pose[2]
        out.append(SimObject(uid, kind, xy, yaw))
    for uid, entry in listed.items():
        xy, yaw = (math.nan, math.nan), 0.0
        if entry.pose is not None:
            xy, yaw = entry.pose[:2], entry.pose[2]
        out.append(SimObject(uid, kinds[entry.model], xy, yaw))
    return tuple(out)


def _appearances(s: SimScenario, sf: ScenarioFile, file: str) -> SimScenario:
    """The file's ``appear`` entries on the objects; every object without a pose needs one."""
    objects = {o.id: o for o in s.objects}
    for i, a in enumerate(sf.appear):
        field = f"appear[{i}]"
        _check_appear(s, a, field=field, file=file)
        old = objects.get(a.obj)
        if old is not None and old.appear is not None:
            raise InputError(f"{a.obj} already appears", file=file, field=field)
        if old is not None and not math.isnan(old.xy[0]):
            raise InputError(
                f"{a.obj} has a pose (objects); give either pose or appear", file=file, field=field
            )
        kind = old.kind if old is not None else OBJECT_KINDS[DEFAULT_MODEL]
        objects[a.obj] = SimObject(a.obj, kind, (math.nan, math.nan), 0.0, a)
    for j, entry in enumerate(sf.objects):
        o = objects[entry.id]
        if o.appear is None and math.isnan(o.xy[0]):
            raise InputError(
                f"object {o.id} is not in the demonstration: it needs a pose or an appear entry",
                file=file,
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


def _check_geometry(s: SimScenario, sf: ScenarioFile) -> None:
    """Objects inside the workspace and apart, goals reachable, the robot clear of objects."""
    index = {o.id: i for i, o in enumerate(s.objects)}
    listed = {entry.id: j for j, entry in enumerate(sf.objects)}

    def field(uid: str) -> str:
        return f"objects[{listed[uid]}]" if uid in listed else f"demonstration (object {uid})"

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
    fields = {a.obj: (f"appear[{i}]", s.source) for i, a in enumerate(sf.appear)}
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
