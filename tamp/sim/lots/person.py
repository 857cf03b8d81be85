"""The scripted person of Zhou et al. §III-B in the Drake workcell: a hand that carries objects.

The person follows the same interference script as ``tamp lots --interference`` (events of
`tamp.lots.task.load_events`, timed by `tamp.lots.person.ScriptedPerson.due`: after the
robot's N-th action, or while it carries the object of its next action). It watches the robot
the way a person in the room would, through the robot's skill command and status (a robot
action ends with a succeeded ``Place``/``Discard``/``Wait``; the robot holds something from a
succeeded ``Pick`` until its place ends), and it sees the objects where they lie (the plant's
body poses: the person is part of the world, not of the robot). The robot's controller learns
of the person only through its camera: nothing of the person is connected to it.

Drake idioms, and why:

- The hand (``lots_person_hand.sdf``) is a body on three prismatic joints (world x, y, z)
  whose PD actuators (implicit in SAP, gravity off for the hand) track the path that
  `PersonSystem` outputs as a desired state: minimum-jerk straight moves, computed from the
  context's time, so the hand moves smoothly between the system's updates. Its collision box
  is filtered against everything (`tamp.sim.lots.plant`): the hand never pushes an object.
- Carrying: while the hand holds an object, `PersonSystem` applies a spatial force on it
  (``carry_forces`` -> the plant's applied-spatial-force input): a critically damped spring
  (60 rad/s, scaled by the object's mass and smallest principal inertia, plus the object's
  weight) towards the pose the object had relative to the hand when it was taken. A weld
  constraint would need its active flag toggled from outside the simulator (the flag lives in
  the plant's context, where no event can set it) and would snap the object to a pose fixed
  at build time; the force is an output like any other and holds the object where the hand
  took it. The robot's own grasps stay friction-only.
- State (abstract): the script's progress, the robot's action count, the queue of person
  actions, the current step and what is carried; changed only in a periodic unrestricted
  update (`PERIOD`). Outputs are computed in Calc callbacks.

Objects the person brings in (``add``) wait on a staging shelf beside the table
(`staged_objects`, from the script's add events); objects it takes away (``remove``) go to
the shelf. In a cell that declares a stack (`tamp.sim.lots.stack`), the person acts on the
stack's top: an object of a stack class put into W^B goes on the top of the stack when that
is the object of the class below it (Fig. 10.4: the person builds the body on the bottom),
and the person takes (``remove``, ``move``) only objects that nothing rests on. A ``move``
(dis_1) takes an object of the class from one workspace to a free spot
of the other. Each object is one trip: over it at the transit height, down, take, up, over the
destination, down, let go, up; the hand parks beyond the table when nothing is due. The
camera renders only when perception asks for a view: the hand appears in the images the robot
takes anyway and costs no render of its own.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.multibody.tree import BodyIndex
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from tamp.errors import InputError
from tamp.lots.person import ACTION_SKILLS, ScriptedPerson
from tamp.lots.task import Event
from tamp.sim.core.messages import SkillCommand, SkillStatus
from tamp.sim.lots.catalogue import PERSON, Footprint
from tamp.sim.lots.scenario import CellObject, CellScenario
from tamp.sim.lots.stack import STACK_SIDE, below, covered, free_top
from tamp.world.interface import Status

#: the person's update period (s): checks the robot's status and advances the hand's steps
PERIOD = 0.02
#: the carrying spring's natural frequency (rad/s); explicit, so omega * time_step << 1
CARRY_OMEGA = 60.0
#: staging shelf: spots along y, this far apart (m)
SHELF_PITCH = 0.12
#: gaps (m): the palm over an object's top when taking it; the object over the table when let go
GRIP_GAP = 0.003
DROP_GAP = 0.004
#: an object lies in a workspace, the basket or on the shelf when its origin is this low (m)
RESTING_Z = 0.1
STAGING = "staging"
#: how long the person takes to start once its slot has begun (s): a person's reaction time,
#: which also lets the robot's hand leave the workspace it has just placed in
REACTION = 0.5


def slot_key(n: int, phase: str) -> str:
    """The name of a script slot (after ``n`` robot actions, ``phase`` idle or holding) among a
    run's draws (`tamp.perturbation.PerturbationSample.jitter`)."""
    return f"after {n} {phase}"


def reaction_time(sample, n: int, phase: str) -> float:
    """How long the person takes to start slot ``(n, phase)``: `REACTION` shifted by the run's
    drawn jitter (``perturbation.timing.jitter``: sigma, clipped at 3 sigma), never below 0."""
    shift = 0.0 if sample is None else sample.jitter(slot_key(n, phase))
    return max(0.0, REACTION + shift)


#: the robot's skills that end one action (the script counts them); Discard is Place(waste)
_ENDS_ACTION = ACTION_SKILLS | {"Discard"}


@dataclass(frozen=True)
class HandStep:
    """One step of the hand: ``move`` to ``to``, ``take``/``let_go`` object ``uid``,
    ``wait`` ``duration`` seconds, or ``done`` (the person action ``job`` has ended)."""

    kind: str
    to: tuple[float, float, float] | None = None
    uid: str = ""
    duration: float = 0.0


@dataclass
class PersonAction:
    """One object carried by the person for one scripted event (times in sim seconds)."""

    event: Event
    after: int
    phase: str
    uid: str = ""
    src: str = ""
    dst: str = ""
    start: float | None = None
    end: float | None = None
    outcome: str = "pending"  # pending | running | done | skipped
    detail: str = ""

    def to_json(self) -> dict[str, Any]:
        return {
            "event": self.event.describe(),
            "disturbance": self.event.disturbance,
            "after": self.after,
            "phase": self.phase,
            "object": self.uid,
            "from": self.src,
            "to": self.dst,
            "start": None if self.start is None else round(self.start, 3),
            "end": None if self.end is None else round(self.end, 3),
            "outcome": self.outcome,
            "detail": self.detail,
            "where": self.event.where,
        }


@dataclass
class PersonState:
    """The system's abstract state (see the module docstring)."""

    script: ScriptedPerson
    done: int = 0  # robot actions completed
    holding: bool = False  # the robot carries what a Pick took
    last_status: int = 0  # the last robot command id whose end was counted
    queue: tuple[PersonAction, ...] = ()  # actions due, not started
    actions: list[PersonAction] = field(default_factory=list)  # started or skipped, in order
    steps: tuple[HandStep, ...] = ()
    step_t0: float | None = None
    move: tuple[tuple[float, ...], tuple[float, ...], float, float] | None = None  # p0, p1, t0, T
    hand: tuple[float, float, float] = PERSON.park  # where the hand is headed (rests)
    carrying: str | None = None
    X_HO: np.ndarray | None = None  # carried object's pose in the hand frame (4x4)
    shelf_next: int = 0  # next free staging spot for an object taken away

    def __deepcopy__(self, memo: dict) -> PersonState:
        new = copy.copy(self)
        new.script = copy.deepcopy(self.script)
        new.actions = [copy.copy(a) for a in self.actions]
        return new

    @property
    def idle(self) -> bool:
        """Nothing due, nothing running, the hand parked (or on its way there)."""
        return not self.queue and not self.steps and self.carrying is None


def on_shelf(x: float, y: float, z: float) -> bool:
    """Is a point resting on the person's staging shelf?"""
    (sx, sy), (lx, ly) = PERSON.shelf_center, PERSON.shelf_size
    return z < RESTING_Z and abs(x - sx) <= lx / 2 and abs(y - sy) <= ly / 2


def shelf_spot(k: int) -> tuple[float, float]:
    """The ``k``-th spot of the staging shelf (table frame, m)."""
    sx, sy = PERSON.shelf_center
    n = int(PERSON.shelf_size[1] / SHELF_PITCH)
    return (sx, sy - PERSON.shelf_size[1] / 2 + SHELF_PITCH * (k % n + 0.5))


def staged_objects(
    events: list[Event] | tuple[Event, ...], scenario: CellScenario
) -> tuple[CellObject, ...]:
    """The objects the script's ``add`` events bring in, waiting on the staging shelf (of
    the classes of ``scenario``: the packaged ones and its own)."""
    out: list[CellObject] = []
    room = int(PERSON.shelf_size[1] / SHELF_PITCH)
    for e in events:
        if e.kind != "add":
            continue
        c = scenario.object_class(e.cls)
        if len(out) + e.count > room:  # each one is a free body the person carries in
            file, _, path = e.where.partition(": ")
            raise InputError(
                f"the person's staging shelf holds {room} objects in the Drake workcell; "
                f"this script adds {len(out) + e.count} (`tamp lots` runs any count "
                "symbolically)",
                file=file or None,
                field=f"{path}.count" if path else "count",
            )
        for _ in range(e.count):
            k = len(out)
            rgb = c.palette[k % len(c.palette)]
            out.append(
                CellObject(f"person_{e.cls}_{k + 1}", e.cls, STAGING, shelf_spot(k), 0.0, rgb)
            )
    return tuple(out)


def _min_jerk(s: float) -> tuple[float, float]:
    """Minimum-jerk position and rate (d/ds) at ``s`` in [0, 1]."""
    s = min(max(s, 0.0), 1.0)
    return s**3 * (10 - 15 * s + 6 * s * s), 30 * s * s * (1 - s) ** 2


class PersonSystem(LeafSystem):
    """The scripted person: the hand's desired state and the carrying forces (see module doc).

    Inputs: ``skill_command`` and ``skill_status`` (the robot's, as a person watches it),
    ``body_poses`` and ``body_spatial_velocities`` (the plant's). Outputs: ``hand_desired_state``
    (6: x, y, z and their rates, in the order of the hand's actuators) and ``carry_forces``
    (the plant's applied spatial forces). ``state(context).actions``: what the person did.
    """

    def __init__(
        self,
        plant,
        scenario: CellScenario,
        events: list[Event] | tuple[Event, ...],
        bodies: dict[str, Any],
        classes: dict[str, str],
        hand,
        staged: tuple[str, ...] = (),
        *,
        period: float = PERIOD,
    ):
        super().__init__()
        self.set_name("person")
        self.scenario = scenario
        self._classes = dict(classes)
        self._footprints = {c: scenario.object_class(c).footprint for c in set(classes.values())}
        self._staged = tuple(staged)
        self._hand_index = int(plant.GetBodyByName(PERSON.hand_body, hand).index())
        self._bodies = {uid: int(b.index()) for uid, b in bodies.items()}
        self._mass: dict[str, tuple[float, np.ndarray, float]] = {}
        for uid, b in bodies.items():
            M = b.default_spatial_inertia()
            com = np.asarray(M.get_com())
            I_com = M.Shift(com).CalcRotationalInertia().CopyToFullMatrix3()
            self._mass[uid] = (float(M.get_mass()), com, float(np.linalg.eigvalsh(I_com)[0]))
        order = [
            PERSON.joints.index(plant.get_joint_actuator(i).joint().name())
            for i in plant.GetJointActuatorIndices(hand)
        ]
        self._order = order
        self._g = float(-plant.gravity_field().gravity_vector()[2])
        self.command_port = self.DeclareAbstractInputPort(
            "skill_command", AbstractValue.Make(SkillCommand())
        )
        self.status_port = self.DeclareAbstractInputPort(
            "skill_status", AbstractValue.Make(SkillStatus())
        )
        self.poses_port = self.DeclareAbstractInputPort(
            "body_poses", AbstractValue.Make([RigidTransform()])
        )
        self.velocities_port = self.DeclareAbstractInputPort(
            "body_spatial_velocities", plant.get_body_spatial_velocities_output_port().Allocate()
        )
        init = PersonState(ScriptedPerson(events))
        self._state = self.DeclareAbstractState(AbstractValue.Make(init))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        ticket = {self.abstract_state_ticket(self._state), self.time_ticket()}
        self.desired_state_port = self.DeclareVectorOutputPort(
            "hand_desired_state", 6, self._calc_desired, prerequisites_of_calc=ticket
        )
        #: a light curtain at ``PERSON.curtain_x``: 1 while the hand (its measured pose) is on
        #: the robot's side; wakes the safety monitor's own camera frames, nothing else
        self.present_port = self.DeclareVectorOutputPort(
            "person_present",
            1,
            self._calc_present,
            prerequisites_of_calc={self.input_port_ticket(self.poses_port.get_index())},
        )
        self.forces_port = self.DeclareAbstractOutputPort(
            "carry_forces",
            lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]),
            self._calc_forces,
            prerequisites_of_calc={self.all_sources_ticket()},
        )

    def state(self, context) -> PersonState:
        return context.get_abstract_state(self._state).get_value()

    # ---- outputs -------------------------------------------------------------------------
    def hand_target(self, s: PersonState, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Desired hand position and velocity at time ``t``."""
        if s.move is None:
            return np.asarray(s.hand, float), np.zeros(3)
        p0, p1, t0, T = s.move
        a, da = _min_jerk((t - t0) / T)
        p0, p1 = np.asarray(p0), np.asarray(p1)
        v = (p1 - p0) * da / T if t - t0 < T else np.zeros(3)
        return p0 + (p1 - p0) * a, v

    def _calc_desired(self, context, output: BasicVector) -> None:
        p, v = self.hand_target(self.state(context), context.get_time())
        output.SetFromVector(np.r_[p[self._order], v[self._order]])

    def _calc_present(self, context, output: BasicVector) -> None:
        x = self.poses_port.Eval(context)[self._hand_index].translation()[0]
        output.SetAtIndex(0, 1.0 if x < PERSON.curtain_x else 0.0)

    def _calc_forces(self, context, output) -> None:
        s = self.state(context)
        if s.carrying is None:
            output.set_value([])
            return
        poses = self.poses_port.Eval(context)
        vels = self.velocities_port.Eval(context)
        uid = s.carrying
        i = self._bodies[uid]
        m, com_B, I_min = self._mass[uid]
        X_WH, X_WO = poses[self._hand_index], poses[i]
        X_des = X_WH @ RigidTransform(s.X_HO)
        V_H, V_O = vels[self._hand_index], vels[i]
        w = CARRY_OMEGA
        p_com, p_des = X_WO @ com_B, X_des @ com_B
        r = p_des - X_WH.translation()
        v_des = V_H.translational() + np.cross(V_H.rotational(), r)
        v_com = V_O.translational() + np.cross(V_O.rotational(), p_com - X_WO.translation())
        f = m * (w * w * (p_des - p_com) + 2 * w * (v_des - v_com)) + [0.0, 0.0, m * self._g]
        aa = (X_des.rotation() @ X_WO.rotation().inverse()).ToAngleAxis()
        theta = aa.axis() * aa.angle()
        tau = I_min * (w * w * theta + 2 * w * (V_H.rotational() - V_O.rotational()))
        force = ExternallyAppliedSpatialForce()
        force.body_index = BodyIndex(i)
        force.p_BoBq_B = com_B
        force.F_Bq_W = SpatialForce(tau, f)
        output.set_value([force])

    # ---- the update ----------------------------------------------------------------------
    def _update(self, context, state) -> EventStatus:
        old = self.state(context)
        s: PersonState = copy.deepcopy(old)
        t = context.get_time()
        self._watch_robot(s, context)
        for n, phase, e in s.script.due(s.done, s.holding):
            s.queue = (*s.queue, *(PersonAction(e, n, phase) for _ in range(e.count)))
            if not s.steps:  # the person reacts: the robot has a moment to move on
                s.steps = (
                    HandStep("wait", duration=reaction_time(self.scenario.sample, n, phase)),
                )
        if s.idle and s.move is None and s.last_status == old.last_status and not s.queue:
            if s.script.progress() == old.script.progress():
                return EventStatus.DidNothing()  # parked, nothing new: keep the state
        if not s.steps and s.queue:
            self._plan_next(s, context, t)
        if s.steps:
            self._advance(s, context, t)
        state.get_mutable_abstract_state(self._state).set_value(s)
        return EventStatus.Succeeded()

    def _watch_robot(self, s: PersonState, context) -> None:
        """Count the robot's completed actions and whether it carries something."""
        cmd: SkillCommand = self.command_port.Eval(context)
        st: SkillStatus = self.status_port.Eval(context)
        if st.id == 0 or st.id != cmd.id or st.status is Status.RUNNING:
            return
        if st.id == s.last_status:
            return
        s.last_status = st.id
        if cmd.name == "Pick" and st.status is Status.SUCCESS:
            s.holding = True
        elif cmd.name in _ENDS_ACTION:
            if cmd.name != "Wait":
                s.holding = False
            if st.status is Status.SUCCESS:
                s.done += 1

    def _where(self, context) -> dict[str, tuple[str, RigidTransform]]:
        """Each object's place (A, B, staging or "") and pose, from the plant."""
        poses = self.poses_port.Eval(context)
        out = {}
        for uid, i in self._bodies.items():
            X = poses[i]
            x, y, z = X.translation()
            where = ""
            if z < RESTING_Z:
                for side, w in self.scenario.workspaces.items():
                    if w.contains(x, y):
                        where = side
                if on_shelf(x, y, z):
                    where = STAGING
            out[uid] = (where, X)
        return out

    def _plan_next(self, s: PersonState, context, t: float) -> None:
        """Start the next due action: choose its object and destination, queue the hand's
        steps. An action that cannot happen (no such object there) is logged as skipped."""
        act, s.queue = s.queue[0], s.queue[1:]
        e = act.event
        where = self._where(context)
        if e.kind == "add":
            src, dst = STAGING, e.side
            pool = [u for u in self._staged if self._classes[u] == e.cls]
        else:
            src = e.src if e.kind == "move" else e.side
            dst = e.dst if e.kind == "move" else STAGING
            pool = sorted(self._bodies)
        taken = {a.uid for a in s.actions if a.outcome in ("running", "done")}
        cands = [
            u for u in pool if self._classes[u] == e.cls and where[u][0] == src and u != s.carrying
        ]
        if e.kind == "add":
            cands = [u for u in cands if u not in taken]
        else:  # a person takes an object from the top: none that another rests on
            cands = [u for u in cands if not self._covered(u, where)]
        act.src, act.dst, act.start = src, dst, t
        s.actions.append(act)
        if not cands:
            act.outcome, act.end = "skipped", t
            act.detail = f"no {e.cls} {'on the shelf' if src == STAGING else 'in W^' + src}"
            if src != STAGING and any(
                self._classes[u] == e.cls and where[u][0] == src for u in pool
            ):
                act.detail = f"every {e.cls} in W^{src} has something on it"
            if tuple(s.hand) != PERSON.park:
                s.steps = (HandStep("move", PERSON.park),)
            return
        uid = cands[0]
        act.uid, act.outcome = uid, "running"
        X_WO = where[uid][1]
        top = self.scenario.object_class(e.cls).footprint.top
        p_take = self._over(X_WO, e.cls)
        stack_top = self._stack_top(dst, e.cls, where)
        if dst == STAGING:
            q = shelf_spot(len(self._staged) + s.shelf_next)
            s.shelf_next += 1
            floor = 0.0
        elif stack_top is not None:  # a level of the declared stack: on its top
            q, floor = stack_top[:2], stack_top[2]
        else:
            q = self._free_spot(dst, uid, where)
            floor = self.scenario.workspaces[dst].floor
        c = X_WO.translation()
        dx, dy = p_take[0] - c[0], p_take[1] - c[1]  # grip point's offset from the origin
        z_take = float(c[2]) + top + GRIP_GAP
        z_put = floor + top + GRIP_GAP + DROP_GAP
        h = PERSON.transit
        s.steps = (
            HandStep("move", (p_take[0], p_take[1], h)),
            HandStep("move", (p_take[0], p_take[1], z_take)),
            HandStep("take", uid=uid),
            HandStep("wait", duration=0.15),
            HandStep("move", (p_take[0], p_take[1], h)),
            HandStep("move", (q[0] + dx, q[1] + dy, h)),
            HandStep("move", (q[0] + dx, q[1] + dy, z_put)),
            HandStep("let_go", uid=uid),
            HandStep("wait", duration=0.25),
            HandStep("move", (q[0] + dx, q[1] + dy, h)),
            HandStep("done"),
        )

    def _over(self, X_WO: RigidTransform, cls: str) -> tuple[float, float]:
        """The point over the middle of the object's footprint (where the palm takes it)."""
        f = self._footprint(cls)
        p = X_WO @ np.array([(f.xmin + f.xmax) / 2, (f.ymin + f.ymax) / 2, 0.0])
        return float(p[0]), float(p[1])

    def _free_spot(self, side: str, uid: str, where) -> tuple[float, float]:
        """The point of W^side (inside by the object's reach) where the object, put down with
        the yaw it has, keeps the largest clearance from every other object lying there:
        where a person would put a thing down. Clearance is measured between footprints
        (`box_gap`), not origins: the Fig. 9 wrench, put 15 cm from the hammer's
        origin, lay on the hammer's head, and lifting the hammer made the plant non-finite."""
        w = self.scenario.workspaces[side]
        others = [
            self._footprint(self._classes[u]).corners(*X.translation()[:2], yaw_of(X))
            for u, (_, X) in where.items()
            if u != uid and _near(X, w)
        ]
        f = self._footprint(self._classes[uid])
        return free_spot(w, f, yaw_of(where[uid][1]), others)

    def _objects(self, where, side: str | None = None) -> dict[str, tuple[str, np.ndarray]]:
        """Each object (of W^side; None: everywhere) as `tamp.sim.lots.stack` reads them:
        id -> (class, pose)."""
        return {
            u: (self._classes[u], X.GetAsMatrix4())
            for u, (w, X) in where.items()
            if side is None or w == side
        }

    def _covered(self, uid: str, where) -> bool:
        """Whether another object rests on ``uid`` (`tamp.sim.lots.stack.covered`)."""
        return covered(uid, self._objects(where), self._footprints)

    def _stack_top(self, side: str, cls: str, where) -> tuple[float, float, float] | None:
        """Where the person puts an object of ``cls`` in W^side when it is a level of the
        cell's declared stack: the middle of the top of an object of the class below it that
        nothing rests on yet (`tamp.sim.lots.stack.free_top`); None when ``cls`` goes on the
        floor there (not a stack class, the base, another workspace, or no such object)."""
        on = below(self.scenario.stack, cls) if side == STACK_SIDE else None
        if on is None:
            return None
        return free_top(on, self._objects(where, side), self._footprints)

    def _footprint(self, cls: str) -> Footprint:
        return self.scenario.object_class(cls).footprint

    def _advance(self, s: PersonState, context, t: float) -> None:
        """Run the current step; a step that ends hands over to the next in the same update."""
        while s.steps:
            step = s.steps[0]
            if s.step_t0 is None:
                s.step_t0 = t
                if step.kind == "move":
                    p0, _ = self.hand_target(s, t)
                    d = float(np.linalg.norm(np.asarray(step.to) - p0))
                    T = max(1.875 * d / PERSON.speed, 0.3)
                    s.move = (tuple(p0), step.to, t, T)
                    s.hand = step.to
            el = t - s.step_t0
            if step.kind == "move":
                if el < s.move[3] + 0.06:
                    return
                s.move = None
            elif step.kind == "wait":
                if el < step.duration:
                    return
            elif step.kind == "take":
                poses = self.poses_port.Eval(context)
                X_WH, X_WO = poses[self._hand_index], poses[self._bodies[step.uid]]
                s.carrying = step.uid
                s.X_HO = (X_WH.inverse() @ X_WO).GetAsMatrix4()
            elif step.kind == "let_go":
                s.carrying, s.X_HO = None, None
            elif step.kind == "done":
                act = s.actions[-1]
                act.outcome, act.end = "done", t
                if not s.queue:  # nothing else due: back to the park position
                    s.steps = (HandStep("move", PERSON.park),)
                    s.step_t0 = None
                    continue
            s.steps, s.step_t0 = s.steps[1:], None
            if not s.steps and s.queue:
                self._plan_next(s, context, t)


def free_spot(w, f, yaw: float, others: list[np.ndarray]) -> tuple[float, float]:
    """The origin, on a 9 x 9 grid over workspace ``w``'s floor (`Workspace.floor_size`,
    inside by the object's reach), that gives an object of footprint ``f`` at ``yaw`` the
    largest gap to the ``others``' footprints (4 x 2 corners each, `Footprint.corners`);
    the centre when there are none."""
    reach = max(abs(f.xmin), abs(f.xmax), abs(f.ymin), abs(f.ymax)) + 0.01
    hx, hy = w.floor_size[0] / 2 - reach, w.floor_size[1] / 2 - reach
    if not others or hx <= 0 or hy <= 0:
        return w.center
    best, best_d = w.center, -1.0
    for dx in np.linspace(-hx, hx, 9):
        for dy in np.linspace(-hy, hy, 9):
            x, y = w.center[0] + dx, w.center[1] + dy
            mine = f.corners(x, y, yaw)
            d = min(box_gap(mine, o) for o in others)
            if d > best_d + 1e-9:
                best, best_d = (float(x), float(y)), d
    return best


def box_gap(a: np.ndarray, b: np.ndarray) -> float:
    """The distance between two convex quadrilaterals (4 x 2 corners, in order); 0 when they
    overlap (no separating axis among their edge normals)."""

    def separated() -> bool:
        for poly in (a, b):
            for i in range(4):
                e = poly[(i + 1) % 4] - poly[i]
                n = np.array([-e[1], e[0]])
                pa, pb = a @ n, b @ n
                if pa.max() < pb.min() or pb.max() < pa.min():
                    return True
        return False

    def to_segment(p: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> float:
        e = q1 - q0
        t = min(max(float(np.dot(p - q0, e) / np.dot(e, e)), 0.0), 1.0)
        return float(np.linalg.norm(p - (q0 + t * e)))

    if not separated():
        return 0.0
    return min(
        to_segment(p, poly[i], poly[(i + 1) % 4])
        for pts, poly in ((a, b), (b, a))
        for p in pts
        for i in range(4)
    )


def yaw_of(X: RigidTransform) -> float:
    """The heading of a pose about the vertical (rad)."""
    R = X.rotation().matrix()
    return math.atan2(R[1, 0], R[0, 0])


def _near(X: RigidTransform, w) -> bool:
    x, y, z = X.translation()
    return (
        z < RESTING_Z
        and abs(x - w.center[0]) <= w.size[0] / 2 + 0.05
        and (abs(y - w.center[1]) <= w.size[1] / 2 + 0.05)
    )


def add_person(builder, cell, plant, scenario: CellScenario, events, skills) -> PersonSystem:
    """Adds the `PersonSystem` of ``events`` to ``builder`` and wires it: the plant's poses
    and velocities and the robot's skill status in; the hand's desired state and the carrying
    forces out to the plant. The caller connects ``skill_command`` (the robot's command)."""
    person = builder.AddSystem(
        PersonSystem(plant, scenario, events, cell.bodies, cell.classes, cell.hand, cell.staged)
    )
    builder.Connect(plant.get_body_poses_output_port(), person.poses_port)
    builder.Connect(plant.get_body_spatial_velocities_output_port(), person.velocities_port)
    builder.Connect(skills.status_port, person.status_port)
    builder.Connect(person.desired_state_port, plant.get_desired_state_input_port(cell.hand))
    builder.Connect(person.forces_port, plant.get_applied_spatial_force_input_port())
    return person
