"""Load a demonstration file (YAML, ``version: 1``) into a `Demonstration` (§IV-A).

Format (positions of objects, steps and free areas are in the user's MR frame)::

    version: 1
    frame:
      robot_position: [x, y, z]      # uP_r, the robot in the user frame (eq. 1)
      rotation: [[..],[..],[..]]     # optional R of eq. (1); default identity (paper's case)
      handedness: [[..],[..],[..]]   # optional A of eq. (4)-(5); default Unity->ROS
    area_radius: 0.15                # radius of every goal / free area (m)
    object_height: 0.2               # optional, for the simulator (m)
    robot:
      start: [x, y, yaw]             # robot frame; default [0, 0, 0]
      domain: path/to/domain.yaml    # optional; default: the packaged youBot domain
    objects:
      - {id: O0, position: [x, y, z]}
    steps:                           # the person's illustrated moves, in order
      - {object: O0, to: [x, y, z]}
    free_areas:                      # optional places that do not affect the task; one
      - {id: free1, position: [x, y, z]}  # may become a buffer goal to break a swap with
                                     # no room (`tamp.demo.constraints`)
    constraints: [[G0, G1]]          # optional explicit order specifications G_i <= G_j
    appear: ["Oa@L1"]                # optional: what happens during execution (SMP-MRO
                                     # Case 3), in the run vocabulary OBJ@PLACE[@WHEN] of
                                     # `tamp.world.events`; a point PLACE x,y,z is in the
                                     # user's frame like every position of this file

``path`` may name a packaged demonstration (``case3.yaml``) from any directory.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from tamp.demo.build import make_demonstration
from tamp.demo.frames import IDENTITY, UNITY_TO_ROS, MRFrame, check_rotation
from tamp.demo.model import Demonstration
from tamp.errors import InputError
from tamp.fileio import Fields, check_vector, check_version, gc_paused, load_yaml
from tamp.scenarios import resolve
from tamp.world.events import Appear, check_events, parse_appear
from tamp.world.geometry import Area, Point, Pose, Quaternion

#: Size limits of a demonstration (exit 2 beyond them, before any geometry is computed).
#: Deriving C and enumerating a chain are linear, but a search state holds a bitmask of
#: the goals, so time and memory grow with steps × states: one object's chain of 20,000
#: goals plans in a few seconds, 50,000 took 100 s and 0.5 GB (benchmarks/demo_scale.py),
#: and no person demonstrates that many moves. Objects: the search's width grows with the
#: objects that still have goals. The file size limit refuses a huge file before the
#: (pure-Python, about 0.5 ms per step) YAML parser reads it.
MAX_STEPS = 20_000
MAX_OBJECTS = 10_000
MAX_BYTES = 2 * 1024 * 1024  # about 100 bytes for each of MAX_STEPS steps

_KEYS = {
    "version",
    "name",
    "description",
    "frame",
    "area_radius",
    "object_height",
    "robot",
    "objects",
    "steps",
    "free_areas",
    "constraints",
    "appear",
}


def _matrix(f: Fields, key: str, default, *, proper: bool) -> tuple[tuple[float, ...], ...]:
    raw = f.raw(key, default)
    if not isinstance(raw, list | tuple) or len(raw) != 3:
        raise f.error(key, "expected a 3x3 matrix (three rows of three numbers)")
    rows = tuple(check_vector(r, 3, f.file, f"{f.path}.{key}[{i}]") for i, r in enumerate(raw))
    why = check_rotation(np.array(rows), proper=proper)
    if why:
        raise f.error(key, why)
    return rows


def load_demonstration(path: str | Path) -> Demonstration:
    """Read, validate and transform a demonstration; bad input raises `InputError`.

    Linear in the steps: the garbage collector is paused while the (acyclic) goals, areas
    and constraints are built (`tamp.fileio.gc_paused`).
    """
    with gc_paused():
        return _load_demonstration(path)


def _load_demonstration(path: str | Path) -> Demonstration:
    source = resolve(path)
    if Path(source).is_file() and Path(source).stat().st_size > MAX_BYTES:
        raise InputError(
            f"larger than {MAX_BYTES // (1024 * 1024)} MiB, the size limit of a demonstration "
            f"file (about 100 bytes for each of at most {MAX_STEPS} steps)",
            file=str(path),
        )
    data, file = load_yaml(source, kind="demonstration")
    return _from_data(data, file)


def demonstration_from_dict(data: Any, source: str) -> Demonstration:
    """The same validation and eq. (1)–(5) as `load_demonstration`, for a mapping already
    in memory (a live MR session sends one): ``data`` has the file format above, ``source``
    names it in errors (``source: field: reason``). A relative ``robot.domain`` is refused,
    since there is no file to resolve it against."""
    if not isinstance(data, dict):
        raise InputError("a demonstration must be a mapping", file=source)
    check_version(data, source)
    robot = data.get("robot")
    domain = robot.get("domain") if isinstance(robot, dict) else None
    if isinstance(domain, str) and not Path(domain).is_absolute():
        raise InputError("must be an absolute path here", file=source, field="robot.domain")
    with gc_paused():
        return _from_data(data, source)


def _from_data(data: dict[str, Any], file: str) -> Demonstration:
    f = Fields(data, file)
    f.check_keys(_KEYS)
    for key, limit in (("objects", MAX_OBJECTS), ("steps", MAX_STEPS)):
        items = data.get(key)
        if isinstance(items, list) and len(items) > limit:
            raise f.error(key, f"{len(items)} entries: more than the limit of {limit}")

    fr = f.sub("frame")
    fr.check_keys({"robot_position", "rotation", "handedness"})
    frame = MRFrame(
        robot_position=fr.vector("robot_position", 3),
        rotation=_matrix(fr, "rotation", IDENTITY, proper=True),
        handedness=_matrix(fr, "handedness", UNITY_TO_ROS, proper=False),
    )
    radius = f.float("area_radius", min=0.0, strict_min=True)
    height = f.float("object_height", 0.2, min=0.0, strict_min=True)

    robot = f.sub("robot", {})
    robot.check_keys({"start", "domain"})
    sx, sy, syaw = robot.vector("start", 3, [0.0, 0.0, 0.0])
    start = Pose(Point(sx, sy, 0.0), Quaternion.from_yaw(syaw))
    domain_file = None
    if robot.has("domain"):
        d = Path(robot.str("domain"))
        if not d.is_absolute():
            d = Path(file).parent / d
        if not d.is_file():
            raise robot.error("domain", f"domain file not found: {d}")
        domain_file = str(d)

    objects: dict[str, Point] = {}
    labels: dict[str, str] = {}
    for i, item in enumerate(f.items("objects")):
        if not isinstance(item, Fields):
            raise InputError("expected a mapping {id, position}", file=file, field=f"objects[{i}]")
        item.check_keys({"id", "position"})
        uid = item.str("id")
        if uid in objects:
            raise item.error("id", f"duplicate object id {uid!r}")
        objects[uid] = frame.to_robot(item.vector("position", 3))
        labels[uid] = f"objects[{i}]"
    if not objects:
        raise f.error("objects", "a demonstration needs at least one object")

    steps: list[tuple[str, Point]] = []
    where = dict(objects)
    for i, item in enumerate(f.items("steps")):
        if not isinstance(item, Fields):
            raise InputError("expected a mapping {object, to}", file=file, field=f"steps[{i}]")
        item.check_keys({"object", "to"})
        obj = item.str("object")
        if obj not in objects:
            raise item.error("object", f"unknown object {obj!r} (known: {', '.join(objects)})")
        to = frame.to_robot(item.vector("to", 3))
        if where[obj].planar_distance(to) <= 1e-9:
            raise item.error("to", f"{obj} is already there: a step must move the object")
        where[obj] = to
        steps.append((obj, to))
    if not steps:
        raise f.error("steps", "a demonstration needs at least one step")

    free: list[Area] = []
    for i, item in enumerate(f.items("free_areas", [])):
        if not isinstance(item, Fields):
            raise InputError(
                "expected a mapping {id, position}", file=file, field=f"free_areas[{i}]"
            )
        item.check_keys({"id", "position", "radius"})
        name = item.str("id")
        if name in {a.name for a in free} or (
            name[:1] == "L" and name[1:].isdigit() and int(name[1:]) < len(steps)
        ):
            raise item.error("id", f"duplicate area name {name!r}")
        r = item.float("radius", radius, min=0.0, strict_min=True)
        free.append(Area(name, frame.to_robot(item.vector("position", 3)), r))

    explicit = []
    for i, pair in enumerate(f.items("constraints", [])):
        if not (
            isinstance(pair, list) and len(pair) == 2 and all(isinstance(g, str) for g in pair)
        ):
            raise InputError("expected [Gi, Gj]", file=file, field=f"constraints[{i}]")
        explicit.append((pair[0], pair[1]))

    appear: list[Appear] = []
    for i, item in enumerate(f.items("appear", [])):
        field = f"appear[{i}]"
        if not isinstance(item, str):
            raise InputError("expected a string OBJ@PLACE[@WHEN]", file=file, field=field)
        a = parse_appear(item, field=field, file=file)
        if isinstance(a.place, Point):
            a = Appear(a.obj, frame.to_robot(a.place.as_tuple()), a.when)
        appear.append(a)

    demo = make_demonstration(
        objects,
        steps,
        radius,
        free_areas=free,
        start=start,
        explicit=explicit,
        object_height=height,
        domain_file=domain_file,
        source=file,
        object_labels=labels,
        appear=tuple(appear),
    )
    check_events(
        demo.appear,
        (),
        objects=demo.objects,
        areas=demo.initial_world().areas,
        domain=demo.domain(),
        fields={"appear": "appear"},
        file=file,
    )
    return demo
