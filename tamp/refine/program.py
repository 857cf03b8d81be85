"""Two robots' event-driven state machines (Figueroa Heredia et al. §2.2, Fig. 1, Fig. 13).

A robot runs its behaviors in order. A behavior moves one *section* (base, arm, gripper)
by a *motion* (a distance or an angle at a speed) until its *event* fires: a sensor
condition on delivered data (force above a threshold, IMU tilt above/below an angle,
odometry progress reaching a value) or another robot's event. A behavior may also *wait
for* events (of the other robot) before it starts.

Parallelized behaviors (Fig. 13(b)): a behavior with ``parallel_with`` set to the previous
behavior's name starts together with it; the previous behavior is *absorbed*: its event
still fires and is recorded (a completion marker) but no longer decides when the robot
continues. Consecutive behaviors linked this way form a *group*; the group's last
behavior's event gates the next group. A section executes one motion at a time.

Every section advances one step per command and commands leave the main CPU at the
behavior's rate P (``rate_hz``, default the program's command rate), so a motion's speed
is ``step · P``: raising P with the step fixed raises the speed by the same ratio (§3.3,
Step 3, for the base).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field, replace

from tamp.perturbation import NONE, Perturbation

SECTIONS = ("base", "arm", "gripper")
SENSORS = ("force", "imu", "odometry")
CATEGORIES = ("I", "II", "III")
MODELS = ("pioneer_lift", "pioneer_parallel")

#: Which motion units a section accepts: the base drives (m) or turns in place (rad), the
#: arm (lift) pitches (rad), the gripper's paddles open or close (m of opening).
UNITS = {"base": ("distance", "angle"), "arm": ("angle",), "gripper": ("distance",)}


def event_id(robot: str, behavior: str) -> str:
    """The event a behavior fires, ``ROBOT.BEHAVIOR``; also its proposition in LTL."""
    return f"{robot}.{behavior}"


def split_event(eid: str) -> tuple[str, str]:
    robot, _, behavior = eid.partition(".")
    return robot, behavior


@dataclass(frozen=True)
class Motion:
    """Move the section by ``amount`` (m or rad, signed) at ``speed`` (m/s or rad/s, > 0)."""

    unit: str  # "distance" | "angle"
    amount: float
    speed: float

    @property
    def nominal_time(self) -> float:
        """Time the whole motion takes at ``speed`` (without waiting for any event)."""
        return abs(self.amount) / self.speed

    def describe(self) -> str:
        u = "m" if self.unit == "distance" else "rad"
        return f"{self.amount:+g} {u} at {self.speed:g} {u}/s"


@dataclass(frozen=True)
class Trigger:
    """What ends a behavior: ``sensor op value`` on delivered data, or ``after`` an event.

    ``op``: ``above``/``below`` compare the reading (force at the gripper: N; imu: pitch of
    the arm, rad, up positive) with ``value``; ``reaches``: the base's odometry progress
    since the behavior started (m or rad, absolute) is at least ``value``.
    """

    sensor: str | None = None
    op: str = ""
    value: float = 0.0
    after: str | None = None

    def describe(self) -> str:
        if self.after is not None:
            return f"after {self.after}"
        unit = {"force": "N", "imu": "rad"}.get(self.sensor or "", "")
        if self.sensor == "odometry":
            return f"odometry reaches {self.value:g}"
        return f"{self.sensor} {self.op} {self.value:g}{' ' + unit if unit else ''}"


@dataclass(frozen=True)
class Behavior:
    """One state of a robot's state machine (§2.2)."""

    name: str
    section: str
    motion: Motion
    event: Trigger
    waits_for: tuple[str, ...] = ()
    parallel_with: str | None = None
    manipulates: bool = False
    rate_hz: float | None = None


@dataclass(frozen=True)
class RobotProgram:
    """One robot: its model (Fig. 7), start pose ``(x, y, yaw)`` and behaviors in order."""

    name: str
    model: str
    start: tuple[float, float, float]
    behaviors: tuple[Behavior, ...]

    def behavior(self, name: str) -> Behavior:
        for b in self.behaviors:
            if b.name == name:
                return b
        raise KeyError(name)

    def index(self, name: str) -> int:
        for i, b in enumerate(self.behaviors):
            if b.name == name:
                return i
        raise KeyError(name)

    def groups(self) -> list[tuple[int, ...]]:
        """Indices of behaviors that start together (linked by ``parallel_with``)."""
        out: list[list[int]] = []
        for i, b in enumerate(self.behaviors):
            if b.parallel_with is not None and out:
                out[-1].append(i)
            else:
                out.append([i])
        return [tuple(g) for g in out]

    def gating(self, i: int) -> bool:
        """True when behavior ``i``'s event decides when the robot continues (not absorbed)."""
        nxt = self.behaviors[i + 1] if i + 1 < len(self.behaviors) else None
        return nxt is None or nxt.parallel_with is None


@dataclass(frozen=True)
class Communication:
    """The measured setting of §4.2: architecture category, sensor and command rates, base
    speed (the default speed of base motions)."""

    category: str
    sensor_rate_hz: float
    command_rate_hz: float
    base_speed: float


@dataclass(frozen=True)
class Program:
    """Two robots' state machines plus the communication setting and the ordering property.

    ``ordering`` is an LTL formula over event ids (``R1.approach``) read with "has fired"
    semantics: the proposition of an event is true from the moment it fires on. ``scene``
    names where the program runs: a packaged scene's name or the user's scene file
    (`tamp.sim.refine.scenario`). ``perturbation`` is the file's ``perturbation:`` section,
    drawn by seeded runs only (not part of the program: equal programs may differ in it).
    """

    name: str
    scene: str
    communication: Communication
    robots: tuple[RobotProgram, ...]
    ordering: str
    description: str = ""
    architecture: str | None = None
    file: str | None = field(default=None, compare=False)
    perturbation: Perturbation = field(default=NONE, compare=False)

    def robot(self, name: str) -> RobotProgram:
        for r in self.robots:
            if r.name == name:
                return r
        raise KeyError(name)

    def events(self) -> list[str]:
        return [event_id(r.name, b.name) for r in self.robots for b in r.behaviors]

    def behaviors(self) -> Iterator[tuple[RobotProgram, int, Behavior]]:
        for r in self.robots:
            for i, b in enumerate(r.behaviors):
                yield r, i, b

    def behavior(self, eid: str) -> Behavior:
        robot, name = split_event(eid)
        return self.robot(robot).behavior(name)

    def rate(self, b: Behavior) -> float:
        """Command rate P of behavior ``b`` (its own, else the program's)."""
        return b.rate_hz if b.rate_hz is not None else self.communication.command_rate_hz

    def with_behavior(self, robot: str, index: int, new: Behavior) -> Program:
        """A copy with behavior ``index`` of ``robot`` replaced."""
        robots = []
        for r in self.robots:
            if r.name == robot:
                bs = list(r.behaviors)
                bs[index] = new
                r = replace(r, behaviors=tuple(bs))
            robots.append(r)
        return replace(self, robots=tuple(robots))

    def with_category(self, category: str) -> Program:
        return replace(self, communication=replace(self.communication, category=category))
