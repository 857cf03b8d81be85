"""The refinement steps (Fig. 3–6, Fig. 13) as pure functions over programs.

Refining the trajectory (§3.2, Fig. 4):
- Step 1 `locate`: per robot, the behaviors before the manipulation of the object, which
  starts where `manipulation_starts` finds it in the original run (first gripper/object
  contact) or where the program marks it.
- Step 2 `parallelize`: behavior n joins n + 1 (both before manipulation) when n took less
  time than n + 1 and nothing obstructs (different sections, n + 1 waits for nothing, n + 1
  is not already in a group with n's section). n is absorbed: its event becomes a
  completion marker (Fig. 13). The runner executes the result once and `revert`s a
  parallelization that collides.
- `slack_waits` (Step 2 across robots, §3.2(b)): a cross-robot wait that the measured run
  shows held nothing back is a candidate to `relax` (run once, `restore`d if it fails).
- `adjust_base_speed` (Fig. 6(c)): in a group whose base motion outlasts the other
  behaviors, the base speed grows so that it ends with them.

Refining the communication rate (§3.3, Fig. 5):
- `RateSearch`: raise P by a step while the triggering sensor's samples arrive without
  delay (wait below the threshold); on the first delayed probe keep the previous P. The
  same object drives the offline search (`refine_rate`, any measured wait function) and
  the RateTuningSupervisor in the simulation.
- `apply_rate` (Step 3): set the robot's P (per behavior) and scale the base speed by the
  same ratio, as the paper says; scaling every section (the step per command kept) is an
  option (``scale="all"``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

from tamp.refine.program import Program, RobotProgram, event_id

# ----------------------------------------------------------------------------- Step 1


def locate(program: Program, starts: Mapping[str, int] | None = None) -> dict[str, tuple[int, ...]]:
    """Step 1: indices of each robot's behaviors before its manipulation of the object.

    ``starts``: robot -> index of its first manipulating behavior (`manipulation_starts`,
    from a measured run); a robot not in it uses its first behavior marked
    ``manipulates`` (all behaviors when none is)."""
    out = {}
    for r in program.robots:
        first = next((i for i, b in enumerate(r.behaviors) if b.manipulates), len(r.behaviors))
        if starts is not None and r.name in starts:
            first = starts[r.name]
        out[r.name] = tuple(range(first))
    return out


@dataclass(frozen=True)
class Boundary:
    """Where robot ``robot``'s manipulation starts: ``index`` of its first manipulating
    behavior (len(behaviors): none), how it was found (``source``), and the first touch
    of a task object in the original run (time, body) if there was one."""

    robot: str
    index: int
    behavior: str | None
    source: str  # "touch", "marked" or "no object in the task"
    touch: tuple[float, str] | None = None
    marked: str | None = None

    def to_json(self) -> dict:
        return {
            "robot": self.robot,
            "behavior": self.behavior,
            "source": self.source,
            "touch": None if self.touch is None else [round(self.touch[0], 3), self.touch[1]],
            "marked": self.marked,
        }


def manipulation_starts(
    program: Program,
    touches: Mapping[str, tuple[float, str]],
    spans: Mapping[str, tuple[float | None, float | None]],
    *,
    has_goal: bool,
) -> dict[str, Boundary]:
    """Step 1 from a measured run: where each robot's manipulation starts.

    ``touches``: robot -> (first time its gripper touched a task object, the body);
    ``spans``: event id -> (start, end) of each behavior in that run. The behavior running
    at the first touch manipulates the object, unless it drives the base: a base motion
    that reaches the object is the approach to it (the paper's Task 4 counts Robot 1's
    forward motion under the chair before the manipulation, Fig. 13), and the manipulation
    starts with the next behavior. A behavior marked ``manipulates`` earlier than that
    moves the boundary earlier (the user's word is kept when it is more cautious). A robot
    that never touched a task object and has no marked behavior is refused
    (`InfeasibleError`) when the task has a goal; in a task without one (no object to
    manipulate) all its behaviors come before manipulation."""
    from tamp.errors import InfeasibleError

    out = {}
    for r in program.robots:
        marked = next((i for i, b in enumerate(r.behaviors) if b.manipulates), None)
        touch = touches.get(r.name)
        found = None
        if touch is not None:
            t = touch[0]
            for i, b in enumerate(r.behaviors):
                start, end = spans.get(event_id(r.name, b.name), (None, None))
                if start is not None and start <= t and (end is None or t <= end):
                    found = i + 1 if b.section == "base" else i
                    break
            else:
                found = next(
                    (
                        i
                        for i, b in enumerate(r.behaviors)
                        if (spans.get(event_id(r.name, b.name), (None, None))[0] or -1.0) >= t
                    ),
                    len(r.behaviors),
                )
        if found is None and marked is None:
            if has_goal:
                raise InfeasibleError(
                    f"{r.name}: where its manipulation starts is unknown: its gripper never "
                    "touched a task object in the original run and no behavior is marked "
                    "'manipulates' (Step 1 needs it)"
                )
            index, source = len(r.behaviors), "no object in the task"
        elif marked is not None and (found is None or marked < found):
            index, source = marked, "marked"
        else:
            assert found is not None  # both None was handled above
            index, source = found, "touch"
        behavior = r.behaviors[index].name if index < len(r.behaviors) else None
        name = r.behaviors[marked].name if marked is not None else None
        out[r.name] = Boundary(r.name, index, behavior, source, touch, name)
    return out


# ----------------------------------------------------------------------------- Step 2


@dataclass(frozen=True)
class Parallelization:
    """Behavior ``absorbed`` (n) of ``robot`` now starts with ``host`` (n + 1)."""

    robot: str
    absorbed: str
    host: str

    def describe(self) -> str:
        return f"{self.robot}: {self.absorbed} runs in parallel with {self.host}"


def _group_sections(r: RobotProgram, i: int) -> set[str]:
    """Sections of the group that behavior ``i`` belongs to (up to and including ``i``)."""
    sections = {r.behaviors[i].section}
    while i > 0 and r.behaviors[i].parallel_with is not None:
        i -= 1
        sections.add(r.behaviors[i].section)
    return sections


def obstruction(r: RobotProgram, n: int) -> str | None:
    """Why behavior n + 1 cannot start with n (None: nothing obstructs)."""
    a, b = r.behaviors[n], r.behaviors[n + 1]
    if b.parallel_with is not None:
        return f"{b.name} already runs in parallel"
    if b.section in _group_sections(r, n):
        return f"{a.name} and {b.name} share the {b.section}"
    if b.waits_for:
        return f"{b.name} waits for {', '.join(b.waits_for)}"
    if b.event.after == event_id(r.name, a.name):
        return f"{b.name} ends after {a.name}"
    return None


def parallelize(
    program: Program,
    durations: Mapping[str, float],
    starts: Mapping[str, int] | None = None,
) -> tuple[Program, list[Parallelization]]:
    """Step 2 over the behaviors located by Step 1 (``starts``: see `locate`), using
    measured ``durations`` (event id -> seconds). Returns the new program and what was
    parallelized, in order."""
    done: list[Parallelization] = []
    pre = locate(program, starts)
    for r in program.robots:
        idx = pre[r.name]
        for n in idx:
            if n + 1 not in idx:
                continue
            cur = program.robot(r.name)
            a, b = cur.behaviors[n], cur.behaviors[n + 1]
            ta, tb = (
                durations.get(event_id(r.name, a.name)),
                durations.get(event_id(r.name, b.name)),
            )
            if ta is None or tb is None or not ta < tb or obstruction(cur, n) is not None:
                continue
            p = Parallelization(r.name, a.name, b.name)
            program = join(program, p)
            done.append(p)
    return program, done


def join(program: Program, p: Parallelization) -> Program:
    """Apply one parallelization: the host starts together with the absorbed behavior (at
    its rate: behaviors that run in parallel share one command rate)."""
    r = program.robot(p.robot)
    i = r.index(p.host)
    absorbed = r.behavior(p.absorbed)
    new = replace(r.behaviors[i], parallel_with=p.absorbed, rate_hz=absorbed.rate_hz)
    return program.with_behavior(p.robot, i, new)


def revert(program: Program, p: Parallelization) -> Program:
    """Undo one parallelization (the host waits for the absorbed behavior's event again)."""
    r = program.robot(p.robot)
    i = r.index(p.host)
    return program.with_behavior(p.robot, i, replace(r.behaviors[i], parallel_with=None))


@dataclass(frozen=True)
class Relaxation:
    """Behavior ``behavior`` of ``robot`` no longer waits for the other robot's ``event``
    (Step 2 across robots, §3.2(b))."""

    robot: str
    behavior: str
    event: str

    def describe(self) -> str:
        return f"{self.robot}: {self.behavior} no longer waits for {self.event}"


def slack_waits(
    program: Program, spans: Mapping[str, tuple[float | None, float | None]]
) -> list[Relaxation]:
    """Step 2 across robots (§3.2(b), the motions of two robots): the cross-robot waits
    that the measured run shows are not needed: the awaited event had fired by the time
    the behavior's own robot let it start (its own predecessors' events), so the wait held
    nothing back. ``spans``: event id -> (start, end) in that run. Whether the program
    still works without it is for the ordering gate and one run to say."""
    from tamp.refine.order import start_predecessors

    out = []
    for r in program.robots:
        for i, b in enumerate(r.behaviors):
            if not b.waits_for:
                continue
            own = start_predecessors(r, i) - set(b.waits_for)
            ends = [spans.get(e, (None, None))[1] for e in own]
            if any(t is None for t in ends):
                continue
            ready = max((t for t in ends if t is not None), default=0.0)
            for e in b.waits_for:
                t = spans.get(e, (None, None))[1]
                if t is not None and t <= ready + 1e-9:
                    out.append(Relaxation(r.name, b.name, e))
    return out


def relax(program: Program, x: Relaxation) -> Program:
    """Drop one cross-robot wait."""
    r = program.robot(x.robot)
    i = r.index(x.behavior)
    b = r.behaviors[i]
    waits = tuple(e for e in b.waits_for if e != x.event)
    return program.with_behavior(x.robot, i, replace(b, waits_for=waits))


def restore(program: Program, x: Relaxation) -> Program:
    """Undo `relax`: the behavior waits for the event again."""
    r = program.robot(x.robot)
    i = r.index(x.behavior)
    b = r.behaviors[i]
    return program.with_behavior(x.robot, i, replace(b, waits_for=(*b.waits_for, x.event)))


@dataclass(frozen=True)
class SpeedChange:
    """Base behavior ``event``'s speed went from ``old`` to ``new`` to end with ``partner``."""

    event: str
    old: float
    new: float
    partner: str

    def describe(self) -> str:
        return (
            f"{self.event}: base speed {self.old:.4g} -> {self.new:.4g} (ends with {self.partner})"
        )


def adjust_base_speed(
    program: Program, durations: Mapping[str, float]
) -> tuple[Program, list[SpeedChange]]:
    """Fig. 6(c): in each parallel group, a base motion that took longer than the group's
    other behaviors is sped up by the ratio of the durations so that it ends with them."""
    changes: list[SpeedChange] = []
    for r in program.robots:
        for group in r.groups():
            if len(group) < 2:
                continue
            members = [r.behaviors[i] for i in group]
            others = [
                (durations.get(event_id(r.name, b.name)), b.name)
                for b in members
                if b.section != "base"
            ]
            others = [(t, n) for t, n in others if t is not None]
            if not others:
                continue
            target, partner = max(others)
            for i in group:
                b = r.behaviors[i]
                t = durations.get(event_id(r.name, b.name))
                if b.section != "base" or t is None or t <= target or target <= 0:
                    continue
                speed = b.motion.speed * t / target
                new = replace(b, motion=replace(b.motion, speed=speed))
                program = program.with_behavior(r.name, i, new)
                changes.append(
                    SpeedChange(event_id(r.name, b.name), b.motion.speed, speed, partner)
                )
    return program, changes


# ----------------------------------------------------------------------------- Fig. 5


@dataclass(frozen=True)
class RateSearch:
    """Fig. 5, Step 2 as a state machine: probe ``rate``; `observe` its measured wait.

    Starts at ``current + step``. A probe whose wait is at most ``threshold`` raises the
    rate by ``step``; the first delayed probe ends the search with the rate before the last
    increment (``found``). ``limit`` caps the rate (commands faster than the sensors are
    not useful); reaching it also ends the search.
    """

    current: float
    step: float
    threshold: float
    limit: float
    rate: float = 0.0
    found: float | None = None
    probes: tuple[tuple[float, float], ...] = ()  # (rate, measured wait)

    def __post_init__(self) -> None:
        if self.rate == 0.0:
            object.__setattr__(self, "rate", min(self.current + self.step, self.limit))
        if self.current >= self.limit and self.found is None:
            object.__setattr__(self, "found", self.current)

    @property
    def done(self) -> bool:
        return self.found is not None

    @property
    def validated(self) -> float:
        """The highest rate known to deliver without delay so far."""
        if self.found is not None:
            return self.found
        return self.rate - self.step if self.rate > self.current else self.current

    def observe(self, wait: float) -> RateSearch:
        """The probe at ``rate`` measured ``wait`` (s): the next state of the search."""
        if self.done:
            return self
        probes = self.probes + ((self.rate, wait),)
        if wait > self.threshold:
            return replace(self, found=self.validated, probes=probes)
        if self.rate >= self.limit:
            return replace(self, found=self.rate, probes=probes)
        return replace(self, rate=min(self.rate + self.step, self.limit), probes=probes)


def refine_rate(search: RateSearch, measure: Callable[[float], float]) -> RateSearch:
    """Run the search to its end with ``measure(rate) -> wait`` (s)."""
    while not search.done:
        search = search.observe(measure(search.rate))
    return search


def behavior_rates(
    program: Program, found: Mapping[str, float], *, back_off: float = 0.0
) -> dict[str, dict[str, float]]:
    """Fig. 5, Steps 2 and 4: each behavior's rate, robot -> behavior -> Hz.

    ``found``: the rates the searches found, keyed ``ROBOT.BEHAVIOR`` (the search of that
    behavior: its trigger sensor under its command load, `Architecture.behavior_searches`)
    or ``ROBOT.SENSOR`` (a search watching that sensor, e.g. online; a key ``ROBOT`` stands
    for all of that robot's sensors). A behavior gets its own rate, else the rate of the
    sensor that triggers its event; one with neither (triggered by another robot's event)
    gets its robot's lowest found rate; behaviors that run in parallel share the lowest rate of
    their group (one command stream). ``back_off`` is subtracted from every rate, which
    never goes below the behavior's current one; behaviors left at their current rate are
    not named (nothing to apply)."""
    out: dict[str, dict[str, float]] = {}
    for r in program.robots:
        own = {k.partition(".")[2]: v for k, v in found.items() if k.partition(".")[0] == r.name}
        if not own:
            continue
        lowest = min(own.values())
        wanted = [
            own.get(b.name, own.get(b.event.sensor or "", own.get("", lowest))) for b in r.behaviors
        ]
        rates: dict[str, float] = {}
        for group in r.groups():
            rate = min(wanted[i] for i in group) - back_off
            for i in group:
                b = r.behaviors[i]
                if rate > program.rate(b) + 1e-9:
                    rates[b.name] = rate
        if rates:
            out[r.name] = rates
    return out


SCALES = ("base", "all")


def apply_rate(
    program: Program,
    robot: str,
    rate: float | Mapping[str, float],
    *,
    scale: str = "base",
) -> Program:
    """Step 3: robot ``robot``'s behaviors command at ``rate`` (one rate, or behavior name
    -> rate as Fig. 5 finds them per behavior; behaviors not named keep theirs).

    ``scale="base"`` is the paper's Step 3 ("if the behavior involves movement of the robot
    base, the speed of the robot base is adjusted according to the percentage rate at which
    the P rate was modified", §3.3): a base behavior's speed scales by the ratio of its new
    rate to its old one; the arm's and gripper's speeds stay (each command moves them a
    smaller step). A base motion that runs in parallel with another section's keeps its
    speed: the speed adjustment (Fig. 6(c)) made it end with the other, which the rate does
    not speed up, and a faster base would arrive before, e.g., its fork is down (our
    reading; measured in Task 4: the approach at 2.3 times its speed drove the raised lever
    into the chair). ``scale="all"`` scales every section's speed (the step per command is
    kept): an option of ours, reported beside the paper's."""
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {SCALES}, got {scale!r}")
    r = program.robot(robot)
    tied = {  # base motions in a group with another section: Fig. 6(c) ended them together
        i
        for group in r.groups()
        if len({r.behaviors[j].section for j in group}) > 1
        for i in group
        if r.behaviors[i].section == "base"
    }
    for i, b in enumerate(r.behaviors):
        new_rate = rate.get(b.name) if isinstance(rate, Mapping) else rate
        if new_rate is None:
            continue
        ratio = new_rate / program.rate(b)
        scaled = scale == "all" or (b.section == "base" and i not in tied)
        speed = b.motion.speed * ratio if scaled else b.motion.speed
        motion = replace(b.motion, speed=speed)
        program = program.with_behavior(robot, i, replace(b, rate_hz=new_rate, motion=motion))
    return program
