"""The LOTS workcell's skills as one LeafSystem, `PandaSkillController` (it drives the
Panda-like 7-DoF arm of `tamp.sim.lots.catalogue.ArmSpec`): a `SkillCommand` in, joint
targets, view requests and a `SkillStatus` out (the same messages as the SMP-MRO workcell,
`tamp.sim.core.messages`).

Skills (arguments are strings, as in `tamp.world.actions.Action`):

- ``LookAt(side)``: move the camera over W^side, settle, count what is in view (two views
  at the settled pose: perception counts only what two views confirm,
  `tamp.sim.core.perception.CONFIRM_VIEWS`); the status detail lists the counts, e.g.
  ``hammer=1,saw=1``. While holding an object that covers more
  than `LOOK_AGAIN_COVER` of the image, a second view with the hand about half a turn round
  (the camera on the other side of the held object; perception's memory joins the two).
- ``Pick(cls[, side])``: closed-loop multi-view grasp (Zhou et al. §IV-B, Fig. 6): a view at
  the look pose finds the target and makes the first prediction; the hand then moves
  continuously down towards the target's preset height (camera ``grasp.descent.
  preset_height`` above its top, the paper's 0.2 m), keeping it centred under the camera
  (differential IK, every control period), and takes a view every ``descent.view_period``
  without stopping; the grasp network runs on each and the views' best grasps are fused
  (`tamp.sim.lots.descent`). While the fused grasp is uncertain the hand descends slowly
  with the camera shifted sideways (exploring); once confident it commits and descends at
  full speed. At the preset height it executes the fused grasp, or hovers up to
  ``descent.hover`` seconds for confidence and else fails the attempt. The final approach
  (``descent.approach: closed``, the default) is one more servo step: views go on, the
  grasp moves with the target's centre (`descent.carried`) and follows the latest confident
  fusion of the same grasp (`descent.same_grasp`); the hand moves over it and turns to its
  yaw (within the wrist's range, `descent.wrist_turn`) while the camera
  still sees the target, then goes straight down, below `BLIND_DEPTH` (where the target is
  in the gripper's region of the image) without views, the goal going on at the target's
  velocity from its last views (`descent.predicted_centre`; frozen for a still target), and
  closes, lifts and checks. ``approach: open``: fixed moves from the last view of the
  descent (over the grasp, down at `APPROACH_SPEED`), corrected once by the target's
  displacement since the confident view. A grasp
  fails when the fingers close on nothing (finger width) or when the target is still on the
  table in the next view (not lifted); it is retried with new predictions up to
  ``grasp.attempts`` times, never again with a grasp that missed or slipped in this pick
  (`grasping.near_grasp`). The target is perception's track: a view without it logs
  ``target lost`` (never another instance in its place), `LOST_VIEWS` such views in a row
  fail the attempt, and the next attempt's look, not finding the track either, says so and
  re-acquires the instance of the class nearest the image centre.
- ``Place(side)``: look at W^side (at the hand's present yaw); put the held object's
  footprint (its top-view points from the grasp's views, in the hand's frame; its offset
  from the TCP kept at the grasp) where the views saw the floor bare and nothing lies,
  inside the floor's edges, at the centre (the hand's yaw kept) farthest from the floor no
  view saw, the objects seen and the remembered hidden ones (`tamp.sim.lots.room`); when
  that clearance is under `PLACE_CLEARANCE`, up to
  `PLACE_VIEWS` more views with the camera shifted sideways to where it shows most of the
  unseen floor, and if they still saw too little, the unseen floor taken as bare; lift,
  one view from
  there. In W^B of a cell that declares a stack (``stack:``, `tamp.sim.lots.stack`), an
  object of a stack class above the base goes on the object of the class below it instead:
  centred on where the view shows that one (detected, or remembered and hidden now), its
  underside `STACK_GAP` over that one's top as the depth image measures it, let go along a
  ramp of the fingers (`RELEASE_TIME`); none seen: the place fails (``object_not_found``),
  still holding.
- ``Discard()`` (also ``Place(waste)``, the ``lots_arm`` domain's name for it): drop the
  held object into the waste basket. Both places check the fingers before letting go: an
  object lost on the way is reported (FAILURE, "dropped ... while carrying it") and the
  robot no longer believes it holds it.
- ``Wait(side)``: the camera over W^side, then hold still for the ``lots_arm`` domain's
  ``Wait`` duration (Alg. 1 line 23: let one action slot pass).
- ``PickAt(side, x, y, yaw_deg)``: a scripted top grasp at a given TCP position and yaw (no
  network, one attempt; the grasp tests use it), then the same lift and check as ``Pick``.

Each skill is a queue of small steps (move, settle, grip, view, check, finish) kept in the
abstract state; views end in a handler that appends the next steps from what was seen, so
the whole skill is data in the Context and one update advances it by one control period.
Moves are straight TCP lines with a minimum-jerk profile, tracked by Drake's differential
IK (`tamp.sim.lots.kinematics`); the descent and the closed final approach are steps that
set a TCP velocity every period (position-based visual servoing on the target's centre from
the latest view: images cost ~50 ms each, so views come at ``descent.view_period``, not
every period). Only a pick's
own views ask perception for a target (and so for a colour image): a class left from an
earlier pick never makes a later look render colour or follow an instance.
A new command id starts a skill (while another runs it is cancelled first); ``cancel=True``
stops the arm where it is (braking within the acceleration limits) and reports FAILURE
("cancelled").
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from tamp.lots.cell import WASTE, lots_domain
from tamp.sim.core.camera import backproject
from tamp.sim.core.messages import Observation, SkillCommand, SkillStatus, ViewRequest
from tamp.sim.core.perception import CONFIRM_VIEWS
from tamp.sim.core.timing import Stopwatch
from tamp.sim.lots.catalogue import ARM
from tamp.sim.lots.descent import (
    GATE_TOLERANCE,
    FusedGrasp,
    Thresholds,
    ViewGrasp,
    approach_aim,
    approach_velocity,
    carried,
    confident,
    explore_offset,
    fuse,
    predicted_centre,
    same_grasp,
    seen_velocity,
    turn_rate,
    wholly_in_view,
    wrist_turn,
)
from tamp.sim.lots.grasping import GraspCandidate, GraspPlanner, near_grasp
from tamp.sim.lots.kinematics import ArmKinematics, down, hand_yaw_for_closing, pose_error
from tamp.sim.lots.room import Room, disc, empty_room, footprint, next_look, observed, place
from tamp.sim.lots.scenario import CellScenario
from tamp.sim.lots.stack import STACK_SIDE, below, support
from tamp.world.interface import Status

SKILLS = ("LookAt", "Pick", "PickAt", "Place", "Discard", "Wait")
OPEN = ARM.finger_max
CLOSED = 0.0
#: fingers closer than this (sum of both, m) after closing: nothing between them
MIN_HOLD_WIDTH = 0.004
#: lowest TCP height over the table for a grasp: the pads' lower edge 2 mm above it
MIN_GRASP_Z = 0.017
GRASP_DEPTH = 0.025  # how far below the object's top the TCP goes (pads reach 15 mm lower)
LIFT_Z = 0.16
ANGULAR_SPEED = 1.2  # rad/s, peak TCP angular speed of a move (minimum jerk: 1.875 x the mean)
APPROACH_SPEED = 0.15  # m/s (mean 0.08), the last 12 cm to the grasp
CARRY_SPEED = 0.2  # m/s, mean TCP speed of moves while the fingers are closed
#: a look while holding is taken again, with the hand turned about half a turn, when the
#: held object covers more than this share of the image (it hides the table behind it)
LOOK_AGAIN_COVER = 0.02
#: the half turn's bounds: short of pi (a slerp over exactly pi has no direction) and within
#: this much of the wrist-centred yaw (the wrist's +-2.9 rad less a margin)
HALF_TURN = math.pi - 0.1
WRIST_REACH = 2.6
#: views in a row without the target that end a descent (it left the view)
LOST_VIEWS = 3
#: a descent that has not reached the preset height after this long (sim s) gives up
DESCENT_TIMEOUT = 30.0
#: the closed final approach stops correcting its goal from views once the camera is this
#: close (m) above the target's top (measured in the views): perception takes every pixel
#: nearer than 0.12 m (its ``hand_depth``, `tamp.sim.core.perception`) for the gripper's,
#: so the target's top vanishes from the views there. That is the binding limit of the
#: geometry in ``lots_arm.sdf``: the camera sits 5.54 cm above the TCP and 6.5 cm off its
#: axis, so the target under the TCP leaves the field of view (+-34.6 deg across the image's
#: width) only at 0.094 m, and the 0.03 m near plane (``camera.near``) is where the target's
#: top is with the TCP at the grasp (2.5 cm under the top); the fingers (pads 1.5 cm below
#: the TCP, 7 cm from the camera) stay inside the gripper's region throughout. 2 cm over
#: 0.12 m keep a whole flat top beyond it (a view whose target is cut there shows part of it,
#: and its centre moves with the cut). So the last 11 cm of the TCP's way down are blind
BLIND_DEPTH = 0.14
#: the closed approach goes below that height only over the goal: within this distance (m)
#: and yaw (rad) of it (`descent.approach_aim`)
APPROACH_REACH = 0.004
APPROACH_TURN = math.radians(3.0)
#: the hand's yaw rate changes by at most this much per second in the closed approach
#: (rad/s^2; Franka's wrist allows 20; a minimum-jerk half turn of a move peaks near 3)
TURN_ACCEL = 4.0
#: a closed approach that has not reached its grasp after this long (sim s) gives up
APPROACH_TIMEOUT = 10.0
#: peak TCP angular speed of that turn (rad/s): the wrist alone turns the hand there, and
#: Franka's last joint allows 2.61 rad/s (the IK plans within 90 %)
TURN_SPEED = 2.0
#: a place's footprint keeps this far from anything and from the floor's edges (m)
PLACE_CLEARANCE = 0.01
#: views a place may add when its views showed no room for the held object
PLACE_VIEWS = 2
#: ... only when a spot that much clearer may lie in the floor no view saw yet (m)
PLACE_GAIN = 0.02
#: the held object's underside this far (m) above where it goes when the fingers open: on
#: the floor, and on a stack's top measured from depth (`STACK_GAP`). An 8 mm drop onto a
#: stack let the opening fingers drag the tower's body 2 cm across the bottom's top (seen on
#: the plant); from 2 mm it lands where it was put
RELEASE_GAP = 0.008
STACK_GAP = 0.002
#: a level put on a stack is let go along a ramp of the fingers' target, from closed to open
#: over this long (s): the squeeze eases off on both pads together. Opened in one step, the
#: compliant pads let go unevenly and flicked the body 1-2 cm across the bottom's 6 cm top
RELEASE_TIME = 1.0
#: after a place the TCP rises at least this far (m) above where it let go
PLACE_LIFT = 0.12


@dataclass(frozen=True)
class Step:
    """One step of a skill. ``pose``: TCP goal (x, y, z, yaw) of a move."""

    #: move | descend | approach | brake | settle | grip | release | wait | view |
    #: check_fingers | check_held | finish
    kind: str
    pose: tuple[float, float, float, float] | None = None
    speed: float = 0.0
    turn_speed: float = 0.0  # peak TCP angular speed of a move (0: `ANGULAR_SPEED`)
    width: float = 0.0
    handler: str = ""
    duration: float = 0.0
    status: Status = Status.SUCCESS
    detail: str = ""
    cause: str | None = None  # a failing finish's `tamp.sim.core.outcome.CAUSES` code


@dataclass
class SkillState:
    """The controller's abstract state: the running command, the arm targets, the step
    queue, what the pick has learned so far, and a log of what happened (sim times)."""

    q: np.ndarray
    v: np.ndarray = field(default_factory=lambda: np.zeros(7))
    finger: float = OPEN
    command: SkillCommand = field(default_factory=SkillCommand)
    status: SkillStatus = field(default_factory=SkillStatus)
    steps: tuple[Step, ...] = ()
    step_t0: float | None = None
    move_from: tuple | None = None  # (p, quaternion wxyz, duration)
    request: ViewRequest = field(default_factory=ViewRequest)
    next_view: int = 1
    side: str = "A"
    target_cls: str | None = None
    track: int | None = None
    target_xy: tuple[float, float] | None = None
    #: (render time, x, y, whole) of the target's centre in this attempt's latest views that
    #: showed it (``whole``: all of it, not cut by the image's edge): where it is now for the
    #: closed approach (`descent.predicted_centre`)
    seen_at: tuple[tuple[float, float, float, bool], ...] = ()
    target_top: float = 0.0  # the target's top above the table, from the last view
    #: the target's top-view points in the table plane round its centre (N x 2, world
    #: axes): the widest of this attempt's views (a low view may show only part of it)
    target_shape: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    views_done: int = 0  # views of this attempt (the look's and the descent's)
    #: the descent (`tamp.sim.lots.descent`): the latest views' best grasps, their fusion,
    #: whether the hand committed, the other objects' centres in the latest view, views in a
    #: row without the target, the exploring views so far, when the last view was asked
    #: for, when the lowest point was reached (None: not yet)
    window: tuple[ViewGrasp, ...] = ()
    fused: FusedGrasp | None = None
    committed: bool = False
    #: the latest confident fusion and the target's centre then: the grasp executed (views
    #: after the commit refine it only while they stay confident)
    sure: tuple[FusedGrasp, tuple[float, float]] | None = None
    others: tuple[tuple[float, float], ...] = ()
    lost: int = 0
    explored: int = 0
    view_asked: float | None = None
    view_done_t: float = 0.0
    bottom_t: float | None = None
    #: the descent's and the closed approach's TCP set point (x, y, z), its velocity (m/s),
    #: the hand's yaw and its rate (rad/s; the descent keeps the yaw)
    servo: tuple[np.ndarray, np.ndarray, float, float] | None = None
    #: (time, measured arm joints) of the last control periods: a view taken while moving is
    #: back-projected from where the camera was when it was rendered
    recent_q: tuple[tuple[float, np.ndarray], ...] = ()
    chosen: GraspCandidate | None = None
    #: (x, y, yaw) of this pick's grasps that missed or slipped: a retry takes another
    missed: tuple[tuple[float, float, float], ...] = ()
    attempt: int = 0
    held: str | None = None
    hold_z: float = MIN_GRASP_Z  # TCP height above the object's bottom when it was picked
    #: the held object's centre relative to the TCP, in the hand's frame (x, y; m), and its
    #: reach: `Place` puts the object, not the TCP, on the free spot
    hold_offset: tuple[float, float] = (0.0, 0.0)
    #: ... and its footprint round its centre in the hand's frame (K x 2; `room.footprint`)
    hold_shape: np.ndarray = field(default_factory=lambda: np.zeros((1, 2)))
    grasp_attempts: int = 0
    grasp_successes: int = 0
    picks_tried: int = 0  # grasp attempts of network picks (the chance failures' index)
    injected: bool = False  # this attempt fails by the run's drawn chance: the hand stays open
    #: what the place's views showed of the workspace's floor, and the extra views taken
    room: Room | None = None
    place_views: int = 0
    #: (workspace, its floor as the looks while holding showed it): a `Place` there next
    #: starts from it (a look's other pose showed what the held object hides in the place's)
    looked: tuple[str, Room] | None = None
    log: list[tuple[float, str]] = field(default_factory=list)

    def __deepcopy__(self, memo: dict) -> SkillState:
        new = copy.copy(self)
        new.q = self.q.copy()
        new.v = self.v.copy()
        new.log = list(self.log)
        return new


def min_jerk(s: float) -> float:
    s = min(max(s, 0.0), 1.0)
    return s**3 * (10 - 15 * s + 6 * s * s)


class PandaSkillController(LeafSystem):
    """Runs the workcell's skills; see the module docstring."""

    def __init__(
        self,
        scenario: CellScenario,
        kin: ArmKinematics,
        planner: GraspPlanner | None,
        q0: np.ndarray,
        actuator_order: list[int],
    ):
        super().__init__()
        self.set_name("skills")
        self.scenario = scenario
        self.kin = kin
        self.planner = planner
        self.dt = scenario.control.period
        #: how far the camera is above the TCP with the hand pointing down (m; 0.0554)
        self._camera_lift = float(
            (RigidTransform(down(0.0), np.zeros(3)) @ kin.X_TC).translation()[2]
        )
        self._order = list(actuator_order)
        #: time spent in the update (differential IK, view handlers, the grasp network calls
        #: they make: `GraspPlanner.network` times those); measurement only
        self.control = Stopwatch()
        self._zeros9 = np.zeros(9)
        #: whether pick attempt k+1 of the run fails by the drawn chance (``perturbation.
        #: skills.Pick``): the hand does not close, like the SMP-MRO workcell's injected losses
        self._chance = () if scenario.sample is None else scenario.sample.skill_failures("Pick")
        self.command_port = self.DeclareAbstractInputPort(
            "skill_command", AbstractValue.Make(SkillCommand())
        )
        self.arm_state_port = self.DeclareVectorInputPort("arm_state", 18)
        self.observation_port = self.DeclareAbstractInputPort(
            "observation", AbstractValue.Make(Observation())
        )
        #: 1.0 while the safety monitor holds the arm: the skill's clock stands still
        self.hold_port = self.DeclareVectorInputPort("hold", 1)
        init = SkillState(q=np.array(q0[:7], float), finger=float(q0[7]))
        self._state = self.DeclareAbstractState(AbstractValue.Make(init))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.dt, 0.0, self._update)
        ticket = {self.abstract_state_ticket(self._state)}
        self.desired_state_port = self.DeclareVectorOutputPort(
            "desired_state", 18, self._calc_desired, prerequisites_of_calc=ticket
        )
        self.view_request_port = self.DeclareAbstractOutputPort(
            "view_request",
            lambda: AbstractValue.Make(ViewRequest()),
            self._calc_request,
            prerequisites_of_calc=ticket,
        )
        self.status_port = self.DeclareAbstractOutputPort(
            "skill_status",
            lambda: AbstractValue.Make(SkillStatus()),
            self._calc_status,
            prerequisites_of_calc=ticket,
        )

    # ---- outputs -------------------------------------------------------------------------
    def state(self, context) -> SkillState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_desired(self, context, output: BasicVector) -> None:
        s = self.state(context)
        q9 = np.concatenate((s.q, (s.finger, s.finger)))
        output.SetFromVector(np.concatenate((q9[self._order], self._zeros9)))

    def _calc_request(self, context, output) -> None:
        output.set_value(self.state(context).request)

    def _calc_status(self, context, output) -> None:
        output.set_value(self.state(context).status)

    # ---- the update ----------------------------------------------------------------------
    def _update(self, context, state) -> EventStatus:
        with self.control:
            return self._update_timed(context, state)

    def _update_timed(self, context, state) -> EventStatus:
        current = self.state(context)
        cmd: SkillCommand = self.command_port.Eval(context)
        running = current.steps and current.status.status is Status.RUNNING
        moving = bool(np.any(current.v))  # a skill ended mid-move: still braking
        if not running and not moving and (cmd.id == 0 or cmd.id == current.command.id):
            return EventStatus.DidNothing()  # idle, no new command: nothing to copy or write
        s: SkillState = copy.deepcopy(current)
        t = context.get_time()
        x = self.arm_state_port.Eval(context)
        q_meas, v_meas = x[:9], x[9:]
        if cmd.id != s.command.id and cmd.id != 0 and not cmd.cancel:
            if s.steps and s.status.status is Status.RUNNING:
                s.log.append((t, f"{s.command} preempted by {cmd}"))
            self._start(s, cmd, t)
        elif cmd.cancel and cmd.id == s.command.id and s.status.status is Status.RUNNING:
            self._finish(s, t, Status.FAILURE, "cancelled")
        held = self.hold_port.HasValue(context) and self.hold_port.Eval(context)[0] > 0.5
        if held and s.steps and s.status.status is Status.RUNNING:
            # stopped by the safety monitor: the targets follow the held arm; a move starts
            # afresh where the arm stands when it resumes (a new minimum-jerk profile), any
            # other step's clock stands still
            kind = s.steps[0].kind
            if kind in ("move", "descend", "approach"):
                s.step_t0, s.move_from = None, None
            elif s.step_t0 is not None:
                s.step_t0 += self.dt
            q_held = np.array(q_meas[:7], float)
            # the command stream carries these targets' rate (the held arm still settling):
            # a motion that resumes goes on from it within the acceleration limits. Resumed
            # from rest instead, a closed approach's first step (at full acceleration) went
            # against the settling arm's rate: joint 6 at 21.7 rad/s^2, over Franka's 20
            motion = kind in ("move", "descend", "approach", "brake")
            s.v = (q_held - s.q) / self.dt if motion else np.zeros(7)
            s.q = q_held
        elif s.steps and s.status.status is Status.RUNNING:
            obs: Observation = self.observation_port.Eval(context)
            self._advance(s, t, q_meas, v_meas, obs)
        elif np.any(s.v):
            # cancelled (or failed) mid-move: come to rest within the acceleration limits
            # where the arm is, rather than stopping the targets in one period
            s.v = self.kin.brake(s.v)
            s.q = s.q + s.v * self.dt
        state.get_mutable_abstract_state(self._state).set_value(s)
        return EventStatus.Succeeded()

    def _start(self, s: SkillState, cmd: SkillCommand, t: float) -> None:
        s.command = cmd
        s.status = SkillStatus(cmd.id, Status.RUNNING)
        s.steps, s.step_t0, s.move_from = (), None, None
        s.log.append((t, f"start {cmd}"))
        name, args = cmd.name, cmd.args
        sides = self.scenario.workspaces
        if name not in ("LookAt", "Place") or s.held is None:
            s.looked = None  # only the looks of the carry since the pick count
        if name == "LookAt" and len(args) == 1 and args[0] in sides:
            s.side = args[0]
            s.steps = (*self._look(args[0]), *self._views("counted"))
        elif name == "Pick" and 1 <= len(args) <= 2 and (len(args) == 1 or args[1] in sides):
            if s.held is not None:
                return self._finish(s, t, Status.FAILURE, f"already holding {s.held}")
            s.side = args[1] if len(args) == 2 else "A"
            s.target_cls, s.track, s.attempt, s.missed = args[0], None, 1, ()
            self._begin_attempt(s)
        elif name == "PickAt" and len(args) == 4 and args[0] in sides:
            if s.held is not None:
                return self._finish(s, t, Status.FAILURE, f"already holding {s.held}")
            try:
                x, y, yaw = (float(a) for a in args[1:])
            except ValueError:
                return self._finish(s, t, Status.FAILURE, f"PickAt needs numbers: {cmd}")
            s.side, s.target_cls, s.track, s.attempt = args[0], "object", None, 1
            s.hold_z = MIN_GRASP_Z
            s.hold_offset, s.hold_shape = (0.0, 0.0), disc()  # unmeasured: the TCP's spot
            s.grasp_attempts += 1
            s.steps = self._grasp_steps(x, y, MIN_GRASP_Z, math.radians(yaw), args[0])
        elif name == "Place" and len(args) == 1 and args[0] in sides:
            if s.held is None:
                return self._finish(s, t, Status.FAILURE, "nothing held")
            looked = s.looked[1] if s.looked is not None and s.looked[0] == args[0] else None
            s.side, s.room, s.place_views, s.looked = args[0], looked, 0, None
            # at the hand's present yaw (a look while holding may have turned it half round):
            # any yaw serves for looking and putting down, and turning back costs seconds
            yaw = self.kin.tcp_yaw(s.q)
            s.steps = (
                self._move(self.look_pose(args[0], yaw=yaw)),
                Step("settle"),
                Step("view", handler="place"),
            )
        elif name == "Wait" and len(args) == 1 and args[0] in sides:
            s.side = args[0]
            s.steps = (
                *self._look(args[0]),
                Step("wait", duration=lots_domain().templates["Wait"].duration),
                Step("finish", detail="waited"),
            )
        elif (name == "Discard" and not args) or (name == "Place" and args == (WASTE,)):
            if s.held is None:
                return self._finish(s, t, Status.FAILURE, "nothing held")
            bx, by = self.scenario.waste_basket
            s.steps = (
                self._move((bx, by, 0.30, 0.0)),
                Step("check_held"),
                Step("grip", width=OPEN),
                Step("wait", duration=0.4),
                Step("finish", detail="discarded", handler="released"),
            )
        else:
            self._finish(s, t, Status.FAILURE, f"unknown skill {cmd} (known: {', '.join(SKILLS)})")

    def _finish(
        self, s: SkillState, t: float, status: Status, detail: str = "", cause: str | None = None
    ) -> None:
        """End the running skill; a FAILURE carries its ``cause`` (`tamp.sim.core.outcome.
        CAUSES`; the skill layer's misuse, e.g. nothing held, is ``task_failed``)."""
        if status is Status.FAILURE and cause is None:
            cause = "task_failed"
        s.status = SkillStatus(s.command.id, status, detail, cause)
        s.steps, s.step_t0, s.move_from = (), None, None
        s.log.append((t, f"{status.value} {s.command}{': ' + detail if detail else ''}"))

    # ---- step plans ----------------------------------------------------------------------
    def look_pose(
        self,
        side: str,
        height: float | None = None,
        at: tuple[float, float] | None = None,
        yaw: float = 0.0,
    ) -> tuple[float, float, float, float]:
        """TCP pose (x, y, z, yaw) that puts the camera ``height`` above the table at ``at``
        (default: the look height over the workspace centre), looking straight down."""
        h = self.scenario.control.look_height if height is None else height
        x, y = self.scenario.workspaces[side].center if at is None else at
        X_WC = RigidTransform(down(yaw), [x, y, h])
        p = self.kin.tcp_for_camera(X_WC).translation()
        return (float(p[0]), float(p[1]), float(p[2]), float(yaw))

    def half_turn(self, s: SkillState) -> float:
        """The yaw about half a turn from the hand's, turning the wrist towards the middle of
        its range and never more than `WRIST_REACH` from it."""
        now = self.kin.tcp_yaw(s.q)
        centre = self.kin.wrist_centred_yaw(s.q)
        towards = math.remainder(centre - now, 2 * math.pi)
        yaw = now + math.copysign(HALF_TURN, towards)
        off = math.remainder(yaw - centre, 2 * math.pi)
        return centre + max(-WRIST_REACH, min(WRIST_REACH, off))

    def _move(self, pose, speed: float | None = None, turn_speed: float = 0.0) -> Step:
        return Step(
            "move",
            pose=tuple(float(v) for v in pose),
            speed=speed or self.scenario.control.speed,
            turn_speed=turn_speed,
        )

    def _look(self, side: str) -> tuple[Step, ...]:
        return (self._move(self.look_pose(side)), Step("settle"))

    @staticmethod
    def _views(handler: str) -> tuple[Step, ...]:
        """A look's views at its settled pose: `perception.CONFIRM_VIEWS` of them, the last
        one read by ``handler``: what one view alone shows is not counted, one view's miss
        does not forget (`tamp.sim.core.perception`)."""
        first = tuple(Step("view", handler="seen") for _ in range(CONFIRM_VIEWS - 1))
        return (*first, Step("view", handler=handler))

    def _begin_attempt(self, s: SkillState) -> None:
        self._reset_descent(s)
        s.chosen, s.target_xy = None, None
        s.steps = (*self._look(s.side), Step("view", handler="target"))

    @staticmethod
    def _reset_descent(s: SkillState) -> None:
        s.views_done, s.window, s.fused, s.committed, s.others = 0, (), None, False, ()
        s.sure = None
        s.lost, s.explored, s.view_asked, s.bottom_t, s.servo = 0, 0, None, None, None
        s.target_shape = np.zeros((0, 2))
        s.seen_at = ()

    # ---- step execution ------------------------------------------------------------------
    def _advance(self, s, t, q_meas, v_meas, obs: Observation) -> None:
        step = s.steps[0]
        if s.step_t0 is None:
            s.step_t0 = t
            self._enter(s, step, t, q_meas)
        el = t - s.step_t0
        done = False
        if step.kind == "move":
            done = self._track(s, el)
        elif step.kind == "descend":
            return self._descend(s, t, el, q_meas, obs)
        elif step.kind == "approach":
            return self._approach(s, t, el, q_meas, obs)
        elif step.kind == "brake":
            s.v = self.kin.brake(s.v)
            s.q = s.q + s.v * self.dt
            done = not np.any(s.v)
            if done:
                s.steps, s.step_t0, s.move_from = s.steps[1:], None, None
            return
        elif step.kind == "settle":
            ok = np.max(np.abs(v_meas[:7])) < 0.03 and np.max(np.abs(q_meas[:7] - s.q)) < 0.01
            done = (el >= 0.1 and ok) or el >= 1.0
        elif step.kind == "grip":
            done = (el >= 0.3 and np.max(np.abs(v_meas[7:])) < 0.003) or el >= 1.5
        elif step.kind == "wait":
            done = el >= step.duration
        elif step.kind == "release":  # open along a ramp (`RELEASE_TIME`)
            s.finger = CLOSED + (OPEN - CLOSED) * min(el / step.duration, 1.0)
            done = el >= step.duration and np.max(np.abs(v_meas[7:])) < 0.003
        elif step.kind == "view":
            if obs.id == s.request.id:
                s.steps = s.steps[1:]
                s.step_t0 = None
                getattr(self, f"_on_{step.handler}")(s, t, obs, q_meas)
                return
        elif step.kind == "check_fingers":
            if q_meas[7] + q_meas[8] < MIN_HOLD_WIDTH:
                s.steps, s.step_t0 = s.steps[1:], None
                return self._retry(s, t, "missed: the fingers closed on nothing", "grasp_missed")
            done = True
        elif step.kind == "check_held":
            if q_meas[7] + q_meas[8] < MIN_HOLD_WIDTH:
                # lost on the way: one more view, so that what the controller observes
                # after this failure shows the empty gripper (not the view before the drop)
                lost, s.held, s.target_cls, s.track = s.held, None, None, None
                s.steps, s.step_t0, s.move_from = (
                    (
                        Step("view", handler="seen"),
                        Step(
                            "finish",
                            status=Status.FAILURE,
                            detail=f"dropped the {lost} while carrying it",
                            cause="grasp_slipped",
                        ),
                    ),
                    None,
                    None,
                )
                return
            done = True
        elif step.kind == "finish":
            if step.handler == "released":
                s.held = None
            return self._finish(s, t, step.status, step.detail, step.cause)
        if done:
            s.steps, s.step_t0, s.move_from = s.steps[1:], None, None
            s.v = np.zeros(7)

    def _enter(self, s: SkillState, step: Step, t: float, q_meas: np.ndarray) -> None:
        if step.kind == "move":
            X0 = self.kin.tcp_pose(s.q)
            x, y, z, yaw = step.pose
            X1 = RigidTransform(down(yaw), [x, y, z])
            dist = float(np.linalg.norm(X1.translation() - X0.translation()))
            ang = float(np.linalg.norm(pose_error(X0, X1)[:3]))
            # with the fingers closed (carrying) the arm moves slower: friction grasps slip
            speed = step.speed if s.finger != CLOSED else min(step.speed, CARRY_SPEED)
            T = max(1.875 * dist / speed, 1.875 * ang / (step.turn_speed or ANGULAR_SPEED), 0.2)
            s.move_from = (X0.translation().copy(), X0.rotation().ToQuaternion().wxyz(), T)
        elif step.kind in ("descend", "approach"):
            p = self.kin.tcp_pose(s.q).translation().copy()
            s.servo = (p, np.zeros(3), self.kin.tcp_yaw(s.q), 0.0)
            if step.kind == "approach":
                s.finger = OPEN  # on the way: the pads are 7 cm or more above the target
        elif step.kind == "grip":
            s.finger = step.width
        elif step.kind == "view":
            # where the camera is, from the arm's own kinematics (the arm has settled):
            # perception back-projects what it sees and projects what it remembers with it;
            # only a pick's views look for its target (and render colour)
            X_WC = self.kin.camera_pose(q_meas[:7])
            aim = step.handler == "target"
            target, track = (s.target_cls, s.track) if aim else (None, None)
            if step.handler == "lifted":  # is the track the grasp picked in the gripper?
                track = s.track
            s.request = ViewRequest(s.next_view, s.side, target, track, X_WC)
            s.next_view += 1

    def _track(self, s: SkillState, el: float) -> bool:
        """One differential-IK step along the current move; True when it has arrived."""
        p0, w0, T = s.move_from
        x, y, z, yaw = s.steps[0].pose
        X1 = RigidTransform(down(yaw), [x, y, z])
        a = min_jerk((el + self.dt) / T)
        q0 = Quaternion(np.asarray(w0))
        w = q0.slerp(a, X1.rotation().ToQuaternion()).wxyz()
        rot = RotationMatrix(Quaternion(w / np.linalg.norm(w)))
        X_des = RigidTransform(rot, (1 - a) * np.asarray(p0) + a * X1.translation())
        if el >= T:
            err = pose_error(self.kin.tcp_pose(s.q), X1)
            there = bool(np.linalg.norm(err[3:]) < 0.002 and np.linalg.norm(err[:3]) < 0.01)
            # the next step starts from rest: arrive only when stopping now keeps within the
            # acceleration limits (else the safety monitor stops the arm), and arrive where
            # the arm stands: a setpoint moved in the period its velocity drops to zero would
            # send the 1 kHz stream that step's speed, and a next move starting the other way
            # would reverse it at twice the limit
            if (there or el >= T + 1.0) and bool(np.all(np.abs(s.v) <= self.kin.amax * self.dt)):
                return True
        if el >= T + 2.0:
            # the pose was not reached in time: give it up, braking to rest within the
            # acceleration limits rather than dropping the velocity to zero in one step
            v = self.kin.brake(s.v)
        else:
            X_now = self.kin.tcp_pose(s.q)
            V = pose_error(X_now, X_des) / self.dt
            v, _ = self.kin.step(s.q, s.v, V)
        if not np.all(np.isfinite(v)):  # never command a non-finite target: brake instead
            v = self.kin.brake(s.v)
        s.q = s.q + v * self.dt
        s.v = v
        return False

    # ---- view handlers -------------------------------------------------------------------
    def _on_counted(self, s: SkillState, t: float, obs: Observation, q_meas) -> None:
        self._look_room(s, obs, q_meas)
        if s.held is not None and obs.hand_cover > LOOK_AGAIN_COVER:
            # the held object hides a patch of the workspace (what the person put there while
            # the robot carried it may lie behind it): look again with the camera on the
            # other side of it; perception's memory joins the two views (what the first saw
            # and the second cannot is counted as occluded)
            held = ",".join(obs.in_hand) or s.held
            s.log.append((t, f"held {held} covers {obs.hand_cover:.0%} of the view: look again"))
            pose = self.look_pose(s.side, yaw=self.half_turn(s))
            s.steps = (
                self._move(pose, turn_speed=TURN_SPEED),
                Step("settle"),
                *self._views("recounted"),
            )
            return
        self._report_counts(s, t, obs)

    def _on_recounted(self, s: SkillState, t: float, obs: Observation, q_meas) -> None:
        self._look_room(s, obs, q_meas)
        self._report_counts(s, t, obs)

    def _look_room(self, s: SkillState, obs: Observation, q_meas) -> None:
        """A look while holding adds what it shows of the workspace's floor to
        `SkillState.looked`, for the `Place` there next."""
        if s.held is None or obs.floor is None:
            return
        room = s.looked[1] if s.looked is not None and s.looked[0] == s.side else None
        s.looked = (s.side, self._room_seen(s.side, room, obs, self.kin.camera_pose(q_meas[:7])))

    def _room_seen(self, side: str, room: Room | None, obs: Observation, X_WC) -> Room:
        """``room`` (None: workspace ``side``'s floor, nothing seen yet) with what view
        ``obs`` (taken at ``X_WC``) shows of the floor: bare cells, the pixels of what
        stands on it, the remembered hidden objects (`tamp.sim.lots.room.observed`)."""
        if room is None:
            ws = self.scenario.workspaces[side]
            room = empty_room(ws.center, ws.floor_size, ws.floor)
        return observed(
            room,
            X_WC,
            self.planner.intrinsics,
            occupied=obs.occupied,
            floor=obs.floor,
            avoid=obs.occluded,
        )

    def _report_counts(self, s: SkillState, t: float, obs: Observation) -> None:
        detail = ",".join(f"{k}={v}" for k, v in sorted(obs.counts.items()))
        if obs.occluded:  # counted, but remembered rather than seen: say so
            detail += "; occluded " + ",".join(sorted(m.cls for m in obs.occluded))
        self._finish(s, t, Status.SUCCESS, detail)

    def _on_seen(self, s: SkillState, t: float, obs: Observation, q_meas) -> None:
        """A view only for the record (the observation the controller reads next)."""

    def _on_target(self, s: SkillState, t: float, obs: Observation, q_meas) -> None:
        """The first view of an attempt (the look pose): find the target, make the first
        prediction, start the descent."""
        if obs.target is None and s.track is not None:
            # the instance followed so far is not in view: say so, then choose afresh
            s.log.append(
                (
                    t,
                    f"target lost: track {s.track} not in view at the look pose; "
                    f"re-acquiring the {s.target_cls} nearest the image centre",
                )
            )
            s.track = None
            s.steps = (Step("view", handler="target"),)
            return
        if obs.target is None:
            if s.attempt == 1:
                return self._finish(
                    s, t, Status.FAILURE, f"no {s.target_cls} in W^{s.side}", "object_not_found"
                )
            return self._retry(s, t, f"no {s.target_cls} in W^{s.side}", "object_not_found")
        self._see(s, t, obs, self.kin.camera_pose(q_meas[:7]))
        s.view_done_t = t
        s.steps = (Step("descend"),)

    def _see(self, s: SkillState, t: float, obs: Observation, X_WC: RigidTransform) -> None:
        """One view of the pick (``X_WC``: the camera when it was rendered): where the target
        is, its best grasp (clear first, then seated, then quality: `GraspPlanner.
        candidates`), the fused grasp over the window, commit when confident."""
        d = self.scenario.grasp.descent
        crop = obs.target
        s.views_done += 1
        if crop is None:
            s.lost += 1
            centre = s.target_xy or (0.0, 0.0)
            s.window = (*s.window, ViewGrasp(None, centre))[-d.window :]
            what = f"track {s.track}" if s.track is not None else f"no {s.target_cls}"
            s.log.append((t, f"view {s.views_done}: target lost ({what} not in view)"))
            return
        s.lost = 0
        det = crop.detection
        s.track = det.track
        p = backproject(det.u, det.v, det.depth, self.planner.intrinsics, X_WC)
        s.target_xy = (float(p[0]), float(p[1]))
        s.target_top = max(float(p[2]), 0.0)  # median depth of its pixels: about its top
        shape = top_view_points(crop, self.planner.intrinsics, X_WC) - s.target_xy
        if len(shape) and (
            not len(s.target_shape) or np.hypot(*shape.T).max() > np.hypot(*s.target_shape.T).max()
        ):
            s.target_shape = shape
        whole = self._wholly_in_view(s, s.target_xy, X_WC)
        s.seen_at = (*s.seen_at[-(2 * d.window) :], (obs.time, *s.target_xy, whole))
        s.others = tuple(
            (float(q[0]), float(q[1]))
            for o in obs.detections
            if o.track != det.track
            for q in [backproject(o.u, o.v, o.depth, self.planner.intrinsics, X_WC)]
        )
        height = float(X_WC.translation()[2]) - s.target_top  # camera above the target
        cands = [
            c
            for c in self.planner.candidates(crop, X_WC.GetAsMatrix4(), height)
            if not any(near_grasp(c, m) for m in s.missed)
        ]
        best = cands[0] if cands else None
        s.window = (*s.window, ViewGrasp(best, s.target_xy))[-d.window :]
        s.fused = fuse(s.window, s.target_xy)
        f = s.fused
        sure = confident(f, Thresholds.of(d))
        s.log.append(
            (
                t,
                f"view {s.views_done} at {height:.2f} m: {s.target_cls} at "
                f"({p[0]:.3f}, {p[1]:.3f}), "
                + (f"best q={best.quality:.2f}" if best else "no grasp on it")
                + (
                    f"; fused over {f.views}: spread {f.spread * 1000:.1f} mm, "
                    f"{math.degrees(f.angle_spread):.0f} deg, q={f.quality:.2f}"
                    if f
                    else ""
                )
                + ("; confident" if sure else ""),
            )
        )
        approaching = bool(s.steps) and s.steps[0].kind == "approach"
        # the final approach keeps to its grasp: another one fused now is not followed
        other = (
            approaching and f is not None and s.sure is not None and not same_grasp(f, s.sure[0])
        )
        if sure and not other:
            s.sure = (f, s.target_xy)
        if sure and not s.committed:
            s.committed = True
            s.log.append((t, f"commit after {s.views_done} views at {height:.2f} m"))

    def _descend(self, s: SkillState, t: float, el: float, q_meas, obs: Observation) -> None:
        """One control period of the descent (module docstring)."""
        d = self.scenario.grasp.descent
        s.recent_q = (*s.recent_q[-9:], (t, np.array(q_meas[:7], float)))
        if s.view_asked is not None and obs.id == s.request.id:
            q_view = next((q for tq, q in s.recent_q if abs(tq - obs.time) < 1e-6), q_meas[:7])
            s.view_asked = None
            s.view_done_t = t
            self._see(s, t, obs, self.kin.camera_pose(q_view))
            if not s.committed and s.fused is not None:
                s.explored += 1
            if s.lost >= LOST_VIEWS:
                why = f"target lost: the {s.target_cls} (track {s.track}) left the view"
                return self._fail_descent(s, t, why, stepped=False)
        if s.view_asked is None and t - s.view_done_t >= d.view_period - 1e-9:
            self._ask_view(s, t)
        p_set, v_set, yaw, _ = s.servo
        ox, oy = (0.0, 0.0)
        if not s.committed:
            ox, oy = explore_offset(s.target_xy, s.others, s.explored, d.explore_shift)
        cx, cy = s.target_xy
        X_goal = RigidTransform(down(yaw), [cx + ox, cy + oy, s.target_top + d.preset_height])
        goal = self.kin.tcp_for_camera(X_goal).translation()
        speed = d.commit_speed if s.committed else d.explore_speed
        v_new = approach_velocity(p_set, goal, v_set, speed, d.accel, self.dt, d.commit_speed)
        p_new = p_set + v_new * self.dt
        s.servo = (p_new, v_new, yaw, 0.0)
        X_des = RigidTransform(down(yaw), p_new)
        V = pose_error(self.kin.tcp_pose(s.q), X_des) / self.dt
        v, _ = self.kin.step(s.q, s.v, V)
        if not np.all(np.isfinite(v)):
            v = self.kin.brake(s.v)
        low = abs(p_new[2] - goal[2]) < 0.003
        if low and s.bottom_t is None:
            s.bottom_t = t
        # stopping where the arm stands takes the joints from last period's velocity (the
        # one the command stream carries: ``s.v``) to rest in one period; that velocity must
        # be within one period's acceleration. Near the goal the TCP hardly moves, but the
        # joint-centring null space can still turn joints (a settle from |v| <= a dt while
        # |s.v| was larger commanded joint 2 at -8.1 rad/s^2, over Franka's 7.5)
        settled = (
            low
            and float(np.linalg.norm(goal - p_new)) < 0.003
            and float(np.linalg.norm(v_new)) < 0.02
            and bool(np.all(np.abs(s.v) <= self.kin.amax * self.dt))
        )
        if settled and s.sure is not None:
            s.steps, s.step_t0, s.servo = s.steps[1:], None, None
            # stop where the arm stands, without this period's step (as a move arrives,
            # `_track`): the stream sees it come to rest within the limits
            s.v = np.zeros(7)
            f, then = s.sure  # moved with the target since that view
            return self._grasp(s, t, carried(f.grasp, then, (cx, cy)))
        s.q, s.v = s.q + v * self.dt, v
        # committed: no hover limit (it is settling over the committed grasp)
        hovered = s.bottom_t is not None and t - s.bottom_t > d.hover and not s.committed
        if hovered or el > DESCENT_TIMEOUT:
            f = s.fused
            why = f"no confident grasp on the {s.target_cls} at the lowest point" + (
                f" (spread {f.spread * 1000:.0f} mm, {math.degrees(f.angle_spread):.0f} deg, "
                f"q={f.quality:.2f} over {f.views} views)"
                if f
                else " (no grasp on it)"
            )
            return self._fail_descent(s, t, why)

    def _fail_descent(
        self,
        s: SkillState,
        t: float,
        why: str,
        cause: str = "object_not_found",
        stepped: bool = True,
    ) -> None:
        """End the descent (or the closed approach) as a failed attempt: brake to rest, then
        `_retry`. ``stepped``: this period's target is already set; else (a view's
        verdict) the arm brakes this period already: a target left standing for one period
        stops the stream's velocity at once (an approach losing its target with the wrist
        turning at 1.1 rad/s commanded joint 7 at 114 rad/s^2)."""
        if not stepped:
            s.v = self.kin.brake(s.v)
            s.q = s.q + s.v * self.dt
        s.steps, s.step_t0, s.servo = s.steps[1:], None, None
        self._retry(s, t, why, cause)
        if s.steps:
            s.steps = (Step("brake"), *s.steps)

    def _ask_view(self, s: SkillState, t: float) -> None:
        """Ask perception for a view while moving; the pose it gets is the camera's at its
        next update (rendered then), from the commanded motion."""
        period = self.scenario.control.perception_period
        ahead = (math.floor(t / period + 1e-6) + 1) * period - t
        X_WC = self.kin.camera_pose(s.q + s.v * max(ahead - self.dt, 0.0))
        s.request = ViewRequest(s.next_view, s.side, s.target_cls, s.track, X_WC)
        s.next_view += 1
        s.view_asked = t

    def _grasp(self, s: SkillState, t: float, g: GraspCandidate) -> None:
        """Execute grasp ``g`` (the fused one): approach (closed loop or open, ``descent.
        approach``), close, lift, look."""
        z = max(g.z - GRASP_DEPTH, MIN_GRASP_Z)
        yaw = hand_yaw_for_closing(g.yaw, toward=self.kin.wrist_centred_yaw(s.q))
        assert s.target_xy is not None  # the view the grasp was fused in saw it
        self._hold(s, g, z, yaw, s.target_xy)
        s.grasp_attempts += 1
        s.picks_tried += 1
        k = s.picks_tried
        s.injected = k <= len(self._chance) and self._chance[k - 1]
        s.log.append(
            (
                t,
                f"grasp at ({g.x:.3f}, {g.y:.3f}, {z:.3f}) yaw {math.degrees(yaw):.0f} "
                f"deg, q={g.quality:.2f} (view at {g.view_height:.2f} m)"
                + ("" if g.seated else ", not seated")
                + ("" if g.clear else ", not clear of other objects")
                + (" [drawn to fail: the hand stays open]" if s.injected else ""),
            )
        )
        if self.scenario.grasp.descent.approach == "closed":
            s.steps = (Step("approach", pose=(g.x, g.y, z, yaw)),)
        else:
            s.steps = self._grasp_steps(g.x, g.y, z, yaw, s.side, close=not s.injected)

    def _hold(
        self,
        s: SkillState,
        g: GraspCandidate,
        z: float,
        yaw: float,
        centre: tuple[float, float],
    ) -> None:
        """Grasp ``g`` is the one executed, with the TCP at height ``z`` and yaw ``yaw`` and
        the target's centre at ``centre``: what `Place` needs of it (that centre and the
        target's footprint in the hand's frame)."""
        s.chosen = g
        s.hold_z = z
        c, w = math.cos(yaw), math.sin(yaw)  # the centre's offset from the TCP, hand frame
        dx, dy = centre[0] - g.x, centre[1] - g.y
        s.hold_offset = (c * dx + w * dy, -w * dx + c * dy)
        # a view may lose a thin part: the held class's length comes from the catalogue
        known = s.target_cls in self.scenario.class_names
        f = self.scenario.object_class(s.target_cls).footprint if known else None
        length = max(f.xmax - f.xmin, f.ymax - f.ymin) if f is not None else 0.0
        s.hold_shape = footprint(s.target_shape, yaw, length=length)

    def _grasp_steps(
        self, x: float, y: float, z: float, yaw: float, side: str, close: bool = True
    ) -> tuple:
        """Open, approach from 12 cm above, then `_close_steps` (``close=False``: an attempt
        drawn to fail, the hand stays open)."""
        return (
            Step("grip", width=OPEN),
            self._move((x, y, z + 0.12, yaw)),
            self._move((x, y, z, yaw), APPROACH_SPEED),
            *self._close_steps(x, y, yaw, side, close),
        )

    def _close_steps(self, x: float, y: float, yaw: float, side: str, close: bool) -> tuple:
        """At the grasp: close (or, drawn to fail, stay open), check the fingers, lift
        straight up, look again."""
        return (
            Step("grip", width=CLOSED if close else OPEN),
            Step("check_fingers"),
            self._move((x, y, LIFT_Z, yaw)),
            *self._look(side),
            Step("view", handler="lifted"),
        )

    def _approach(self, s: SkillState, t: float, el: float, q_meas, obs: Observation) -> None:
        """One control period of the closed final approach (Zhou et al. §IV-B: the grasp from
        the observations along the trajectory; module docstring, `tamp.sim.lots.descent`):
        views every ``view_period`` while the camera sees the target; the goal (the step's
        pose) is the latest confident grasp carried with the target's centre as it is now
        (`_target_now`); the TCP is servoed over it and turned to its yaw, then goes
        straight down, below the gate (`BLIND_DEPTH`) without views; at the grasp,
        `_close_steps`."""
        d = self.scenario.grasp.descent
        step = s.steps[0]
        assert s.servo is not None and s.sure is not None  # entered after a confident view
        s.recent_q = (*s.recent_q[-9:], (t, np.array(q_meas[:7], float)))
        p_set, v_set, yaw, w = s.servo
        # the TCP height at which the camera is `BLIND_DEPTH` above the target's top
        gate = s.target_top + BLIND_DEPTH - self._camera_lift
        blind = p_set[2] < gate - GATE_TOLERANCE
        if s.view_asked is not None and obs.id == s.request.id:
            s.view_asked = None
            s.view_done_t = t
            if not blind:  # one asked at the gate and rendered below it shows a cut target
                q_view = next((q for tq, q in s.recent_q if abs(tq - obs.time) < 1e-6), q_meas[:7])
                X_WC = self.kin.camera_pose(q_view)
                if obs.target is None or self._wholly_in_view(
                    s, self._target_now(s, obs.time), X_WC
                ):
                    self._see(s, t, obs, X_WC)
                else:
                    s.lost = 0
                    s.log.append(
                        (t, f"approach view: part of the {s.target_cls} out of the image: not read")
                    )
                if s.lost >= LOST_VIEWS:
                    why = (
                        f"target lost: the {s.target_cls} (track {s.track}) left the view "
                        "during the final approach"
                    )
                    return self._fail_descent(s, t, why, stepped=False)
                gate = s.target_top + BLIND_DEPTH - self._camera_lift
        if not blind and s.view_asked is None and t - s.view_done_t >= d.view_period - 1e-9:
            self._ask_view(s, t)
        # the latest confident grasp carried with the target to where it is now; its yaw as
        # the same closing line nearest the goal's (never a flip of the hand)
        f, then = s.sure
        centre = self._target_now(s, t)
        g = carried(f.grasp, then, centre)
        z = max(g.z - GRASP_DEPTH, MIN_GRASP_Z)
        goal_yaw = hand_yaw_for_closing(g.yaw, toward=step.pose[3])
        s.steps = (replace(step, pose=(g.x, g.y, z, goal_yaw)), *s.steps[1:])
        goal = np.array([g.x, g.y, z])
        turn = math.remainder(goal_yaw - yaw, 2 * math.pi)  # how far off, either way round
        seen = s.lost == 0  # never into the blind part on a view that missed the target
        aim = approach_aim(p_set, goal, turn, gate, APPROACH_REACH, APPROACH_TURN, seen)
        lateral = self.scenario.control.speed
        v_new = approach_velocity(p_set, aim, v_set, APPROACH_SPEED, d.accel, self.dt, lateral)
        centred = self.kin.wrist_centred_yaw(s.q)
        w_new = turn_rate(wrist_turn(yaw, goal_yaw, centred), w, ANGULAR_SPEED, TURN_ACCEL, self.dt)
        p_new, yaw_new = p_set + v_new * self.dt, yaw + w_new * self.dt
        s.servo = (p_new, v_new, yaw_new, w_new)
        if not blind and p_new[2] < gate - GATE_TOLERANCE:
            s.view_asked = None  # an answer rendered below the gate is not read
            vx, vy = seen_velocity(s.seen_at)
            s.log.append(
                (
                    t,
                    f"approach: last view, the camera {BLIND_DEPTH:.2f} m over the "
                    f"{s.target_cls}'s top (nearer, the gripper hides it); the grasp at "
                    f"({g.x:.3f}, {g.y:.3f}, {z:.3f}) yaw {math.degrees(goal_yaw):.0f} deg "
                    f"goes on at ({vx * 1000:.0f}, {vy * 1000:.0f}) mm/s",
                )
            )
        X_des = RigidTransform(down(yaw_new), p_new)
        V = pose_error(self.kin.tcp_pose(s.q), X_des) / self.dt
        v, _ = self.kin.step(s.q, s.v, V)
        if not np.all(np.isfinite(v)):
            v = self.kin.brake(s.v)
        # arrived: at the grasp, come down to rest (sideways it may still follow a sliding
        # target), the arm there too (not only the set point: a joint at its limit holds
        # it back), stopping where it stands within the acceleration limits (as `_descend`
        # settles)
        err = pose_error(self.kin.tcp_pose(s.q), RigidTransform(down(goal_yaw), goal))
        arrived = (
            float(np.linalg.norm(goal - p_new)) < 0.002
            and float(np.linalg.norm(err[3:])) < 0.003
            and float(np.linalg.norm(err[:3])) < 0.02
            and abs(math.remainder(goal_yaw - yaw_new, 2 * math.pi)) < 0.01
            and abs(float(v_new[2])) < 0.01
            and abs(w_new) < 0.05
            and bool(np.all(np.abs(s.v) <= self.kin.amax * self.dt))
        )
        if arrived:
            s.steps, s.step_t0, s.servo = s.steps[1:], None, None
            s.v = np.zeros(7)
            self._hold(s, g, z, goal_yaw, centre)
            s.log.append((t, f"at the grasp ({g.x:.3f}, {g.y:.3f}, {z:.3f})"))
            s.steps = self._close_steps(g.x, g.y, goal_yaw, s.side, close=not s.injected)
            return
        s.q, s.v = s.q + v * self.dt, v
        if el > APPROACH_TIMEOUT:
            why = f"the final approach did not reach the grasp on the {s.target_cls} in time"
            return self._fail_descent(s, t, why, "unreachable")

    def _wholly_in_view(
        self, s: SkillState, centre: tuple[float, float], X_WC: RigidTransform
    ) -> bool:
        """Whether the target's outline (`SkillState.target_shape` round ``centre``, at its
        top) lies inside the image of the camera at ``X_WC`` (`descent.wholly_in_view`)."""
        cx, cy = centre
        pts = s.target_shape
        W = np.vstack((pts[:, 0] + cx, pts[:, 1] + cy, np.full(len(pts), s.target_top)))
        cam = self.scenario.camera
        return wholly_in_view(
            X_WC.inverse().multiply(W), self.planner.intrinsics, cam.width, cam.height
        )

    @staticmethod
    def _target_now(s: SkillState, t: float) -> tuple[float, float]:
        """The target's centre at time ``t``: the latest view's, carried on at the velocity
        the attempt's recent views show (`descent.predicted_centre`; still: where it was)."""
        if not s.seen_at:
            assert s.target_xy is not None  # a view of the attempt found it
            return s.target_xy
        return predicted_centre(s.seen_at, t)

    def _on_lifted(self, s: SkillState, t: float, obs: Observation, q_meas) -> None:
        if s.injected:
            s.injected = False
            return self._retry(
                s,
                t,
                "the hand did not close (a drawn failure: perturbation.skills)",
                "injected_failure",
            )
        if q_meas[7] + q_meas[8] < MIN_HOLD_WIDTH:
            return self._retry(s, t, "slipped: the fingers closed after the lift", "grasp_slipped")
        if any(d.track == s.track for d in obs.detections):  # its points are still there
            return self._retry(
                s, t, f"not lifted: the {s.target_cls} is still on the table", "grasp_slipped"
            )
        s.held = s.target_cls
        s.grasp_successes += 1
        self._finish(s, t, Status.SUCCESS, f"holding {s.held}")

    def _retry(self, s: SkillState, t: float, why: str, cause: str) -> None:
        """A failed grasp attempt (``cause``: `tamp.sim.core.outcome.CAUSES`): try again from
        the look pose, or fail the skill with that cause after the last attempt."""
        s.log.append((t, f"grasp attempt {s.attempt} failed: {why}"))
        if s.chosen is not None and cause in ("grasp_missed", "grasp_slipped"):
            s.missed = (*s.missed, (s.chosen.x, s.chosen.y, s.chosen.yaw))
        if s.attempt >= self.scenario.grasp.attempts or s.command.name == "PickAt":
            return self._finish(s, t, Status.FAILURE, f"{why} ({s.attempt} attempts)", cause)
        s.attempt += 1
        x, y, z, _ = self.kin_pose(s)
        self._reset_descent(s)
        s.chosen = None
        s.steps = (
            Step("grip", width=OPEN),
            self._move((x, y, max(z, LIFT_Z), 0.0)),
            *self._look(s.side),
            Step("view", handler="target"),
        )

    def kin_pose(self, s: SkillState) -> tuple[float, float, float, float]:
        p = self.kin.tcp_pose(s.q).translation()
        return (float(p[0]), float(p[1]), float(p[2]), 0.0)

    def _on_place(self, s: SkillState, t: float, obs: Observation, q_meas) -> None:
        X_WC = self.kin.camera_pose(q_meas[:7])
        workspace = self.scenario.workspaces[s.side]
        on = below(self.scenario.stack, s.held) if s.side == STACK_SIDE else None
        if on is not None:
            # a level of the declared stack: on the top of the object of the class below,
            # where this view shows it (or perception remembers it, hidden now): its centre
            # and its top from the depth image, never the plant's pose
            seen = [
                (d.cls, backproject(d.u, d.v, d.depth, self.planner.intrinsics, X_WC))
                for d in obs.detections
            ] + [(m.cls, m.position) for m in obs.occluded]
            top = support(on, seen)
            if top is None:
                return self._finish(
                    s,
                    t,
                    Status.FAILURE,
                    f"no {on} seen in W^{s.side} to stack the {s.held} on",
                    "object_not_found",
                )
            cx, cy, floor = top
            gap = STACK_GAP
            yaw = self.kin.tcp_yaw(s.q)  # the look's yaw: the held object's offset turns with it
            where = f" on the {on} (its top at {floor:.3f} m)"
        else:
            # the object's footprint goes where views saw the floor bare and nothing else
            # lies, inside the edges (`tamp.sim.lots.room`)
            s.room = self._room_seen(s.side, s.room, obs, X_WC)
            # at the hand's present yaw: turning the hand with the object held (in 45 degree
            # steps, to fit a long one beside another) lost objects in two narratives
            yaws = [self.kin.tcp_yaw(s.q)]
            walls = workspace.tray  # keep off a tray's walls first (`room.WALL_MARGIN`)
            best = place(s.room, s.hold_shape, yaws, walls=walls)
            # what the floor no view saw could give, asked only when the seen floor is short
            hoped = (
                place(s.room, s.hold_shape, yaws, unseen_bare=True, walls=walls)
                if best.clearance < PLACE_CLEARANCE
                else best
            )
            if (
                best.clearance < PLACE_CLEARANCE
                and s.place_views < PLACE_VIEWS
                and obs.hidden is not None
                and hoped.clearance > best.clearance + PLACE_GAIN  # the unseen may hold room
            ):
                at = next_look(s.room, obs.hidden, X_WC, self.planner.intrinsics)
                if at is not None:
                    s.place_views += 1
                    s.log.append(
                        (
                            t,
                            f"no room seen for the {s.held} ({best.clearance:.3f} m clear): "
                            f"look again from ({at[0]:.3f}, {at[1]:.3f})",
                        )
                    )
                    now = self.kin.tcp_yaw(s.q)
                    s.steps = (
                        self._move(self.look_pose(s.side, at=at, yaw=now)),
                        Step("settle"),
                        Step("view", handler="place"),
                    )
                    return
            where = ""
            if best.clearance < PLACE_CLEARANCE and hoped.clearance > best.clearance:
                # the views saw too little bare floor for it (a held saw hides 88 % of the
                # image): the floor no view saw is taken as bare, what was seen is avoided
                best = hoped
                where = ", partly on floor no view saw"
            cx, cy, yaw = best.x, best.y, best.yaw
            floor, gap = workspace.floor, RELEASE_GAP
            where += "".join(f", away from the hidden {m.cls}" for m in obs.occluded)
            if math.isfinite(best.clearance):
                where += f", {best.clearance:.3f} m clear"
        c, w = math.cos(yaw), math.sin(yaw)
        hx, hy = s.hold_offset
        x, y = cx - (c * hx - w * hy), cy - (w * hx + c * hy)
        z = floor + s.hold_z + gap
        # lift clear: the camera (5.5 cm above the TCP) farther than perception's hand depth
        # from the top of what it put down, which may stand on a stack
        lift = max(LIFT_Z, z + PLACE_LIFT)
        s.log.append((t, f"place the {s.held}'s centre at ({cx:.3f}, {cy:.3f}){where}"))
        s.target_cls, s.track = None, None  # no grasp target: the views below need no colour
        s.steps = (
            self._move((x, y, z + 0.12, yaw)),
            Step("check_held"),
            self._move((x, y, z, yaw), APPROACH_SPEED),
            Step("release", duration=RELEASE_TIME) if on else Step("grip", width=OPEN),
            self._move((x, y, lift, yaw)),
            # one view from over the object just put down: perception remembers where it
            # lies (a later view with an object in the gripper may have it hidden)
            Step("settle"),
            Step("view", handler="seen"),
            Step("finish", detail=f"placed {s.held} in W^{s.side}", handler="released"),
        )


def top_view_points(crop, intrinsics, X_WC: RigidTransform) -> np.ndarray:
    """The target's mask in the crop back-projected through its depth (N x 2, world x, y):
    its footprint as the camera sees it from above."""
    vs, us = np.nonzero(crop.mask)
    z = crop.depth[vs, us] if len(us) else np.zeros(0)
    ok = z > 0
    if not ok.any():
        return np.zeros((0, 2))
    u0, v0 = crop.origin
    pts = backproject(us[ok] + u0, vs[ok] + v0, z[ok], intrinsics, X_WC)
    return np.asarray(pts[:2]).T
