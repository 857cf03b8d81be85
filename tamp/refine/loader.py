"""Program files (YAML, ``version: 1``): load with strict validation, write back (refined).

Format::

    version: 1
    name: task4
    description: Open the folding chair lying on the floor (Fig. 9(d), Fig. 11).
    scene: open_chair               # a packaged scene (flip_briefcase | flip_scale | lift_scale
                                    # | open_chair | table) or a scene file relative to this
                                    # file (tamp.sim.refine.scenario)
    architecture: arch.yaml         # optional; default: the packaged calibrated architecture
    communication:
      category: II                  # Table 1: I | II | III
      sensor_rate_hz: 200
      command_rate_hz: 10           # P
      base_speed: 1.05e-2           # m/s, default speed of base motions
    ordering: "G(R1.pull_out -> R2.grip)"   # LTL over events, "has fired" semantics
    robots:
      - name: R1
        model: pioneer_lift         # Fig. 7(a); pioneer_parallel: Fig. 7(b)
        start: [x, y, yaw]
        behaviors:
          - name: lower_arm
            section: arm            # base | arm | gripper
            motion: {angle: -0.6, speed: 0.0105}    # or {distance: m}; base speed optional
            event: {sensor: force, above: 3.0}      # N; imu above|below: arm pitch (rad, up +)
                                                    # odometry reaches: base progress (m|rad)
            # event: {after: R2.grip}               # or: the other robot's event
            waits_for: [R2.grip]    # optional: events that must have fired before it starts
            parallel_with: prev     # optional: starts with the previous behavior (Fig. 13)
            manipulates: true       # optional: manipulation starts here (Step 1)
            rate_hz: 23             # optional: this behavior's command rate P
    perturbation:                   # optional, seeded runs only (tamp.perturbation)
      robot: {xy: 0.01, yaw: 0.02}  # each robot's start pose, drawn per seed

Every error is an `InputError` naming the file and the dotted field (CLI exit 2).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from tamp import scenarios
from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.perturbation import parse_perturbation
from tamp.refine.program import (
    CATEGORIES,
    MODELS,
    SECTIONS,
    SENSORS,
    UNITS,
    Behavior,
    Communication,
    Motion,
    Program,
    RobotProgram,
    Trigger,
    event_id,
)

#: The packaged scenes' folder in `tamp.scenarios` (``tamp/scenarios/refine/scenes``).
SCENES = "refine/scenes"

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_EVENT_TOKEN = re.compile(r"\b([A-Za-z][A-Za-z0-9_]*\.[A-Za-z0-9_]+)\b")
_KEYS = (
    "version",
    "name",
    "description",
    "scene",
    "architecture",
    "communication",
    "ordering",
    "robots",
    "perturbation",  # seeded runs only: `tamp.perturbation`
)
_BEHAVIOR_KEYS = (
    "name",
    "section",
    "motion",
    "event",
    "waits_for",
    "parallel_with",
    "manipulates",
    "rate_hz",
)


def scene_path(name_or_path: str | Path) -> Path:
    """The file of a scene: a user path if it exists, else the packaged scene of that name
    (`tamp.scenarios.resolve` in `SCENES`)."""
    return scenarios.resolve(name_or_path, SCENES)


def packaged_scenes() -> tuple[str, ...]:
    """The names of the packaged scenes."""
    return tuple(sorted(p.stem for p in (scenarios.ROOT / SCENES).glob("*.yaml")))


def load_program(path: str | Path) -> Program:
    """Read and validate a program file (a path, or a packaged name such as ``task4``
    resolved by `tamp.scenarios.resolve`); any problem is an `InputError` (file, field)."""
    data, file = load_yaml(scenarios.resolve(path, "refine"), kind="refinement program")
    f = Fields(data, file)
    f.check_keys(_KEYS)
    c = f.sub("communication")
    c.check_keys(("category", "sensor_rate_hz", "command_rate_hz", "base_speed"))
    comm = Communication(
        category=c.str("category", choices=CATEGORIES),
        sensor_rate_hz=c.float("sensor_rate_hz", min=0.0, strict_min=True),
        command_rate_hz=c.float("command_rate_hz", min=0.0, strict_min=True),
        base_speed=c.float("base_speed", min=0.0, strict_min=True),
    )
    robots_raw = f.items("robots")
    if len(robots_raw) != 2:
        raise f.error("robots", f"expected two robots, got {len(robots_raw)}")
    names = []
    for i, r in enumerate(robots_raw):
        if not isinstance(r, Fields):
            raise InputError("expected a mapping", file=file, field=f"robots[{i}]")
        names.append(_name(r, "name"))
    if len(set(names)) != len(names):
        raise f.error("robots", f"duplicate robot names {names}")
    known = {n: [] for n in names}
    for r in robots_raw:
        for b in r.items("behaviors"):
            if isinstance(b, Fields) and isinstance(b.raw("name", None), str):
                known[r.raw("name")].append(b.raw("name"))
    events = {event_id(n, b) for n, bs in known.items() for b in bs}
    robots = tuple(_robot(r, comm, events) for r in robots_raw)
    architecture = None
    if f.has("architecture"):
        a = Path(f.str("architecture"))
        if not a.is_absolute():
            a = Path(file).parent / a
        if not a.is_file():
            raise f.error("architecture", f"architecture file not found: {a}")
        architecture = str(a)
    ordering = f.str("ordering")
    for token in _EVENT_TOKEN.findall(ordering):
        if token not in events:
            raise f.error("ordering", f"unknown event {token!r} (events: {sorted(events)})")
    return Program(
        name=f.str("name", Path(file).stem),
        scene=_scene(f, file),
        communication=comm,
        robots=robots,
        ordering=ordering,
        description=str(f.raw("description", "")).strip(),
        architecture=architecture,
        file=file,
        perturbation=parse_perturbation(f),
    )


def _scene(f: Fields, file: str) -> str:
    """``scene``: the user's scene file (relative to the program file) when it exists, else
    a packaged scene's name (the file's contents are read by the workcell)."""
    ref = f.str("scene")
    local = Path(file).parent / ref
    if local.is_file():
        return str(local)
    if ref not in packaged_scenes():
        raise f.error(
            "scene",
            f"no scene file {local} and no packaged scene {ref!r} "
            f"(packaged: {', '.join(packaged_scenes())})",
        )
    return ref


def _name(f: Fields, key: str) -> str:
    value = f.str(key)
    if not _NAME.match(value):
        raise f.error(key, f"names are identifiers (letters, digits, _), got {value!r}")
    return value


def _robot(r: Fields, comm: Communication, events: set[str]) -> RobotProgram:
    r.check_keys(("name", "model", "start", "behaviors"))
    name = r.str("name")
    raw = r.items("behaviors")
    if not raw:
        raise r.error("behaviors", "a robot needs at least one behavior")
    behaviors: list[Behavior] = []
    for i, item in enumerate(raw):
        if not isinstance(item, Fields):
            raise InputError("expected a mapping", file=r.file, field=f"{r.path}.behaviors[{i}]")
        behaviors.append(_behavior(item, name, behaviors, comm, events))
    return RobotProgram(
        name=name,
        model=r.str("model", choices=MODELS),
        start=r.vector("start", 3),
        behaviors=tuple(behaviors),
    )


def _behavior(
    b: Fields, robot: str, before: list[Behavior], comm: Communication, events: set[str]
) -> Behavior:
    b.check_keys(_BEHAVIOR_KEYS)
    name = _name(b, "name")
    if any(x.name == name for x in before):
        raise b.error("name", f"duplicate behavior name {name!r} in robot {robot}")
    section = b.str("section", choices=SECTIONS)
    motion = _motion(b.sub("motion"), section, comm)
    trigger = _trigger(b.sub("event"), robot, section, events)
    own = event_id(robot, name)
    waits = []
    for j, w in enumerate(b.items("waits_for", [])):
        field = f"waits_for[{j}]"
        if not isinstance(w, str) or w not in events:
            raise b.error(field, f"unknown event {w!r} (events: {sorted(events)})")
        if w == own:
            raise b.error(field, "a behavior cannot wait for its own event")
        waits.append(w)
    parallel = None
    if b.has("parallel_with"):
        parallel = b.str("parallel_with")
        if not before or before[-1].name != parallel:
            prev = before[-1].name if before else "none"
            raise b.error(
                "parallel_with", f"must name the previous behavior ({prev}), got {parallel!r}"
            )
        k = len(before) - 1
        group = [before[k]]
        while k > 0 and before[k].parallel_with is not None:
            k -= 1
            group.append(before[k])
        clash = next((x.name for x in group if x.section == section), None)
        if clash is not None:
            raise b.error(
                "parallel_with",
                f"{clash} moves the {section} too: a section executes one motion at a time",
            )
    rate = b.float("rate_hz", None, min=0.0, strict_min=True) if b.has("rate_hz") else None
    if parallel is not None and rate != before[-1].rate_hz:
        raise b.error("rate_hz", f"behaviors that run in parallel share one rate ({parallel})")
    return Behavior(
        name=name,
        section=section,
        motion=motion,
        event=trigger,
        waits_for=tuple(waits),
        parallel_with=parallel,
        manipulates=b.bool("manipulates", False),
        rate_hz=rate,
    )


def _motion(m: Fields, section: str, comm: Communication) -> Motion:
    m.check_keys(("distance", "angle", "speed"))
    units = [u for u in ("distance", "angle") if m.has(u)]
    if len(units) != 1:
        raise m.error(None, "give exactly one of distance (m) or angle (rad)")
    unit = units[0]
    if unit not in UNITS[section]:
        raise m.error(unit, f"the {section} moves by {' or '.join(UNITS[section])}, not {unit}")
    amount = m.float(unit)
    if amount == 0.0:
        raise m.error(unit, "a motion must move (got 0)")
    default = comm.base_speed if section == "base" and unit == "distance" else ...
    speed = m.float("speed", default, min=0.0, strict_min=True)
    return Motion(unit, amount, speed)


def _trigger(e: Fields, robot: str, section: str, events: set[str]) -> Trigger:
    e.check_keys(("sensor", "above", "below", "reaches", "after"))
    if e.has("after"):
        if any(e.has(k) for k in ("sensor", "above", "below", "reaches")):
            raise e.error("after", "an event is either a sensor condition or after an event")
        after = e.str("after")
        if after not in events:
            raise e.error("after", f"unknown event {after!r} (events: {sorted(events)})")
        if after.partition(".")[0] == robot:
            raise e.error("after", "'after' names the other robot's event")
        return Trigger(after=after)
    sensor = e.str("sensor", choices=SENSORS)
    ops = [op for op in ("above", "below", "reaches") if e.has(op)]
    if len(ops) != 1:
        raise e.error(None, "give exactly one of above, below, reaches")
    op = ops[0]
    if (sensor == "odometry") != (op == "reaches"):
        raise e.error(op, "odometry ends with 'reaches'; force and imu with 'above'/'below'")
    if sensor == "odometry" and section != "base":
        raise e.error("sensor", f"odometry measures the base, not the {section}")
    if sensor == "imu":
        value = e.float(op)  # signed pitch of the arm (rad, up positive)
    else:
        value = e.float(op, min=0.0, strict_min=op == "reaches")
    return Trigger(sensor=sensor, op=op, value=value)


# ----------------------------------------------------------------------------- writing


def program_to_dict(p: Program) -> dict[str, Any]:
    """The program in the file format (``load_program`` reads it back equal)."""
    out: dict[str, Any] = {"version": 1, "name": p.name}
    if p.description:
        out["description"] = p.description
    out["scene"] = p.scene
    if p.architecture:
        out["architecture"] = p.architecture
    c = p.communication
    out["communication"] = {
        "category": c.category,
        "sensor_rate_hz": c.sensor_rate_hz,
        "command_rate_hz": c.command_rate_hz,
        "base_speed": c.base_speed,
    }
    out["ordering"] = p.ordering
    out["robots"] = [
        {
            "name": r.name,
            "model": r.model,
            "start": list(r.start),
            "behaviors": [_behavior_dict(b) for b in r.behaviors],
        }
        for r in p.robots
    ]
    return out


def _behavior_dict(b: Behavior) -> dict[str, Any]:
    d: dict[str, Any] = {"name": b.name, "section": b.section}
    d["motion"] = {b.motion.unit: b.motion.amount, "speed": b.motion.speed}
    t = b.event
    d["event"] = {"after": t.after} if t.after else {"sensor": t.sensor, t.op: t.value}
    if b.waits_for:
        d["waits_for"] = list(b.waits_for)
    if b.parallel_with:
        d["parallel_with"] = b.parallel_with
    if b.manipulates:
        d["manipulates"] = True
    if b.rate_hz is not None:
        d["rate_hz"] = b.rate_hz
    return d


def dump_program(p: Program) -> str:
    """YAML text of the program (block style, keys in the documented order)."""
    return yaml.safe_dump(program_to_dict(p), sort_keys=False, default_flow_style=None)
