"""A live demonstration: what a person shows in MR, kept as the demonstration file's mapping.

SMP-MRO (Nakamura & Sekiyama, IEEE Access, §IV-A) has the person move virtual copies of the
objects; each released grab is one step ``U_k`` (object, new position). `DemoSession` holds
the session as the very ``version: 1`` mapping a demonstration file holds (positions in the
person's raw Unity frame, `tamp.serve.mr`), so that

- every check and the MR → robot conversion (eq. 1–5) are the loader's own
  (`tamp.demo.demonstration_from_dict`), with errors that name the field;
- ``export`` is that mapping as YAML, and ``tamp plan`` of the exported file gives the
  same plan as the live session.

The session survives reconnects: it belongs to the server, not to a connection.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any

import yaml

from tamp.demo import Demonstration, demonstration_from_dict
from tamp.demo.frames import MRFrame
from tamp.errors import InputError
from tamp.serve.mr import (
    MessageError,
    frame_of,
    number,
    point,
    robot_to_mr,
    rotation_of,
    to_file,
    to_mr,
)

#: Bounds of one live session (the loader's own limits apply too).
MAX_OBJECTS = 1000
MAX_STEPS = 5000
MAX_ID = 64


class SessionError(ValueError):
    """A request that the session refuses; the text says why (sent as ``message``)."""


def _ident(value: Any, field: str) -> str:
    if not isinstance(value, str) or not value or len(value) > MAX_ID:
        raise MessageError(field, f"expected a name of 1 to {MAX_ID} characters")
    if not all(c.isalnum() or c in "_-." for c in value):
        raise MessageError(field, "use letters, digits, '_', '-' or '.'")
    return value


def _entries(
    args: dict[str, Any], key: str, frame: str, limit: int, *, radius: bool = False
) -> list[dict[str, Any]]:
    raw = args.get(key) or []
    if not isinstance(raw, list):
        raise MessageError(key, "expected a list of {id, pose}")
    if len(raw) > limit:
        raise MessageError(key, f"{len(raw)} entries: more than the limit of {limit}")
    out = []
    for i, item in enumerate(raw):
        where = f"{key}[{i}]"
        if not isinstance(item, dict):
            raise MessageError(where, "expected {id, pose}")
        pose = item.get("pose") or {}
        if not isinstance(pose, dict):
            raise MessageError(f"{where}.pose", "expected a geometry_msgs/Pose")
        entry = {
            "id": _ident(item.get("id"), f"{where}.id"),
            "position": to_file(point(pose.get("position"), f"{where}.pose.position"), frame),
        }
        r = item.get("radius", 0.0)
        if radius and r not in (None, 0, 0.0):
            entry["radius"] = number(r, f"{where}.radius")
        out.append(entry)
    return out


@dataclass
class DemoSession:
    """The session's mapping and steps; methods raise `MessageError` / `InputError` /
    `SessionError` with the reason."""

    number: int = 0
    data: dict[str, Any] | None = None
    mr_steps: list[list[float]] = field(default_factory=list)  # each step as sent, in mr

    @property
    def id(self) -> str | None:
        return f"s{self.number}" if self.data is not None else None

    @property
    def source(self) -> str:
        return f"live:{self.id}"

    def begin(self, args: dict[str, Any]) -> str:
        """Start a new session from a ``tamp_msgs/BeginDemo`` request; returns the message."""
        frame = frame_of(args)
        robot = args.get("robot")
        robot = {} if robot is None else robot  # a ROS default: the MR origin, no rotation
        if not isinstance(robot, dict):
            raise MessageError("robot", "expected a geometry_msgs/Pose")
        data: dict[str, Any] = {"version": 1}
        name = args.get("name") or ""
        if name:
            data["name"] = _ident(name, "name")
        data["frame"] = {
            "robot_position": to_file(point(robot.get("position") or {}, "robot.position"), frame)
        }
        rotation = rotation_of(robot.get("orientation"), frame, "robot.orientation")
        if rotation is not None:
            data["frame"]["rotation"] = rotation
        data["area_radius"] = number(args.get("area_radius", 0.15), "area_radius")
        height = args.get("object_height") or 0.0
        if height:
            data["object_height"] = number(height, "object_height")
        start = args.get("start") or []
        if start:
            if not isinstance(start, list) or len(start) != 3:
                raise MessageError("start", "expected [x, y, yaw] in the robot frame, or []")
            data["robot"] = {"start": [number(v, f"start[{i}]") for i, v in enumerate(start)]}
        data["objects"] = _entries(args, "objects", frame, MAX_OBJECTS)
        data["steps"] = []
        free = _entries(args, "free_areas", frame, MAX_OBJECTS, radius=True)
        if free:
            data["free_areas"] = free
        appear = args.get("appear") or []
        if appear:
            if not isinstance(appear, list) or not all(isinstance(a, str) for a in appear):
                raise MessageError("appear", "expected a list of OBJ@PLACE[@WHEN] strings")
            data["appear"] = list(appear)
        self.number += 1
        self.data = data
        self.mr_steps = []
        self._check_begin()
        return f"session {self.id}: {len(data['objects'])} objects"

    def open(self, data: dict[str, Any], name: str) -> str:
        """Start a new session from a demonstration file's mapping: its frame, radius,
        robot start, objects, free areas and appearances; its steps and constraints are left
        for the person to show."""
        if not isinstance(data, dict):
            raise SessionError(f"{name}: not a demonstration mapping")
        keep = (
            "version",
            "name",
            "frame",
            "area_radius",
            "object_height",
            "robot",
            "objects",
            "free_areas",
            "appear",
        )
        self.number += 1
        self.data = {k: copy.deepcopy(data[k]) for k in keep if k in data}
        self.data["steps"] = []
        self.mr_steps = []
        self._check_begin()
        return f"session {self.id}: {len(self.data['objects'])} objects from {name}"

    def _check_begin(self) -> None:
        """The loader's checks up to the steps (frame, radius, robot, objects)."""
        head = {k: v for k, v in self.data.items() if k != "appear"}
        try:
            demonstration_from_dict(head, self.source)
        except InputError as exc:
            if exc.field == "steps":  # everything before the steps is valid
                return
            self.data = None
            raise

    def _need(self) -> dict[str, Any]:
        if self.data is None:
            raise SessionError("no demonstration: call /tamp/demo/begin first")
        return self.data

    def step(self, msg: dict[str, Any]) -> dict[str, Any]:
        """Add one released grab (``tamp_msgs/DemoStep``), checked by the loader with the
        steps before it; returns the step as published on ``/tamp/demo/steps``."""
        data = self._need()
        frame = frame_of(msg)
        obj = _ident(msg.get("object_id"), "object_id")
        pose = msg.get("pose") or {}
        if not isinstance(pose, dict):
            raise MessageError("pose", "expected a geometry_msgs/Pose")
        if len(data["steps"]) >= MAX_STEPS:
            raise SessionError(f"more than {MAX_STEPS} steps")
        p = point(pose.get("position"), "pose.position")
        to = to_file(p, frame)
        candidate = copy.deepcopy(data)
        candidate["steps"].append({"object": obj, "to": to})
        candidate.pop("appear", None)  # may name goals of later steps: checked when planning
        demonstration_from_dict(candidate, self.source)
        data["steps"].append({"object": obj, "to": to})
        self.mr_steps.append(to_mr(to))
        return self.steps_json()[-1]

    def undo(self) -> str:
        data = self._need()
        if not data["steps"]:
            raise SessionError("no step to undo")
        s = data["steps"].pop()
        self.mr_steps.pop()
        return f"undid the step of {s['object']}; {len(data['steps'])} steps left"

    def reset(self) -> str:
        data = self._need()
        data["steps"].clear()
        self.mr_steps.clear()
        return f"session {self.id}: steps cleared"

    def demonstration_dict(self, constraints: list[list[str]] = ()) -> dict[str, Any]:
        """The session as a demonstration file's mapping (plus explicit constraints)."""
        data = copy.deepcopy(self._need())
        if constraints:
            data["constraints"] = [list(c) for c in constraints]
        return data

    def demonstration(self, constraints: list[list[str]] = ()) -> Demonstration:
        data = self.demonstration_dict(constraints)
        if not data["steps"]:
            raise SessionError("no steps yet: move an object first")
        return demonstration_from_dict(data, self.source)

    def export(self, constraints: list[list[str]] = ()) -> str:
        """The ``version: 1`` YAML that ``tamp plan`` reads."""
        return yaml.safe_dump(
            self.demonstration_dict(constraints), sort_keys=False, default_flow_style=None
        )

    def mr_frame(self) -> MRFrame:
        fr = self._need()["frame"]
        kw = {"rotation": tuple(map(tuple, fr["rotation"]))} if "rotation" in fr else {}
        return MRFrame(robot_position=tuple(fr["robot_position"]), **kw)

    def steps_json(self) -> list[dict[str, Any]]:
        """Each step with its goal id, the robot-frame and the MR-frame position."""
        data = self._need()
        frame = self.mr_frame()
        out = []
        for k, (s, mr) in enumerate(zip(data["steps"], self.mr_steps, strict=True)):
            rp = frame.to_robot(tuple(s["to"]))
            out.append(
                {
                    "goal": f"G{k}",
                    "object": s["object"],
                    "robot": [round(v, 6) + 0.0 for v in rp.as_tuple()],
                    "mr": mr,
                }
            )
        return out

    def scene_json(self) -> dict[str, Any]:
        """Objects and free areas at their start, in ``mr`` and the robot frame (the page
        and the headset draw these)."""
        data = self._need()
        frame = self.mr_frame()

        def entry(e: dict[str, Any]) -> dict[str, Any]:
            return {
                "id": e["id"],
                "mr": to_mr(e["position"]),
                "robot": [
                    round(v, 6) + 0.0 for v in frame.to_robot(tuple(e["position"])).as_tuple()
                ],
            }

        start = (data.get("robot") or {}).get("start", [0.0, 0.0, 0.0])
        return {
            "session": self.id,
            "area_radius": data["area_radius"],
            "robot_mr": robot_to_mr(frame, (start[0], start[1], 0.0)),
            "robot_yaw": start[2],
            "objects": [entry(e) for e in data["objects"]],
            "free_areas": [entry(e) for e in data.get("free_areas", [])],
        }


def parse_constraints(raw: Any) -> list[list[str]]:
    """``["G0<=G2", …]`` (or ``[["G0", "G2"]]``) → ``[["G0", "G2"], …]``."""
    if raw in (None, ""):
        return []
    if not isinstance(raw, list) or len(raw) > 10_000:
        raise MessageError("constraints", "expected a list of 'Gi<=Gj'")
    out = []
    for i, c in enumerate(raw):
        if isinstance(c, str) and "<=" in c:
            a, b = (s.strip() for s in c.split("<=", 1))
        elif isinstance(c, list) and len(c) == 2 and all(isinstance(g, str) for g in c):
            a, b = c
        else:
            raise MessageError(f"constraints[{i}]", "expected 'Gi<=Gj'")
        out.append([_ident(a, f"constraints[{i}]"), _ident(b, f"constraints[{i}]")])
    return out
