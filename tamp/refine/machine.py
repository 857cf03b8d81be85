"""One robot's state machine as its main CPU runs it (§2.2, Fig. 1, Fig. 13), without Drake.

`Machine.step` is what the workcell's state-machine system
(`tamp.sim.refine.skills.PioneerStateMachine`) does once per sensor period:

1. **Events on delivered data.** A running behavior's event fires when its condition holds
   on the latest *delivered* sample of its sensor created after the behavior started
   (force above/below, IMU pitch above/below, odometry progress since the start reaching a
   value), or when the named event of the other robot has fired. A late sample means a
   late event, and the section keeps moving meanwhile: the overshoot is physical.
2. **Starts.** A behavior starts once every event it must follow has fired
   (`tamp.refine.order.start_predecessors`: the previous group's gating event, what the
   group waits for, an absorbed behavior still moving the same section).
3. **Commands at rate P.** When a command is due (every 1 / P, P the supervisor's rate or
   the running behavior's own), every running behavior whose event has not fired advances
   its section by one step (speed / the behavior's rate, so the speed scales with P) up to
   its motion's amount, and one command with the absolute setpoints of every joint is
   published. Commands leave also while every section holds (the main CPU's cycle).
   When an event fires, its section holds where its delivered sensor says it is (base:
   odometry, arm: IMU), so the motion between the true crossing and the late event stays.

What a machine puts out: a `Command` (absolute setpoints of the robot's joints, `JOINTS`
order, to its actuators through the communication network) and its `Progress` (fired
events, to the other robot's machine and the rate supervisor).

The robots (Fig. 7) are Pioneer-like: a planar base (x, y, yaw), a lift lever that pitches
(``arm_pitch``, up positive) and two prismatic paddles/fingers, each 0 .. `FINGER_MAX` from
the centre line; a program's gripper motion changes the *opening*, the sum of both.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from tamp.refine.order import start_predecessors
from tamp.refine.program import Behavior, Program, RobotProgram, event_id
from tamp.refine.queues import Delivery
from tamp.refine.timeline import BehaviorRecord

#: The joints a command sets, in its order (the models' joint names).
JOINTS = (
    "base_x",
    "base_y",
    "base_yaw",
    "arm_pitch",
    "finger_left_joint",
    "finger_right_joint",
)
FINGER_MAX = 0.08  # m from the centre line, per finger
OPENING_START = 2 * FINGER_MAX  # both grippers start fully open

#: setpoint slots: base x, y, yaw, arm pitch, gripper opening
X, Y, YAW, ARM, OPENING = range(5)


@dataclass(frozen=True)
class Command:
    """The ``number``-th command of a robot (0: none yet), created at ``created``: absolute
    setpoints of its joints (`JOINTS` order, each finger at half the opening) and the
    ``sections`` its running behaviors move (its load on the network,
    `tamp.refine.architecture.Architecture.command_stream`)."""

    number: int = 0
    created: float = 0.0
    setpoints: tuple[float, ...] = ()
    sections: tuple[str, ...] = ()

    def __deepcopy__(self, memo: dict) -> Command:
        return self  # immutable: a Drake state copy costs nothing


@dataclass(frozen=True)
class Progress:
    """What a robot's machine has done: fired events (id -> time), the behaviors running
    now, whether every behavior's event fired, and the command rate it uses."""

    fired: dict[str, float] = field(default_factory=dict)
    running: tuple[str, ...] = ()
    done: bool = False
    rate: float = 0.0

    def __deepcopy__(self, memo: dict) -> Progress:
        return self


@dataclass(frozen=True)
class MachineState:
    """Started/fired times per behavior, odometry at each start, amounts commanded, the
    section setpoints and the command stream."""

    setpoints: tuple[float, float, float, float, float]
    started: dict[str, float] = field(default_factory=dict)
    fired: dict[str, float] = field(default_factory=dict)
    refs: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    issued: dict[str, float] = field(default_factory=dict)
    next_due: float = 0.0
    command: Command = Command()
    rate: float = 0.0

    def __deepcopy__(self, memo: dict) -> MachineState:
        return self  # immutable (the dicts are never changed in place)


def wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def progress(b: Behavior, ref: tuple[float, float, float], pose: tuple[float, float, float]):
    """Odometry progress of base behavior ``b`` since ``ref`` (m along the start heading, or
    rad turned), absolute."""
    if b.motion.unit == "angle":
        return abs(wrap(pose[2] - ref[2]))
    c, s = math.cos(ref[2]), math.sin(ref[2])
    return abs((pose[0] - ref[0]) * c + (pose[1] - ref[1]) * s)


class Machine:
    """The state machine of robot ``robot`` of ``program`` (pure: `step` returns new state)."""

    def __init__(self, program: Program, robot: str):
        self.program = program
        self.robot: RobotProgram = program.robot(robot)
        self.preds = {
            b.name: frozenset(start_predecessors(self.robot, i))
            for i, b in enumerate(self.robot.behaviors)
        }
        self._ids = {b.name: event_id(self.robot.name, b.name) for b in self.robot.behaviors}

    def initial(self) -> MachineState:
        x, y, yaw = self.robot.start
        return MachineState(setpoints=(x, y, yaw, 0.0, OPENING_START))

    def joint_setpoints(self, sp: tuple[float, ...]) -> tuple[float, ...]:
        """Setpoints in `JOINTS` order (each finger at half the opening)."""
        half = min(max(sp[OPENING] / 2, 0.0), FINGER_MAX)
        return (sp[X], sp[Y], sp[YAW], sp[ARM], half, half)

    def running(self, s: MachineState) -> list[Behavior]:
        return [b for b in self.robot.behaviors if b.name in s.started and b.name not in s.fired]

    def rate_of(self, s: MachineState, override: float | None) -> float:
        if override is not None:
            return override
        run = self.running(s)
        if run:
            return self.program.rate(run[0])
        started = [b for b in self.robot.behaviors if b.name in s.started]
        b = started[-1] if started else self.robot.behaviors[0]
        return self.program.rate(b)

    def _triggered(
        self, b: Behavior, s: MachineState, samples: Mapping[str, Delivery], fired: set[str]
    ) -> bool:
        t = b.event
        if t.after is not None:
            return t.after in fired
        d = samples.get(t.sensor or "")
        if d is None or d.message.created < s.started[b.name] - 1e-9:
            return False
        if t.sensor == "odometry":
            return progress(b, s.refs[b.name], d.message.value) >= t.value - 1e-12
        v = float(d.message.value)
        return v > t.value if t.op == "above" else v < t.value

    @staticmethod
    def _hold(b: Behavior, sp: list[float], samples: Mapping[str, Delivery]) -> None:
        """A section whose behavior ended holds where its sensor says it is (the driver's
        stop), not where the setpoints ran ahead while the event was on its way."""
        if b.section == "base" and "odometry" in samples:
            sp[X], sp[Y], sp[YAW] = samples["odometry"].message.value
        elif b.section == "arm" and "imu" in samples:
            sp[ARM] = float(samples["imu"].message.value)

    def step(
        self,
        s: MachineState,
        t: float,
        samples: Mapping[str, Delivery],
        others: Mapping[str, float],
        override: float | None = None,
    ) -> MachineState:
        """The machine one sensor period on, at time ``t`` (module docstring); ``s`` itself
        when nothing changed (no event fired, nothing started, no command due)."""
        ids = self._ids
        fired_ids = set(others)
        fired_ids.update(ids[n] for n in s.fired)
        new_fired: dict[str, float] = {}
        sp = list(s.setpoints)
        for b in self.running(s):
            if self._triggered(b, s, samples, fired_ids):
                new_fired[b.name] = t
                fired_ids.add(ids[b.name])
                self._hold(b, sp, samples)
        if new_fired:
            s = replace(s, setpoints=tuple(sp), fired={**s.fired, **new_fired})
        starts = [
            b.name
            for b in self.robot.behaviors
            if b.name not in s.started and self.preds[b.name] <= fired_ids
        ]
        if starts:
            odo = samples.get("odometry")
            ref = tuple(odo.message.value) if odo is not None else self.robot.start
            s = replace(
                s,
                started={**s.started, **dict.fromkeys(starts, t)},
                refs={**s.refs, **dict.fromkeys(starts, ref)},
            )
        rate = self.rate_of(s, override)
        if t + 1e-9 < s.next_due:
            return s if rate == s.rate else replace(s, rate=rate)
        sp = list(s.setpoints)
        issued = dict(s.issued)
        for b in self.running(s):
            done = issued.get(b.name, 0.0)
            left = abs(b.motion.amount) - done
            if left <= 1e-12:
                continue
            inc = min(b.motion.speed / self.program.rate(b), left)
            issued[b.name] = done + inc
            delta = math.copysign(inc, b.motion.amount)
            if b.section == "base" and b.motion.unit == "distance":
                sp[X] += delta * math.cos(sp[YAW])
                sp[Y] += delta * math.sin(sp[YAW])
            elif b.section == "base":
                sp[YAW] += delta
            elif b.section == "arm":
                sp[ARM] += delta
            else:
                sp[OPENING] = min(max(sp[OPENING] + delta, 0.0), OPENING_START)
        setpoints = tuple(sp)
        sections = tuple(dict.fromkeys(b.section for b in self.running(s)))
        command = Command(s.command.number + 1, t, self.joint_setpoints(setpoints), sections)
        next_due = max(s.next_due + 1.0 / rate, t)
        return replace(
            s, setpoints=setpoints, issued=issued, command=command, next_due=next_due, rate=rate
        )

    def progress_of(self, s: MachineState) -> Progress:
        name = self.robot.name
        return Progress(
            fired={event_id(name, n): v for n, v in s.fired.items()},
            running=tuple(b.name for b in self.running(s)),
            done=len(s.fired) == len(self.robot.behaviors),
            rate=s.rate,
        )

    def records(self, s: MachineState) -> list[BehaviorRecord]:
        """The timeline of this robot (behaviors never started have ``start`` None)."""
        return [
            BehaviorRecord(
                self.robot.name,
                b.name,
                b.section,
                s.started.get(b.name),
                s.fired.get(b.name),
                self.robot.gating(i),
            )
            for i, b in enumerate(self.robot.behaviors)
        ]
