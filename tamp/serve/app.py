"""The demonstration → plan → execution flow of SMP-MRO over rosbridge (`TampApp`).

SMP-MRO (Nakamura & Sekiyama, IEEE Access, Fig. 1 and §V) closes a loop through mixed
reality: the person demonstrates (§IV-A), the robot side derives goals and constraints,
builds the reachability graph and picks the cheapest order (Alg. 1, A*), executes it as a
behavior tree grown at run time (§IV-C, Alg. 2–3), and shows the plan back in MR. `TampApp`
puts that loop on a `RosbridgeServer`:

services (request → answer; std_srvs/Trigger answers ``success``, ``message``)
  ``/tamp/demo/begin`` (tamp_msgs/BeginDemo), ``/tamp/demo/open`` (tamp_msgs/OpenDemo: a
  packaged demonstration's scene, without its steps), ``/tamp/demo/undo``, ``/reset``,
  ``/export`` (the ``version: 1`` YAML in ``message``), ``/tamp/plan`` (tamp_msgs/Plan),
  ``/tamp/execute``, ``/tamp/cancel``, ``/tamp/server/stats`` (the server's counters);
topics in
  ``/tamp/demo/step`` (tamp_msgs/DemoStep: one per released grab);
topics out (std_msgs/String holding JSON unless named; latched ones are re-sent to every
new subscriber)
  ``/tamp/state`` (latched: phase idle → demonstrating → planned → executing → done |
  failed | cancelled), ``/tamp/scene`` (latched: objects and areas), ``/tamp/demo/steps``
  (latched), ``/tamp/plan_result`` (latched: ``tamp plan --json``'s document),
  ``/tamp/execution`` (latched: ``tamp plan --execute --json``'s document), ``/tamp/bt``
  (latched, latest-wins), ``/tamp/events`` (queued: action start and end, recovery,
  conflict, appearance, rejected steps), ``/tamp/robot/pose`` (geometry_msgs/PoseStamped in
  ``mr``), ``/tf`` (tf2_msgs/TFMessage), ``/tf_static`` (latched: ``mr`` → ``robot``).

The planning and execution functions are given (`Pipeline`): the command line passes the
ones ``tamp plan`` and ``tamp plan --execute`` (or the Drake youBot cell) use, so a live
session plans and runs exactly like a file. They run in worker threads.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from tamp.errors import TampError
from tamp.fileio import with_schema
from tamp.serve.mr import MessageError, pose_stamped, robot_to_mr, stamp
from tamp.serve.server import Client, RosbridgeServer, ServiceError
from tamp.serve.session import DemoSession, SessionError, parse_constraints

log = logging.getLogger("tamp.serve")

PHASES = ("idle", "demonstrating", "planned", "executing", "done", "failed", "cancelled")
COST_MODELS = ("distance", "time", "success")
STRING = "std_msgs/String"
TRIGGER = "std_srvs/Trigger"


@dataclass
class Pipeline:
    """How a demonstration is planned and executed.

    ``plan(demo, cost_model)`` returns a `tamp.rg.PlanResult` that passed the verification
    gate (or raises a `TampError` with the reason); ``execute(demo, plan, mapping,
    channel)`` (``mapping``: the demonstration as a file's mapping,
    `DemoSession.demonstration_dict`; ``channel``: a `RunChannel`) returns the document
    ``tamp plan --execute --json`` prints (``executed``, ``growth``, ``world_events``,
    ``final_world``, ``status``, ...). An executor that reports while it runs sets
    ``"live": true`` in it; one that can stop early raises `RunCancelled` once the channel
    is cancelled.
    """

    plan: Callable[[Any, str], Any]
    execute: Callable[[Any, Any, dict[str, Any], RunChannel], dict[str, Any]]
    name: str = "symbolic"


class RunCancelled(Exception):
    """Raised by an executor that stopped because its run was cancelled."""


@dataclass
class RunChannel:
    """What a running executor may report to the clients while it runs (from its worker
    thread): events, the tree's status, the robot's pose and joints."""

    run: str
    cancel: threading.Event
    app: TampApp

    @property
    def cancelled(self) -> bool:
        return self.cancel.is_set()

    def event(self, kind: str, **fields: Any) -> None:
        self.app._event(kind, run=self.run, **fields)

    def bt(self, **fields: Any) -> None:
        self.app.server.publish_threadsafe("/tamp/bt", _text({"run": self.run, **fields}))

    def robot(self, x: float, y: float, yaw: float) -> None:
        """The robot's base at (x, y, yaw) in the robot frame."""
        self.app._publish_robot(x, y, yaw)

    def joints(self, names: list[str], positions: list[float]) -> None:
        self.app.server.publish_threadsafe(
            "/joint_states",
            {
                "header": {"frame_id": "", "stamp": stamp()},
                "name": list(names),
                "position": [float(v) for v in positions],
                "velocity": [],
                "effort": [],
            },
        )


def _text(doc: Any) -> dict[str, str]:
    return {"data": json.dumps(doc, allow_nan=False, separators=(",", ":"))}


class TampApp:
    """The session, its phase, and the services and topics above (module docstring)."""

    def __init__(self, server: RosbridgeServer, pipeline: Pipeline, *, plan_timeout: float = 120):
        self.server = server
        self.pipeline = pipeline
        self.session = DemoSession()
        self.lock = threading.RLock()
        self.phase = "idle"
        self.version = 0  # bumped by every change of the demonstration
        self.planned: tuple | None = None  # version, demo, plan, constraints, mapping
        self.runs = 0
        self.cancel = threading.Event()
        self._declare(plan_timeout)

    def _declare(self, plan_timeout: float) -> None:
        s = self.server
        for name, slot in (
            ("/tamp/state", False),
            ("/tamp/scene", False),
            ("/tamp/demo/steps", False),
            ("/tamp/plan_result", False),
            ("/tamp/execution", False),
            ("/tamp/bt", True),
        ):
            s.topic(name, STRING, latched=True, slot=slot)
        s.topic("/tamp/events", STRING)
        s.topic("/tamp/robot/pose", "geometry_msgs/PoseStamped", latched=True, slot=True)
        s.topic("/tf", "tf2_msgs/TFMessage", slot=True)
        s.topic("/joint_states", "sensor_msgs/JointState", slot=True)
        s.topic("/tf_static", "tf2_msgs/TFMessage", latched=True)
        s.topic("/tamp/demo/step", "tamp_msgs/DemoStep", inbound=self._on_step)
        begin_fields = (
            "header",
            "name",
            "robot",
            "objects",
            "free_areas",
            "area_radius",
            "object_height",
            "start",
            "appear",
        )
        s.service(
            "/tamp/demo/begin", "tamp_msgs/BeginDemo", self._begin, request_fields=begin_fields
        )
        s.service("/tamp/demo/open", "tamp_msgs/OpenDemo", self._open, request_fields=("name",))
        s.service("/tamp/demo/undo", TRIGGER, self._undo)
        s.service("/tamp/demo/reset", TRIGGER, self._reset)
        s.service("/tamp/demo/export", TRIGGER, self._export)
        s.service(
            "/tamp/plan",
            "tamp_msgs/Plan",
            self._plan,
            blocking=True,
            timeout=plan_timeout,
            request_fields=("cost_model", "constraints"),
        )
        s.service("/tamp/execute", TRIGGER, self._execute)
        s.service("/tamp/cancel", TRIGGER, self._cancel)
        s.service("/tamp/server/stats", TRIGGER, self._stats)
        self._set_phase("idle")

    # ---- state ----------------------------------------------------------------------------

    def _set_phase(self, phase: str, **extra: Any) -> None:
        self.phase = phase
        doc = {
            "phase": phase,
            "session": self.session.id,
            "run": f"r{self.runs}" if self.runs else None,
            "executor": self.pipeline.name,
            **extra,
        }
        self.server.publish_threadsafe("/tamp/state", _text(doc))

    def _event(self, kind: str, **fields: Any) -> None:
        self.server.publish_threadsafe("/tamp/events", _text({"kind": kind, **fields}))

    def _publish_steps(self) -> None:
        doc = {"session": self.session.id, "steps": self.session.steps_json()}
        self.server.publish_threadsafe("/tamp/demo/steps", _text(doc))

    def _changed(self) -> None:
        """The demonstration changed: a plan made before no longer applies."""
        self.version += 1
        self.planned = None
        self._publish_steps()
        self._set_phase("demonstrating", steps=len(self.session.demonstration_dict()["steps"]))

    @staticmethod
    def _fail(exc: Exception) -> dict[str, Any]:
        return {"success": False, "message": str(exc)}

    # ---- demonstration --------------------------------------------------------------------

    def _begin(self, _client: Client | None, args: dict[str, Any]) -> dict[str, Any]:
        with self.lock:
            if self.phase == "executing":
                return {**self._fail(SessionError("executing: cancel first")), "session_id": ""}
            try:
                message = self.session.begin(args)
            except (MessageError, TampError) as exc:
                return {**self._fail(exc), "session_id": ""}
            self._started()
            return {"success": True, "message": message, "session_id": self.session.id}

    def _open(self, _client: Client | None, args: dict[str, Any]) -> dict[str, Any]:
        """A packaged demonstration's frame, objects and free areas, without its steps."""
        from tamp.fileio import load_yaml
        from tamp.scenarios import path as packaged

        name = args.get("name")
        if not isinstance(name, str) or "/" in name or "\\" in name or not name.endswith(".yaml"):
            return {
                "success": False,
                "message": "name: a packaged demonstration, e.g. case2.yaml",
                "session_id": "",
            }
        with self.lock:
            if self.phase == "executing":
                return {**self._fail(SessionError("executing: cancel first")), "session_id": ""}
            try:
                data, _ = load_yaml(packaged(name), kind="demonstration")
                message = self.session.open(data, name)
            except (MessageError, TampError, OSError) as exc:
                return {**self._fail(exc), "session_id": ""}
            self._started()
            return {"success": True, "message": message, "session_id": self.session.id}

    def open_file(self, data: dict[str, Any], name: str) -> str:
        """Begin a session from a demonstration file's mapping (``tamp serve --demo``)."""
        with self.lock:
            message = self.session.open(data, name)
            self._started()
            return message

    def _started(self) -> None:
        self.server.publish_threadsafe("/tamp/scene", _text(self.session.scene_json()))
        self.server.publish_threadsafe(
            "/tamp/plan_result",
            _text({"session": self.session.id, "success": False, "message": "not planned"}),
        )
        frame = self.session.mr_frame()
        origin = robot_to_mr(frame, (0.0, 0.0, 0.0))
        tf = {"transforms": [_transform("mr", "robot", origin, 0.0)]}
        self.server.publish_threadsafe("/tf_static", tf)
        self._changed()

    def _on_step(self, client: Client, msg: dict[str, Any]) -> None:
        with self.lock:
            why = None
            if self.phase == "executing":
                why = "a step while executing is ignored: cancel first"
            else:
                try:
                    step = self.session.step(msg)
                except (MessageError, TampError, SessionError) as exc:
                    why = str(exc)
            if why is not None:
                self.server.counters["steps_rejected"] += 1
                self._event("step_rejected", why=why, object=str(msg.get("object_id"))[:64])
                if client.wants_status("warning"):
                    self.server._put(
                        client, json.dumps({"op": "status", "level": "warning", "msg": why}), None
                    )
                return
            self._event("step", **step)
            self._changed()

    def _undo(self, _client: Client | None, _args: dict[str, Any]) -> dict[str, Any]:
        return self._edit(self.session.undo)

    def _reset(self, _client: Client | None, _args: dict[str, Any]) -> dict[str, Any]:
        return self._edit(self.session.reset)

    def _edit(self, change: Callable[[], str]) -> dict[str, Any]:
        with self.lock:
            if self.phase == "executing":
                return self._fail(SessionError("executing: cancel first"))
            try:
                message = change()
            except SessionError as exc:
                return self._fail(exc)
            self._changed()
            return {"success": True, "message": message}

    def _export(self, _client: Client | None, _args: dict[str, Any]) -> dict[str, Any]:
        with self.lock:
            try:
                constraints = self.planned[3] if self.planned else []
                return {"success": True, "message": self.session.export(constraints)}
            except SessionError as exc:
                return self._fail(exc)

    # ---- plan and execute ----------------------------------------------------------------

    def _plan(self, _client: Client | None, args: dict[str, Any]) -> dict[str, Any]:
        empty = {"order": [], "cost": 0.0, "plan_json": ""}
        cost = args.get("cost_model") or "distance"
        if cost not in COST_MODELS:
            return {
                **empty,
                "success": False,
                "message": f"cost_model: {str(cost)[:40]!r} is not one of {', '.join(COST_MODELS)}",
            }
        with self.lock:
            if self.phase == "executing":
                return {**empty, **self._fail(SessionError("executing: cancel first"))}
            try:
                constraints = parse_constraints(args.get("constraints"))
                demo = self.session.demonstration(constraints)
                mapping = self.session.demonstration_dict(constraints)
            except (MessageError, TampError, SessionError) as exc:
                return {**empty, **self._fail(exc)}
            version = self.version
        try:
            result = self.pipeline.plan(demo, cost)
        except TampError as exc:
            self.server.publish_threadsafe(
                "/tamp/plan_result",
                _text({"session": self.session.id, "success": False, "message": str(exc)}),
            )
            return {**empty, **self._fail(exc)}
        doc = with_schema(result.to_json())  # what `tamp plan --json` prints
        plan_json = json.dumps(doc, indent=2)
        with self.lock:
            if version != self.version:
                return {
                    **empty,
                    "success": False,
                    "message": "the demonstration changed while planning: plan again",
                }
            self.planned = (version, demo, result, constraints, mapping)
            self._set_phase("planned", order=list(result.order))
        frame = self.session.mr_frame()
        goals_mr = {g["id"]: robot_to_mr(frame, tuple(g["position"])) for g in doc["goals"]}
        self.server.publish_threadsafe(
            "/tamp/plan_result",
            _text(
                {
                    "session": self.session.id,
                    "success": True,
                    "message": _order_text(result),
                    "plan": doc,
                    "goals_mr": goals_mr,
                }
            ),
        )
        return {
            "success": True,
            "message": _order_text(result),
            "order": list(result.order),
            "cost": float(result.cost),
            "plan_json": plan_json,
        }

    def _execute(self, _client: Client | None, _args: dict[str, Any]) -> dict[str, Any]:
        with self.lock:
            if self.phase == "executing":
                return self._fail(SessionError("already executing"))
            if self.planned is None or self.planned[0] != self.version:
                return self._fail(
                    SessionError("nothing planned for this demonstration: call /tamp/plan first")
                )
            _, demo, result, _, mapping = self.planned
            self.runs += 1
            run = f"r{self.runs}"
            self.cancel = threading.Event()
            self._set_phase("executing")
        channel = RunChannel(run, self.cancel, self)
        threading.Thread(
            target=self._run,
            args=(run, demo, result, mapping, channel),
            name=f"tamp-serve-{run}",
            daemon=True,
        ).start()
        return {"success": True, "message": f"run {run} started ({self.pipeline.name})"}

    def _run(self, run: str, demo: Any, result: Any, mapping: dict, channel: RunChannel) -> None:
        cancel = channel.cancel
        try:
            doc = self.pipeline.execute(demo, result, mapping, channel)
            error = None
        except RunCancelled:
            return  # the state already says so
        except TampError as exc:
            doc, error = None, str(exc)
        except Exception as exc:  # never a dead worker without a word
            log.exception("run %s failed", run)
            doc, error = None, f"internal error: {type(exc).__name__}: {exc}"
        with self.lock:
            if cancel.is_set() or f"r{self.runs}" != run:
                return  # cancelled: the state already says so
            if doc is None:
                self._event("run_failed", run=run, why=error)
                self._set_phase("failed", message=error, ok=False)
                return
            self._publish_run(run, doc)
            ok = bool(doc.get("reached", doc.get("ok", False)))
            self._set_phase("done" if ok else "failed", ok=ok, message=doc.get("reason"))

    def _publish_run(self, run: str, doc: dict[str, Any]) -> None:
        """The run's events in tick order, the tree's status, the robot's final pose."""
        events = [
            (e["clock"], 0, {"kind": e["kind"], "what": e["what"]})
            for e in doc.get("world_events", [])
        ]
        events += [
            (e["tick"], 1, {"kind": e["kind"], "condition": e["condition"], "why": e["why"]})
            for e in doc.get("growth", [])
            if e["kind"] in ("recovery", "conflict", "retry", "stop")
        ]
        if doc.get("live"):  # the executor reported its events while it ran
            events = []
        for tick, _, e in sorted(events, key=lambda x: (x[0], x[1])):
            self._event(e.pop("kind"), run=run, tick=tick, **e)
            if "what" in e:
                self.server.publish_threadsafe(
                    "/tamp/bt", _text({"run": run, "tick": tick, "running": e["what"]})
                )
        self.server.publish_threadsafe(
            "/tamp/bt",
            _text(
                {
                    "run": run,
                    "tick": doc.get("ticks"),
                    "running": None,
                    "status": doc.get("status"),
                    "tree_size": doc.get("tree_size"),
                    "goals_reached": doc.get("goals_reached"),
                }
            ),
        )
        final = doc.get("final_world") or {}
        if "robot" in final:
            self._publish_robot(*final["robot"])
        frame = self.session.mr_frame()
        final_mr = {
            uid: robot_to_mr(frame, tuple(pos))
            for uid, pos in (final.get("objects") or {}).items()
            if isinstance(pos, list | tuple) and len(pos) == 3
        }
        self.server.publish_threadsafe(
            "/tamp/execution", _text({"run": run, **doc, "final_mr": final_mr})
        )

    def _stats(self, _client: Client | None, _args: dict[str, Any]) -> dict[str, Any]:
        """The server's counters (messages in and out, drops, refusals) as JSON."""
        doc = {**self.server.counters, "clients": len(self.server.clients)}
        return {"success": True, "message": json.dumps(doc, sort_keys=True)}

    def _publish_robot(self, x: float, y: float, yaw: float) -> None:
        """The robot's base (robot frame) on /tamp/robot/pose and /tf, in ``mr``."""
        p = robot_to_mr(self.session.mr_frame(), (x, y, 0.0))
        self.server.publish_threadsafe("/tamp/robot/pose", pose_stamped(p, yaw))
        self.server.publish_threadsafe(
            "/tf", {"transforms": [_transform("mr", "base_link", p, yaw)]}
        )

    def _cancel(self, _client: Client | None, _args: dict[str, Any]) -> dict[str, Any]:
        with self.lock:
            if self.phase != "executing":
                return self._fail(SessionError(f"nothing is executing (phase {self.phase})"))
            self.cancel.set()
            self._event("cancelled", run=f"r{self.runs}")
            self._set_phase("cancelled")
            return {"success": True, "message": f"run r{self.runs} cancelled"}


def _order_text(result: Any) -> str:
    return f"order {' '.join(result.order)} cost {result.cost:.3f}"


def _transform(parent: str, child: str, p: list[float], yaw: float) -> dict[str, Any]:
    import math

    ps = pose_stamped(p, yaw, parent)
    return {
        "header": ps["header"],
        "child_frame_id": child,
        "transform": {
            "translation": ps["pose"]["position"],
            "rotation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
        },
    }


__all__ = ["PHASES", "Pipeline", "RunCancelled", "RunChannel", "ServiceError", "TampApp"]
