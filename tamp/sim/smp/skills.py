"""YouBotSkillController: runs MoveTo / Pick / Place on the youBot-like mobile manipulator
(SMP-MRO §V-A3).

A LeafSystem with a periodic unrestricted update (the controller period, e.g. 20 ms). Its
abstract state holds the command it works on, the phase of the skill, the reference
`Segment` the joints track, and the weld it asks for. Outputs, computed from that state:
- ``desired_state``: [q_d, v_d] of the robot's PD-controlled actuators (the plant's
  desired-state input), the reference segment sampled once per period (discrete state);
- ``status``: `SkillStatus` (RUNNING, then SUCCESS or FAILURE) for the current command id;
- ``grasp``: `GraspRequest`, the weld the gripper asks for.

Each phase is planned when it begins, from the measured plant state (robot joints and body
poses), so nothing assumes the previous phase ended exactly where it was meant to. Skills:
- MoveTo(target): fold the arm if the hand is free, drive to a stand-off pose 0.40 m from
  the target facing it (grid A* path around the objects, trapezoidal profile).
- Pick(o): fold, drive to o's stand-off pose (skipped when already there), IK pre-grasp
  above o, descend, close the fingers, ask for the weld, lift 6-10 cm, and check on the plant
  that o rose with the gripper (a lost grasp is a FAILURE; scripted failures drop the weld).
- Place(o, l): refuse if l is occupied, drive to l's stand-off pose, IK above l's centre,
  lower until o is 4 mm above the floor, release the weld, open, retreat, fold, and check
  on the plant that o rests inside l.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.sim.core.messages import GraspRequest, SkillCommand, SkillStatus
from tamp.sim.smp.ik import ArmIK, grasp_rotation
from tamp.sim.smp.motion import (
    STANDOFF,
    BasePlanner,
    Disc,
    Segment,
    base_segment,
    joint_segment,
    standoff_pose,
    wrap,
)
from tamp.sim.smp.placement import Body, why_not_in
from tamp.sim.smp.robot import HOME_ARM, ROBOT, ObjectKind
from tamp.sim.smp.scenario import BaseLimits
from tamp.world.events import Fail
from tamp.world.geometry import Area
from tamp.world.interface import Status

N = len(ROBOT.joints)  # 10: base x, y, yaw, arm 1..5, fingers left/right
ARM = slice(3, 8)
FING = slice(8, 10)
ARM_SPEED = 1.2  # rad/s peak joint speed of arm moves
SETTLE_TIMEOUT = 1.5  # s after a segment ends before a phase gives up waiting to settle
# Heights above the grasp / place pose, tried in order: the youBot arm with the palm down
# reaches only ~0.3 m above the floor at the stand-off distance, and the base stops within
# a couple of centimetres of its stand-off pose, so lower fall-backs keep IK solvable.
PREGRASP_HEIGHTS = (0.08, 0.06, 0.04)
LIFT_HEIGHTS = (0.10, 0.08, 0.06)
PREPLACE_HEIGHTS = (0.08, 0.06, 0.04)
PLACE_CLEARANCE = 0.004
#: friction grasps let go a little higher: the object can slip down in the fingers while
#: lifted, and lowering it onto the floor pushes it askew in the hand (measured)
FRICTION_PLACE_CLEARANCE = 0.008
#: finger reference of a friction grasp (m, below the joints' lower limit 0): the fingers'
#: PD force is kp x (opening - SQUEEZE), ~21 N each on a bottle (weight 2.9 N)
SQUEEZE = -0.02

PHASES = {
    "MoveTo": ("fold", "drive"),
    "Pick": (
        "fold",
        "drive",
        "pregrasp",
        "descend",
        "close",
        "weld",
        "lift",
        "check_pick",
    ),
    "Place": (
        "drive",
        "preplace",
        "lower",
        "release",
        "open",
        "retreat",
        "fold",
        "check_place",
    ),
}


@dataclass
class ControllerState:
    """Everything the controller remembers between updates (kept small: deep-copied)."""

    cmd: SkillCommand = field(default_factory=SkillCommand)
    status: SkillStatus = field(default_factory=SkillStatus)
    phases: tuple[str, ...] = ()
    phase: str = ""
    segment: Segment | None = None
    grasp: GraspRequest = field(default_factory=GraspRequest)
    attempts: dict = field(default_factory=dict)
    memo: dict = field(default_factory=dict)  # per-skill values: IK solutions, start heights
    found: dict = field(default_factory=dict)  # areas the tree found at run time, by name
    #: every skill failure so far: (sim time, action, cause, detail), for the run's cause
    failures: tuple = ()

    def __deepcopy__(self, memo: dict) -> ControllerState:
        # Drake deep-copies abstract state on every update. Segments, arrays and messages
        # are never changed in place (updates build new ones), so sharing them is a copy.
        return ControllerState(
            self.cmd,
            self.status,
            self.phases,
            self.phase,
            self.segment,
            self.grasp,
            dict(self.attempts),
            dict(self.memo),
            dict(self.found),
            self.failures,
        )


class SkillFailure(Exception):
    """A phase cannot be carried out; the skill reports FAILURE with this reason, and the
    run records ``cause`` (one of `tamp.sim.core.outcome.CAUSES`)."""

    def __init__(self, why: str, cause: str = "skill_failed"):
        super().__init__(why)
        self.cause = cause


class YouBotSkillController(LeafSystem):
    """MoveTo / Pick / Place skills driving the plant's PD-controlled actuators."""

    def __init__(
        self,
        *,
        period: float,
        bodies: dict[str, int],
        kinds: dict[str, ObjectKind],
        palm_body: int,
        areas: dict[str, Area],
        actuator_order: list[int],
        q_start: np.ndarray,
        base_limits: BaseLimits,
        workspace: tuple[float, float, float, float],
        failures: tuple[Fail, ...] = (),
        chance_failures: tuple[tuple[str, tuple[bool, ...]], ...] = (),
        grasp: str = "weld",
        perception: str = "truth",
    ):
        super().__init__()
        self.set_name("skill_controller")
        self._bodies = dict(bodies)
        self._kinds = dict(kinds)
        self._palm = palm_body
        self._areas = dict(areas)
        self._order = list(actuator_order)  # actuator k drives robot joint _order[k]
        self._limits = base_limits
        self._workspace = workspace
        self._failures = tuple(failures)
        self._chance = dict(chance_failures)  # action -> does attempt k+1 fail (drawn)
        self._friction = grasp == "friction"  # fingers hold by friction, no weld
        #: body poses of objects are the plant's (truth) or the camera's estimates (camera)
        self._truth = perception == "truth"
        self._ik = ArmIK()
        self._planner = BasePlanner(workspace)

        self.command_port = self.DeclareAbstractInputPort(
            "command", AbstractValue.Make(SkillCommand())
        )
        self.robot_state_port = self.DeclareVectorInputPort("robot_state", 2 * N)
        self.body_poses_port = self.DeclareAbstractInputPort(
            "body_poses", AbstractValue.Make([RigidTransform()])
        )
        init = ControllerState(segment=Segment(0.0, 0.0, q_start.copy(), q_start.copy()))
        self._state = self.DeclareAbstractState(AbstractValue.Make(init))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        # The desired state is discrete state written by the update (the reference sampled at
        # the middle of each control period) and output by Drake itself: no Python call per
        # plant step. The other outputs depend on the abstract state only (no feedthrough).
        self._period = period
        x0 = np.concatenate([q_start[self._order], np.zeros(N)])
        self._xd = self.DeclareDiscreteState(x0)
        self.desired_state_port = self.DeclareStateOutputPort("desired_state", self._xd)
        only_state = {self.abstract_state_ticket(self._state)}
        self.status_port = self.DeclareAbstractOutputPort(
            "status",
            lambda: AbstractValue.Make(SkillStatus()),
            self._calc_status,
            prerequisites_of_calc=only_state,
        )
        self.grasp_port = self.DeclareAbstractOutputPort(
            "grasp",
            lambda: AbstractValue.Make(GraspRequest()),
            self._calc_grasp,
            prerequisites_of_calc=only_state,
        )

    # -- outputs ----------------------------------------------------------------------------
    def _st(self, context) -> ControllerState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_status(self, context, output) -> None:
        output.set_value(self._st(context).status)

    def _calc_grasp(self, context, output) -> None:
        output.set_value(self._st(context).grasp)

    # -- update -----------------------------------------------------------------------------
    def _update(self, context, state) -> EventStatus:
        t = context.get_time()
        st: ControllerState = copy.deepcopy(self._st(context))
        cmd: SkillCommand = self.command_port.Eval(context)
        x = self.robot_state_port.Eval(context)
        q = np.asarray(x[:N])
        poses = self.body_poses_port.Eval(context)
        running = st.status.status is Status.RUNNING
        if cmd.id > st.cmd.id and not cmd.cancel:
            self._begin(st, cmd, t, q, poses)
        elif cmd.cancel and cmd.id == st.cmd.id and running:
            here = self._here(st, q)
            st.segment = Segment(t, 0.0, here, here.copy())  # stop where it is
            st.phases, st.phase = (), ""
            st.status = SkillStatus(cmd.id, Status.FAILURE, "cancelled")
            st.cmd = cmd
        elif running:
            self._step(st, t, q, poses)
        state.get_mutable_abstract_state(self._state).set_value(st)
        qd, vd = st.segment.sample(t + 0.5 * self._period)
        state.get_mutable_discrete_state(self._xd).set_value(
            np.concatenate([qd[self._order], vd[self._order]])
        )
        return EventStatus.Succeeded()

    def _begin(self, st: ControllerState, cmd: SkillCommand, t, q, poses) -> None:
        st.cmd = cmd
        for area in cmd.areas:  # an l_free the tree found at run time: a fixed place, kept
            st.found.setdefault(area.name, area)  # in the context (state), never on self
        st.memo = {}
        key = (cmd.name, tuple(cmd.args))
        st.attempts[key] = st.attempts.get(key, 0) + 1
        if cmd.name not in PHASES:
            st.status = SkillStatus(cmd.id, Status.FAILURE, f"unknown skill {cmd.name}")
            return
        st.status = SkillStatus(cmd.id, Status.RUNNING)
        st.phases = PHASES[cmd.name]
        st.phase = ""
        try:
            self._check_start(st, q, poses)
            self._next_phase(st, t, q, poses)
        except SkillFailure as exc:
            self._fail(st, t, q, str(exc), exc.cause)

    def _fail(self, st: ControllerState, t, q, why: str, cause: str) -> None:
        here = self._here(st, q)
        st.segment = Segment(t, 0.0, here, here.copy())
        st.status = SkillStatus(st.cmd.id, Status.FAILURE, why, cause)
        st.phases, st.phase = (), ""
        st.failures = st.failures + ((t, str(st.cmd), cause, why),)

    def _here(self, st: ControllerState, q) -> np.ndarray:
        """The measured joints with the fingers' reference kept: stopping never loosens a
        friction grasp (the fingers stand where the object stops them, short of their
        reference, and the difference is what squeezes it)."""
        here = q.copy()
        here[FING] = st.segment.q1[FING]
        return here

    def _move(self, st: ControllerState, t, q, q1, speed: float, min_time: float) -> Segment:
        """A smooth move from the measured joints to ``q1``, the fingers' reference going on
        from where it was (`_here`): started from the fingers' measured opening, a friction
        grasp's reference would jump back to where the object stops them and the squeeze
        would vanish at the start of every move (the held object slipped down and turned in
        the fingers as the arm left for the pre-place pose: Case 3, O_a)."""
        return joint_segment(t, self._here(st, q), q1, speed, min_time)

    def failures(self, context) -> tuple[tuple[float, str, str, str], ...]:
        """Every skill failure of the run in ``context``: (time, action, cause, detail)."""
        return self._st(context).failures

    def _step(self, st: ControllerState, t, q, poses) -> None:
        seg = st.segment
        if t < seg.t_end - 1e-9:
            return
        err = np.abs(seg.q1 - q)
        if self._friction and seg.q1[8] == SQUEEZE:
            err[FING] = 0.0  # squeezing: the object stops the fingers short of their target
        settled = err[0:2].max() < 0.02 and err[2] < 0.03 and err[3:].max() < 0.03
        if not settled and t < seg.t_end + SETTLE_TIMEOUT:
            return
        try:
            self._next_phase(st, t, q, poses)
        except SkillFailure as exc:
            self._fail(st, t, q, str(exc), exc.cause)

    def _next_phase(self, st: ControllerState, t, q, poses) -> None:
        while st.phases:
            st.phase, st.phases = st.phases[0], st.phases[1:]
            seg = getattr(self, f"_phase_{st.phase}")(st, t, q, poses)
            if seg is not None:
                st.segment = seg
                return
        st.status = SkillStatus(st.cmd.id, Status.SUCCESS)
        st.phase = ""

    # -- measurements -----------------------------------------------------------------------
    def _X(self, poses, uid: str) -> RigidTransform:
        return poses[self._bodies[uid]]

    def _visible(self, uid: str, X: RigidTransform) -> bool:
        x, y, _ = X.translation()
        xmin, xmax, ymin, ymax = self._workspace
        return xmin <= x <= xmax and ymin <= y <= ymax

    def _obstacles(self, st: ControllerState, poses, exclude: set[str]) -> list[Disc]:
        out = []
        for uid in self._bodies:
            if uid in exclude or uid == st.grasp.obj:
                continue
            X = self._X(poses, uid)
            if self._visible(uid, X):
                p = X.translation()
                out.append(Disc(p[0], p[1], self._kinds[uid].radius))
        return out

    def areas(self, context) -> dict[str, Area]:
        """The areas known in ``context``: the demonstration's and those the tree found at
        run time (`ControllerState.found`, per context: one diagram can run twice)."""
        return {**self._areas, **self._st(context).found}

    def _area(self, st: ControllerState, name: str) -> Area | None:
        return self._areas.get(name) or st.found.get(name)

    def _target_xy(self, st: ControllerState, ref: str, poses) -> tuple[float, float]:
        if ref in self._bodies:
            p = self._X(poses, ref).translation()
            return (p[0], p[1])
        area = self._area(st, ref)
        if area is not None:
            return (area.pos.x, area.pos.y)
        raise SkillFailure(f"unknown object or area {ref!r}", "object_not_found")

    def _check_start(self, st: ControllerState, q, poses) -> None:
        name, args = st.cmd.name, st.cmd.args
        if name == "MoveTo":
            if len(args) != 1:
                raise SkillFailure("MoveTo takes one target")
            self._target_xy(st, args[0], poses)
        elif name == "Pick":
            if len(args) != 1 or args[0] not in self._bodies:
                raise SkillFailure(f"cannot pick {args}")
            if st.grasp.obj is not None or st.grasp.holding is not None:
                raise SkillFailure(f"hand holds {st.grasp.obj or st.grasp.holding}")
            if not self._visible(args[0], self._X(poses, args[0])):
                raise SkillFailure(f"{args[0]} is not in the workspace", "object_not_found")
        elif name == "Place":
            if len(args) != 2 or self._area(st, args[1]) is None:
                raise SkillFailure(f"cannot place {args}")
            if st.grasp.holding != args[0] or st.grasp.obj != args[0]:
                raise SkillFailure(f"{args[0]} is not held", "grasp_slipped")
            if self._friction and not self._in_hand(args[0], q):
                st.grasp = GraspRequest()  # the hand is empty: the tree sees it and re-picks
                raise SkillFailure(
                    f"{args[0]} slipped out of the fingers while carried", "grasp_slipped"
                )
            self._check_free(st, poses)

    def _check_free(self, st: ControllerState, poses) -> None:
        """Fail (``area_occupied``) when an object other than the held one is believed in
        the area a Place is for: at the start, and again before lowering (a person may put
        one there while the robot drives and reaches: Case 3's O_a)."""
        held, name = st.cmd.args
        area = self._area(st, name)
        for uid in self._bodies:
            if uid == held:
                continue
            p = self._X(poses, uid).translation()
            if math.hypot(p[0] - area.pos.x, p[1] - area.pos.y) <= area.radius:
                raise SkillFailure(f"area {name} is occupied by {uid}", "area_occupied")

    # -- phases (each returns the segment to track, or None when there is nothing to do) -----
    def _phase_fold(self, st, t, q, poses):
        if st.grasp.obj is not None:
            return None
        q1 = q.copy()
        q1[ARM] = HOME_ARM
        q1[FING] = ROBOT.finger_open
        if np.abs(q1 - q)[3:].max() < 0.02:
            return None
        return self._move(st, t, q, q1, ARM_SPEED, 0.4)

    def _phase_drive(self, st, t, q, poses):
        ref = st.cmd.args[0] if st.cmd.name != "Place" else st.cmd.args[1]
        target = self._target_xy(st, ref, poses)
        exclude = {ref, st.grasp.obj} if st.grasp.obj else {ref}
        a = self._area(st, ref)
        if a is not None:  # what lies in the target area is what the robot works on
            for uid in self._bodies:
                p = self._X(poses, uid).translation()
                if math.hypot(p[0] - a.pos.x, p[1] - a.pos.y) < a.radius + self._kinds[uid].radius:
                    exclude.add(uid)
        obstacles = self._obstacles(st, poses, exclude)
        dist = math.hypot(target[0] - q[0], target[1] - q[1])
        facing = abs(wrap(math.atan2(target[1] - q[1], target[0] - q[0]) - q[2]))
        if abs(dist - STANDOFF) < 0.03 and facing < 0.06:
            return None
        radius = ROBOT.planning_radius
        goal = standoff_pose(target, (q[0], q[1]), obstacles, self._workspace, radius)
        if goal is None:
            raise SkillFailure(f"no free place to stand near {ref}", "unreachable")
        path = self._planner.plan((q[0], q[1]), goal[:2], obstacles, radius)
        if path is None:
            raise SkillFailure(f"no path to {ref}", "unreachable")
        hold = st.segment.q1.copy()  # the arm and fingers keep their last reference
        hold[0:3] = q[0:3]
        return base_segment(t, hold, goal, path, self._limits)

    def _phase_pregrasp(self, st, t, q, poses):
        uid = st.cmd.args[0]
        X_WO = self._X(poses, uid)
        kind = self._kinds[uid]
        res = self._ik.grasp(q, X_WO, kind)
        if res is None:
            raise SkillFailure(f"{uid} is out of the arm's reach", "unreachable")
        q_g = q.copy()
        q_g[ARM] = res.q_arm
        yaw = RollPitchYaw(X_WO.rotation()).yaw_angle()
        R_WG = RotationMatrix.MakeZRotation(yaw).multiply(grasp_rotation(res.variant).transpose())
        point = X_WO.translation() + [0.0, 0.0, kind.grasp_height]
        pre = self._first(q_g, point, PREGRASP_HEIGHTS, R_WG, res.q_arm)
        lift = self._first(q_g, point, LIFT_HEIGHTS, R_WG, res.q_arm)
        if pre is None or lift is None:
            raise SkillFailure(f"no pre-grasp or lift pose for {uid}", "unreachable")
        st.memo.update(
            grasp=res.q_arm,
            pre=pre[0],
            lift=lift[0],
            lift_height=lift[1],
            variant=res.variant,
            z0=X_WO.translation()[2],
        )
        q1 = q.copy()
        q1[ARM] = pre[0]
        q1[FING] = ROBOT.finger_open
        return self._move(st, t, q, q1, ARM_SPEED, 0.6)

    def _first(self, q, point, heights, R_WG=None, nominal=None):
        """(arm joints, height) for the first height above ``point`` that IK can reach."""
        for h in heights:
            sol = self._ik.solve(q, point + np.array([0.0, 0.0, h]), R_WG=R_WG, nominal_arm=nominal)
            if sol is not None:
                return sol, h
        return None

    def _phase_descend(self, st, t, q, poses):
        q1 = q.copy()
        q1[ARM] = st.memo["grasp"]
        q1[FING] = ROBOT.finger_open
        return self._move(st, t, q, q1, 0.8, 0.6)

    def _phase_close(self, st, t, q, poses):
        # whether this attempt fails by script (``fail``) or by the drawn chance (``skills``)
        st.memo["lost"] = self._scripted_failure(st) or self._chance_failure(st)
        kind = self._kinds[st.cmd.args[0]]
        q1 = q.copy()
        q1[ARM] = st.memo["grasp"]
        if not self._friction:
            q1[FING] = kind.half_width + 0.002  # around the object; the weld holds it
        elif st.memo["lost"]:
            q1[FING] = ROBOT.finger_open  # an injected failure: the hand does not close
        else:
            q1[FING] = SQUEEZE  # the PD force on the fingers holds it by friction
        return self._move(st, t, q, q1, 0.2, 0.3)

    def _phase_weld(self, st, t, q, poses):
        if not st.memo["lost"]:  # friction grasps ask for no weld (the system has none)
            st.grasp = GraspRequest(st.cmd.args[0], st.memo["variant"], st.grasp.holding)
        return Segment(t, 0.1, self._here(st, q), st.segment.q1.copy())

    def _scripted_failure(self, st: ControllerState) -> bool:
        """Whether this attempt is one of the first ``times`` attempts a `Fail` names."""
        name = st.cmd.name
        for f in self._failures:
            if f.matches(name, tuple(st.cmd.args)):
                tried = sum(n for (a, args), n in st.attempts.items() if f.matches(a, args))
                if tried <= f.times:
                    return True
        return False

    def _chance_failure(self, st: ControllerState) -> bool:
        """Whether this attempt of the action (all arguments counted) fails by the drawn
        chance of the run's perturbation (`RunConditions.chance_failures`)."""
        draws = self._chance.get(st.cmd.name, ())
        n = sum(k for (a, _), k in st.attempts.items() if a == st.cmd.name)
        return 0 < n <= len(draws) and draws[n - 1]

    def _in_hand(self, uid: str, q) -> bool:
        """The gripper's own sensor (friction grasps): the fingers have closed (they stand
        1 cm short of fully open at least) and stand apart by at least the object's half
        width, so something is between them."""
        gap = float(q[8] + q[9])
        return self._kinds[uid].half_width < gap < 2 * ROBOT.finger_open - 0.01

    def _phase_lift(self, st, t, q, poses):
        q1 = st.segment.q1.copy()
        q1[ARM] = st.memo["lift"]
        return self._move(st, t, q, q1, ARM_SPEED, 0.6)

    def _phase_check_pick(self, st, t, q, poses):
        uid = st.cmd.args[0]
        z = self._X(poses, uid).translation()[2]
        # Did it come up with the hand? Friction grasps ask the gripper (the fingers stand
        # apart); weld grasps look at the object's height on the plant, or, with the camera
        # (which cannot see under the gripper), trust the weld they switched on.
        if self._truth:
            risen = z >= st.memo["z0"] + 0.5 * st.memo["lift_height"]
        else:
            risen = self._friction or not st.memo["lost"]
        held = not self._friction or self._in_hand(uid, q)
        if st.grasp.obj != uid or not risen or not held:
            st.grasp = GraspRequest()
            if st.memo.get("lost"):
                cause = "injected_failure"
            elif not held:
                cause = "grasp_missed"
            else:
                cause = "grasp_slipped"
            raise SkillFailure(f"grasp of {uid} lost (it stayed at z = {z:.3f} m)", cause)
        st.grasp = GraspRequest(st.grasp.obj, st.grasp.variant, holding=uid)
        return None

    def _place_point(self, st, height: float) -> np.ndarray:
        uid, area = st.cmd.args
        a = self._area(st, area).pos
        kind = self._kinds[uid]
        clearance = FRICTION_PLACE_CLEARANCE if self._friction else PLACE_CLEARANCE
        z = kind.half_height + clearance + kind.grasp_height + height
        return np.array([a.x, a.y, z])

    def _phase_preplace(self, st, t, q, poses):
        found = self._first(q, self._place_point(st, 0.0), PREPLACE_HEIGHTS)
        if found is None:
            raise SkillFailure(f"area {st.cmd.args[1]} is out of the arm's reach", "unreachable")
        pre = found[0]
        q_pre = q.copy()
        q_pre[ARM] = pre
        down = self._ik.solve(q_pre, self._place_point(st, 0.0), nominal_arm=pre)
        if down is None:
            raise SkillFailure(
                f"cannot lower {st.cmd.args[0]} into {st.cmd.args[1]}", "unreachable"
            )
        st.memo.update(pre=pre, down=down)
        q1 = st.segment.q1.copy()
        q1[ARM] = pre
        return self._move(st, t, q, q1, ARM_SPEED, 0.6)

    def _phase_lower(self, st, t, q, poses):
        uid = st.cmd.args[0]
        if self._friction and not self._in_hand(uid, q):
            st.grasp = GraspRequest()
            raise SkillFailure(f"{uid} slipped out of the fingers above the area", "grasp_slipped")
        self._check_free(st, poses)
        q1 = st.segment.q1.copy()
        q1[ARM] = st.memo["down"]
        return self._move(st, t, q, q1, 0.8, 0.6)

    def _phase_release(self, st, t, q, poses):
        st.grasp = GraspRequest(holding=st.grasp.holding)
        return Segment(t, 0.1, self._here(st, q), st.segment.q1.copy())

    def _phase_open(self, st, t, q, poses):
        q1 = st.segment.q1.copy()
        q1[FING] = ROBOT.finger_open
        return self._move(st, t, q, q1, 0.2, 0.25)

    def _phase_retreat(self, st, t, q, poses):
        q1 = st.segment.q1.copy()
        q1[ARM] = st.memo["pre"]
        return self._move(st, t, q, q1, ARM_SPEED, 0.5)

    def _phase_check_place(self, st, t, q, poses):
        uid, area = st.cmd.args
        why = why_not_in(self._body(poses, uid), self._area(st, area), self._bodies_now(poses))
        if why is not None:
            st.grasp = GraspRequest()  # the hand let go: it holds nothing, whatever happened
            raise SkillFailure(why, "placement_off")
        st.grasp = GraspRequest()
        return None

    def _body(self, poses, uid: str) -> Body:
        x, y, z = self._X(poses, uid).translation()
        return Body(uid, float(x), float(y), float(z), self._kinds[uid])

    def _bodies_now(self, poses) -> list[Body]:
        return [self._body(poses, uid) for uid in self._bodies]
