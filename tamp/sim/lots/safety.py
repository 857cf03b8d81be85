"""The workcell's safety monitor (Zhou et al. §IV-C, pre-collision measures) as a LeafSystem
between the arm command stream and the plant.

- Something near (class-agnostic, `tamp.sim.lots.depth_safety`): the monitor's own
  low-resolution depth camera on the wrist gives points in the world through the intrinsics
  and the camera pose (the arm's own kinematics at the measured joint angles); every point
  that is not the table, the gripper, the held object or the static scene (learnt while no
  person was in the cell, or let go by the robot) is foreign, and its distance to the end
  effector's collision boxes and the held object's box is measured. Below
  ``hand_distance`` (0.05 m) the arm holds position; it resumes when a frame shows nothing
  foreign that near. No label image, body index or pose of anything but the arm reaches
  the monitor. The rate (``image_period``,
  10 ms) and the resolution (80 x 45) follow from the arm's stopping distance and the
  person's speed: see `tamp.sim.lots.depth_safety`.
- Joint speed and acceleration limits (Franka's published values, `catalogue.ARM`): the
  measured joint speeds (plant state) and the commanded speeds and accelerations (the 1 kHz
  command, accelerations over one check period) are checked every ``check_period``; a breach
  is an emergency stop.
- Command-rate watchdog: the commands published by the stream (`tamp.sim.lots.command`)
  per check period give its rate; below ``min_command_rate`` (1000 Hz) it is an emergency
  stop.

A stop holds the arm joints at their measured positions at the stop (desired velocity zero)
and the fingers at their commanded width, and raises ``stopped`` for the skill controller,
which freezes its step clock meanwhile (so the task takes longer by the stop's duration).
An emergency stop lasts at least ``recovery`` seconds and until its cause has cleared.
Every stop is logged (`SafetyStop`: sim time, cause, duration).

Rendering is the budget: at perception's ticks while perception renders (the arm at a view),
the monitor takes a frame and, while no person is in the cell (the optional
``person_present`` input: a light curtain at the workcell's edge), learns the static scene
from it (objects resting where the robot works are not intruders). While a person is
present, or while stopped for something near, it takes a frame every ``image_period``.
Frames are counted in ``frames`` (own period) and ``shared`` (at perception's ticks).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Box, SceneGraph
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from tamp.sim.core.parsing import make_parser
from tamp.sim.core.perception import ViewTap
from tamp.sim.lots.catalogue import ARM, CLASSES
from tamp.sim.lots.depth_safety import (
    Boxes,
    Scene,
    depth_points,
    learn_background,
    learn_released,
    separation,
)
from tamp.sim.lots.scenario import SafetySettings

CAUSES = ("hand_near", "speed_limit", "accel_limit", "command_rate")
#: slack on the joint limits for the diff-IK QP's solver tolerance
LIMIT_SLACK = 1.01
EE_BODIES = (ARM.hand_body, *ARM.finger_bodies)


@dataclass(frozen=True)
class SafetyStop:
    """One stop: when it began (sim s), why, and how long the arm was held (s)."""

    time: float
    cause: str
    detail: str = ""
    duration: float = 0.0

    def to_json(self) -> dict[str, Any]:
        d = round(self.duration, 3)
        return {
            "time": round(self.time, 3),
            "cause": self.cause,
            "duration": d,
            "detail": self.detail,
        }


@dataclass(frozen=True)
class SafetyState:
    """The monitor's abstract state."""

    stop: SafetyStop | None = None  # the stop in force
    hold: np.ndarray | None = None  # the held desired positions (actuator order)
    until: float = 0.0  # an emergency stop lasts at least until then
    stops: tuple[SafetyStop, ...] = ()  # finished stops
    hand_distance: float = math.inf  # nearest foreign point in the last frame (inf: none)
    background: np.ndarray | None = None  # voxel keys of the static scene (depth_safety)
    held: tuple[RigidTransform, np.ndarray] | None = None  # the held box at the last frame
    image_time: float | None = None
    last_own_image: float = -math.inf
    frames: int = 0  # images rendered for the monitor alone
    shared: int = 0  # images read when perception rendered them anyway
    count: float = 0.0  # command count at the last check
    check_time: float | None = None
    v_cmd: np.ndarray | None = None  # commanded arm velocities at the last check
    command_rate: float = math.nan  # measured at the last check (Hz)
    min_rate: float = math.inf  # lowest rate measured while running

    def __deepcopy__(self, memo: dict) -> SafetyState:
        return self  # immutable

    def all_stops(self, now: float) -> list[SafetyStop]:
        """Finished stops and the one in force (its duration up to ``now``)."""
        out = list(self.stops)
        if self.stop is not None:
            stop = self.stop
            detail = f"{stop.detail}; still stopped at the end"
            out.append(SafetyStop(stop.time, stop.cause, detail, now - stop.time))
        return out


# ---- geometry --------------------------------------------------------------------------------
@dataclass(frozen=True)
class GripperBox:
    """A collision box of the end effector: its body, pose in the body, half sizes."""

    body: str
    X_BG: RigidTransform
    half: np.ndarray


class GripperModel:
    """The arm's own model with its collision geometry: the end effector's boxes and the
    camera pose at given joint positions (the robot's knowledge of itself, no objects)."""

    def __init__(self) -> None:
        self.plant = MultibodyPlant(0.0)
        scene_graph = SceneGraph()
        self.plant.RegisterAsSourceForSceneGraph(scene_graph)
        (model,) = make_parser(self.plant).AddModelsFromUrl(ARM.url)
        self.plant.WeldFrames(self.plant.world_frame(), self.plant.GetFrameByName(ARM.base_frame))
        self.plant.Finalize()
        inspector = scene_graph.model_inspector()
        boxes = []
        for name in EE_BODIES:
            body = self.plant.GetBodyByName(name, model)
            for gid in self.plant.GetCollisionGeometriesForBody(body):
                shape = inspector.GetShape(gid)
                if isinstance(shape, Box):
                    half = np.array([shape.width(), shape.depth(), shape.height()]) / 2
                    boxes.append(GripperBox(name, inspector.GetPoseInFrame(gid), half))
        self.boxes = tuple(boxes)
        self._bodies = {name: self.plant.GetBodyByName(name, model) for name in EE_BODIES}
        self.camera = self.plant.GetFrameByName(ARM.camera_frame, model)
        self.tcp = self.plant.GetFrameByName(ARM.tcp_frame, model)
        self.context = self.plant.CreateDefaultContext()

    def set(self, q9: np.ndarray) -> None:
        """The arm's 9 positions, in the plant's order (as the cell's ``arm_state``)."""
        self.plant.SetPositions(self.context, np.asarray(q9, float))

    def camera_pose(self) -> RigidTransform:
        return self.camera.CalcPoseInWorld(self.context)

    def tcp_pose(self) -> RigidTransform:
        return self.tcp.CalcPoseInWorld(self.context)

    def boxes_in_world(self) -> Boxes:
        out = []
        for b in self.boxes:
            X_WB = self.plant.EvalBodyPoseInWorld(self.context, self._bodies[b.body])
            out.append((X_WB @ b.X_BG, b.half))
        return out


def held_box(X_WT: RigidTransform, opening: float) -> tuple[RigidTransform, np.ndarray]:
    """The held object's box in the world: in the TCP frame (z along the approach, y across
    the pads), the catalogue's largest object between pads ``opening`` apart, from the pads'
    tops down to the largest object's height below the pads' tips."""
    reach = max(max(abs(v) for v in (f.xmin, f.xmax, f.ymin, f.ymax)) for f in _FOOTPRINTS)
    tallest = max(f.top for f in _FOOTPRINTS)
    z0, z1 = -HELD_ABOVE, PAD_BELOW + tallest
    half = np.array([reach, opening / 2, (z1 - z0) / 2])
    return X_WT @ RigidTransform([0.0, 0.0, (z0 + z1) / 2]), half


_FOOTPRINTS = tuple(c.footprint for c in CLASSES.values())
#: the pads reach this far below the TCP, and their tops this far above it (m)
PAD_BELOW = 0.015
HELD_ABOVE = 0.015
#: the fingers hold something when commanded this much closer than they are (m)
GRIP_GAP = 0.002


# ---- the stop logic (pure) -------------------------------------------------------------------
@dataclass(frozen=True)
class Checks:
    """What one check measured: the command rate and the limit breaches (cause, detail)."""

    rate: float
    breaches: tuple[tuple[str, str], ...] = ()


def check_limits(
    v_meas: np.ndarray, v_cmd: np.ndarray, v_cmd_prev: np.ndarray | None, dt: float
) -> list[tuple[str, str]]:
    """Speed and acceleration breaches of the 7 arm joints (joint order): measured and
    commanded speeds against Franka's velocity limits, the commanded accelerations over
    ``dt`` against its acceleration limits."""
    vmax = np.array(ARM.max_velocity) * LIMIT_SLACK
    amax = np.array(ARM.max_acceleration) * LIMIT_SLACK
    out = []
    for what, v in (("measured", v_meas), ("commanded", v_cmd)):
        k = int(np.argmax(np.abs(v) / vmax))
        if abs(v[k]) > vmax[k]:
            out.append(("speed_limit", f"{what} joint{k + 1} {v[k]:.2f} rad/s"))
    if v_cmd_prev is not None and dt > 0:
        a = (v_cmd - v_cmd_prev) / dt
        k = int(np.argmax(np.abs(a) / amax))
        if abs(a[k]) > amax[k]:
            out.append(("accel_limit", f"commanded joint{k + 1} {a[k]:.1f} rad/s^2"))
    return out


def next_stop(
    s: SafetyState,
    t: float,
    settings: SafetySettings,
    checks: Checks,
    new_image: bool,
    hold: np.ndarray,
) -> SafetyState:
    """The stop decision of one check: begin, keep or end a stop (see the module docstring).
    ``hold``: the desired positions to hold if a stop begins now."""
    rate_low = checks.rate < settings.min_command_rate * (1 - 1e-6)
    near = s.hand_distance < settings.hand_distance
    if s.stop is None:
        cause = None
        if new_image and near:
            cause = ("hand_near", f"something {s.hand_distance:.3f} m from the end effector")
        elif rate_low:
            cause = ("command_rate", f"{checks.rate:.0f} Hz")
        elif checks.breaches:
            cause = checks.breaches[0]
        if cause is None:
            return s
        stop = SafetyStop(t, cause[0], cause[1])
        until = t if cause[0] == "hand_near" else t + settings.recovery
        return _replace(s, stop=stop, hold=hold, until=until)
    if s.stop.cause == "hand_near":
        cleared = new_image and not near
    elif s.stop.cause == "command_rate":
        cleared = t >= s.until and not rate_low
    else:
        cleared = t >= s.until
    if not cleared:
        return s
    done = SafetyStop(s.stop.time, s.stop.cause, s.stop.detail, t - s.stop.time)
    return _replace(s, stop=None, hold=None, stops=(*s.stops, done), v_cmd=None)


def _replace(s: SafetyState, **changes) -> SafetyState:
    return dataclasses.replace(s, **changes)


def on_grid(t: float, period: float) -> bool:
    """Whether ``t`` is a tick of a periodic event of ``period`` (offset 0)."""
    k = t / period
    return abs(k - round(k)) < 1e-6


# ---- the LeafSystem --------------------------------------------------------------------------
class SafetyMonitor(LeafSystem):
    """Passes the arm command to the plant, or holds the arm (see the module docstring).

    Inputs: ``command`` (18: desired state, actuator order), ``command_count`` (1),
    ``arm_state`` (18: the plant's arm positions and velocities, joint order), the safety
    camera's ``depth_image`` (``width`` x ``height``, ``intrinsics``, at the arm's camera
    frame), ``view_request`` and ``observation`` (to know when perception renders),
    ``person_present`` (optional, 1: a person is in the workcell). ``table_z``: the height of
    the table's top (m), the one plane the monitor knows.
    Outputs: ``desired_state`` (18, to the plant), ``stopped`` (1: 1.0 while stopped).
    """

    def __init__(
        self,
        settings: SafetySettings,
        *,
        intrinsics: tuple[float, float, float, float],
        width: int,
        height: int,
        perception_period: float,
        actuator_order: list[int],
        table_z: float = 0.0,
    ):
        super().__init__()
        self.set_name("safety")
        self.settings = settings
        self.table_z = table_z
        self.size = (width, height)  # the depth image's, px
        self.intrinsics = intrinsics
        self.perception_period = perception_period
        self._order = np.asarray(actuator_order)
        self._arm_k = np.flatnonzero(self._order < 7)  # actuator slots of arm joints
        self._joint_of = self._order[self._arm_k]  # their joint indices
        self._finger_k = np.flatnonzero(self._order >= 7)  # actuator slots of the fingers
        self.gripper = GripperModel()
        self.command_port = self.DeclareVectorInputPort("command", 18)
        self.count_port = self.DeclareVectorInputPort("command_count", 1)
        self.arm_state_port = self.DeclareVectorInputPort("arm_state", 18)
        self.view = ViewTap.declare(self, width, height)
        self.depth_port = self.view.depth
        self.request_port = self.view.request
        self.observation_port = self.view.observation
        self.present_port = self.DeclareVectorInputPort("person_present", 1)
        self._state = self.DeclareAbstractState(AbstractValue.Make(SafetyState()))
        self.DeclarePeriodicUnrestrictedUpdateEvent(settings.check_period, 0.0, self._update)
        ticket = self.abstract_state_ticket(self._state)
        self.desired_state_port = self.DeclareVectorOutputPort(
            "desired_state",
            18,
            self._calc_desired,
            {ticket, self.command_port.ticket()},
        )
        self.stopped_port = self.DeclareVectorOutputPort("stopped", 1, self._calc_stopped, {ticket})
        #: (sim time, own period?, CPU seconds of rendering and judging the depth frame) of
        #: every look (measurement only, not simulation state; CPU time, so that other jobs
        #: on the machine do not count)
        self.looks: list[tuple[float, bool, float]] = []

    def state(self, context) -> SafetyState:
        return context.get_abstract_state(self._state).get_value()

    # ---- outputs ---------------------------------------------------------------------------
    def _calc_desired(self, context, output: BasicVector) -> None:
        s = self.state(context)
        if s.hold is None:
            output.SetFromVector(self.command_port.Eval(context))
        else:
            output.SetFromVector(np.r_[s.hold, np.zeros(9)])

    def _calc_stopped(self, context, output: BasicVector) -> None:
        output.SetFromVector([0.0 if self.state(context).stop is None else 1.0])

    # ---- the update ------------------------------------------------------------------------
    def _update(self, context, state) -> EventStatus:
        s = self.state(context)
        t = context.get_time()
        x = self.arm_state_port.Eval(context)
        q_meas, v_meas = x[:9], x[9:]
        command = self.command_port.Eval(context)
        count = float(self.count_port.Eval(context)[0])
        rate = math.inf
        if s.check_time is not None and t > s.check_time:
            rate = (count - s.count) / (t - s.check_time)
        v_cmd = np.zeros(7)
        v_cmd[self._joint_of] = command[9:][self._arm_k]
        breaches: list[tuple[str, str]] = []
        if s.stop is None:
            dt = t - s.check_time if s.check_time is not None else 0.0
            breaches = check_limits(v_meas[:7], v_cmd, s.v_cmd, dt)
        s = _replace(
            s,
            count=count,
            check_time=t,
            v_cmd=v_cmd if s.stop is None else None,
            command_rate=rate,
            min_rate=min(s.min_rate, rate) if s.stop is None else s.min_rate,
        )
        s, new_image = self._look(context, s, t, q_meas, command)
        hold = command[:9].copy()
        hold[self._arm_k] = q_meas[self._joint_of]
        s = next_stop(s, t, self.settings, Checks(rate, tuple(breaches)), new_image, hold)
        state.get_mutable_abstract_state(self._state).set_value(s)
        return EventStatus.Succeeded()

    def _look(self, context, s: SafetyState, t: float, q_meas, command) -> tuple[SafetyState, bool]:
        """Take a frame at perception's renders, and every ``image_period`` while a person is
        present or the arm is stopped for something near; learn the static scene while no
        person is present, else measure the nearest foreign point's distance."""
        present = self.present_port.HasValue(context) and self.present_port.Eval(context)[0] > 0.5
        shared = on_grid(t, self.perception_period) and self.view.serving(context) is not None
        watch = present or (s.stop is not None and s.stop.cause == "hand_near")
        own = watch and t - s.last_own_image >= self.settings.image_period - 1e-9
        if not (shared or own):
            return s, False
        t0 = time.process_time()
        depth = self.depth_port.Eval(context).data[..., 0]
        self.gripper.set(q_meas)
        points, too_close = depth_points(depth, self.intrinsics, self.gripper.camera_pose())
        held = self._held(q_meas, command)
        scene = Scene(self.table_z, self.gripper.boxes_in_world(), held)
        background = s.background if s.background is not None else np.zeros(0, np.int64)
        if present and s.held is not None and not held:  # let go here: the robot's doing
            background = learn_released(background, points, s.held)
        if present:
            scene = dataclasses.replace(scene, background=background)
            d = separation(points, scene, too_close)
        else:  # nobody in the cell: what the camera sees is the static scene
            background = learn_background(background, points, scene)
            d = math.inf
        self.looks.append((t, own, time.process_time() - t0))
        if own:
            s = _replace(s, frames=s.frames + 1, last_own_image=t)
        else:
            s = _replace(s, shared=s.shared + 1)
        s = _replace(s, held=held[0] if held else None, background=background)
        return _replace(s, hand_distance=d, image_time=t), True

    def _held(self, q_meas, command) -> Boxes:
        """The held object's box while the fingers are commanded closer than they are (they
        hold something), else none."""
        want = command[:9][self._finger_k]
        have = q_meas[self._order[self._finger_k]]
        if len(want) == 0 or not np.all(want < have - GRIP_GAP):
            return []
        return [held_box(self.gripper.tcp_pose(), float(np.sum(have)))]
