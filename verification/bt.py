"""Every execution of a grown behavior tree, explored explicitly and model-checked.

SMP-MRO grows its tree at run time (§IV-C, Alg. 2-3), so what must be verified is the
*executor* (`tamp.bt.PaBtExecutor`: tree + growth rules), not one static tree. The
exploration runs the real executor object, tick by tick, against `BranchingWorld`, a
symbolic `World` in which every skill takes one tick and then either succeeds (effects
applied, §IV-C1 ``a.eef``) or fails (state unchanged). Each tick is replayed from a deep
copy of (executor, world) once per combination of skill outcomes, so the explored graph
holds every execution the executor can produce. A state is the pair (world state, tree
snapshot: node kinds, statuses, cursors, failure counts, running skill, growth counters);
equal snapshots are merged, which makes the graph finite and the count meaningful.

Choices written down here:
- Failures are bounded: at most ``max_failures`` skill failures per execution (default 1).
  With unbounded failures no controller reaches its goal on every path (a skill can fail
  forever); the executor's own retry limit still applies inside that budget.
- Scripted interference uses `tamp.world.symbolic`'s `Appear` and `Move` events: an object
  appears when the robot first comes within reach of it (Case 3's O_a at l_1), or at a
  given tick; a person moves an object at a given tick.
- The exploration is bounded by ``max_states``; when the bound is hit the verdict says so
  and a holding verdict is only "no violation among the explored states". The states left
  unexpanded at the bound are not dead ends (`TransitionSystem.unexpanded`): a path that
  stops there is a counterexample only when it is already a bad prefix (see
  `verification.kripke`), never merely because the exploration stopped.

Propositions available to properties (labels of a state; unknown names are bad input):
``goal`` (the tree returned SUCCESS: every goal of C_goal reached in order), ``failed``
(the executor stopped with FAILURE), ``running``, ``action_failed`` (a skill failed in the
last tick), ``holding`` (the hand holds an object), ``placed_in_occupied`` (the last tick
placed an object into an area that already held another one), counters usable in
comparisons — ``holding_count`` (objects held), ``objects_in_<area>`` — and ground
predicates written as quoted propositions, e.g. ``"IsObjectAt(O1, L1)"``,
``"IsGraspedObject(Oa)"`` (SMP-MRO §V-A2).
"""

from __future__ import annotations

import copy
import re
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import spot

from tamp.errors import InputError
from tamp.world.actions import Action
from tamp.world.geometry import Area, Point, Pose
from tamp.world.interface import Status
from tamp.world.predicates import (
    DEFAULT_REACH,
    PREDICATES,
    IsObjectAt,
    IsRobotCloseTo,
    Predicate,
)
from tamp.world.state import WorldState
from verification import ltl
from verification.kripke import TransitionSystem, model_check
from verification.verdict import Report, Verdict

DEFAULT_PROPERTIES = ("G !placed_in_occupied", "G (holding_count <= 1)", "F goal")
FLAGS = ("goal", "failed", "running", "action_failed", "holding", "placed_in_occupied")
COUNTERS = ("holding_count",)
_PRED = re.compile(r"^\s*([A-Za-z_]\w*)\s*\(\s*([^()]*)\)\s*$")


# -- the branching world ----------------------------------------------------------------------


@dataclass
class _Skill:
    action: Action
    started: int
    status: Status = Status.RUNNING
    applicable: bool = True


class BranchingWorld:
    """`World` whose skill outcomes come from a choice list (SUCCESS when exhausted).

    ``choices`` is consumed by the skills that finish in this tick; ``decisions`` records
    every outcome used, so the explorer can branch on each of them. A skill started at
    clock ``c`` finishes at its first poll with clock > ``c``; a skill whose preconditions
    do not hold fails without a choice (deterministically).
    """

    def __init__(
        self,
        state: WorldState,
        *,
        events: Iterable = (),
        may_fail: Iterable[str] | None = None,
        failures_left: int = 1,
        reach: float = DEFAULT_REACH,
    ) -> None:
        self.state = state
        self.clock = 0
        self.events = list(events)
        self.may_fail = None if may_fail is None else frozenset(may_fail)
        self.failures_left = failures_left
        self.reach = reach
        self.skills: dict[int, _Skill] = {}
        self.running: int | None = None
        self.next_handle = 1
        self.choices: list[Status] = []
        self.decisions: list[Status] = []
        self.last_failed = False
        self.last_placed_in_occupied = False
        self.tick_events: list[str] = []

    # World protocol
    def observe(self) -> WorldState:
        return self.state

    def start(self, action: Action) -> int:
        if self.running is not None:
            raise RuntimeError(f"cannot start {action}: another skill is running")
        h = self.next_handle
        self.next_handle += 1
        self.skills = {h: _Skill(action, self.clock, applicable=action.applicable(self.state))}
        self.running = h
        self.tick_events.append(f"start {action}")
        return h

    def poll(self, handle: int) -> Status:
        sk = self.skills.get(handle)
        if sk is None:
            return Status.FAILURE
        if sk.status is not Status.RUNNING:
            return sk.status
        if not sk.applicable or not sk.action.applicable(self.state):
            return self._finish(sk, Status.FAILURE)
        if self.clock <= sk.started:
            return Status.RUNNING
        can_fail = self.failures_left > 0 and (
            self.may_fail is None or sk.action.name in self.may_fail
        )
        outcome = Status.SUCCESS
        if can_fail:
            k = len(self.decisions)
            outcome = self.choices[k] if k < len(self.choices) else Status.SUCCESS
            self.decisions.append(outcome)
        if outcome is Status.FAILURE:
            self.failures_left -= 1
            return self._finish(sk, Status.FAILURE)
        before = self.state
        self.state = sk.action.apply(self.state)
        if sk.action.name == "Place" and len(sk.action.args) == 2:
            obj, area = sk.action.args
            if area in before.areas and [
                o for o in self.state.objects_in(before.area(area)) if o != obj
            ]:
                self.last_placed_in_occupied = True
        return self._finish(sk, Status.SUCCESS)

    def cancel(self, handle: int) -> None:
        sk = self.skills.get(handle)
        if sk is not None and sk.status is Status.RUNNING:
            sk.status = Status.FAILURE
            self.tick_events.append(f"cancel {sk.action}")
        if self.running == handle:
            self.running = None

    def add_area(self, area: Area) -> None:
        if area.name not in self.state.areas:
            self.state = self.state.with_area(area)

    def step(self) -> None:
        """Advance the clock one tick, fire due interference, reset per-tick flags."""
        self.clock += 1
        self.last_failed = False
        self.last_placed_in_occupied = False
        self.tick_events = []
        remaining = []
        for ev in self.events:
            at = getattr(ev, "at_tick", None)
            due = (
                self.clock >= at
                if at is not None
                else self.state.robot.pos.planar_distance(ev.pos) <= self.reach + 1e-9
            )
            if due:
                self._fire(ev)
            else:
                remaining.append(ev)
        self.events = remaining

    def _fire(self, ev) -> None:
        old = self.state.objects.get(ev.obj)
        orientation = old.pose.orientation if old else Pose.at(0, 0).orientation
        state = self.state
        if state.held == ev.obj:
            state = state.with_held(None)
        self.state = state.with_object_at(ev.obj, Pose(ev.pos, orientation))
        verb = "appears" if type(ev).__name__ == "Appear" else "is moved"
        self.tick_events.append(f"{ev.obj} {verb} at ({ev.pos.x:g}, {ev.pos.y:g})")

    def _finish(self, sk: _Skill, status: Status) -> Status:
        sk.status = status
        self.tick_events.append(f"{sk.action} -> {status.value}")
        if self.running is not None and self.skills.get(self.running) is sk:
            self.running = None
        if status is Status.FAILURE:
            self.last_failed = True
        return status

    def fingerprint(self) -> tuple:
        s = self.state
        timed = any(getattr(ev, "at_tick", None) is not None for ev in self.events)
        running = self.skills.get(self.running) if self.running is not None else None
        return (
            _state_key(s),
            str(running.action) if running else None,
            self.failures_left,
            tuple(repr(ev) for ev in self.events),
            self.clock if timed else None,
        )


def _state_key(s: WorldState) -> tuple:
    return (
        (round(s.robot.pos.x, 6), round(s.robot.pos.y, 6), round(s.robot.orientation.yaw(), 6)),
        s.held,
        tuple(
            sorted((k, tuple(round(v, 6) for v in o.pos.as_tuple())) for k, o in s.objects.items())
        ),
        tuple(sorted(s.areas)),
    )


# -- executor snapshots -------------------------------------------------------------------------

_SKIP = {"uid", "parent", "children", "tick_id", "status", "__weakref__", "key", "pred", "action"}


def _freeze(v):
    if isinstance(v, list | tuple):
        return tuple(_freeze(x) for x in v)
    if isinstance(v, dict):
        return tuple(sorted((str(k), _freeze(x)) for k, x in v.items()))
    if isinstance(v, int | float | str | bool | type(None)):
        return v
    return str(v)


_SLOTS: dict[type, tuple[str, ...]] = {}
_PLAIN = (int, float, str, bool, type(None))


def _slots_of(cls: type) -> tuple[str, ...]:
    names = _SLOTS.get(cls)
    if names is None:
        names = tuple(
            slot
            for klass in cls.__mro__
            for slot in getattr(klass, "__slots__", ())
            if slot not in _SKIP
        )
        _SLOTS[cls] = names
    return names


def tree_fingerprint(executor) -> tuple:
    """Structure and execution state of the executor's tree, without tick numbers."""
    nodes = []
    tick = executor.tick_id
    for n in executor.root.walk():
        values = []
        for slot in _slots_of(type(n)):
            v = getattr(n, slot, None)
            if slot == "handle":
                v = v is not None
            elif not isinstance(v, _PLAIN):
                v = _freeze(v)
            values.append(v)
        nodes.append(
            (
                type(n).__name__,
                n.describe(),
                len(n.children),
                None if n.status is None else n.status.value,
                n.tick_id == tick,
                tuple(values),
            )
        )
    running = executor.running.describe() if executor.running is not None else None
    completed = getattr(executor, "_completed_from", {})
    try:
        completed_key = frozenset(completed.items())
    except TypeError:  # unhashable keys: fall back to a canonical text form
        completed_key = _freeze(dict(completed))
    return (
        tuple(nodes),
        None if executor.result is None else executor.result.value,
        running,
        # growth bookkeeping that changes what the executor does next (livelock and
        # fruitless-growth limits, expansion budget, reserved free areas)
        completed_key,
        getattr(executor, "_fruitless", 0),
        executor.stats.expansions,
        tuple(getattr(executor, "reserved", ())),
        tuple(sorted(getattr(executor, "extra_areas", {}))),
    )


# -- labels ---------------------------------------------------------------------------------------


def _parse_pred(name: str) -> Predicate | None:
    m = _PRED.match(name)
    if not m or m.group(1) not in PREDICATES:
        return None
    cls, kinds = PREDICATES[m.group(1)]
    args = [a.strip() for a in m.group(2).split(",") if a.strip()]
    if cls is IsRobotCloseTo:
        if len(args) == 1:
            return IsRobotCloseTo(args[0])
        if len(args) == 2:
            try:
                return IsRobotCloseTo(args[0], float(args[1]))
            except ValueError:
                return None
        return None
    if len(args) != len(kinds):
        return None
    return cls(*args)


class Labeller:
    """Truth of each proposition a property uses, on (executor, world) after a tick."""

    def __init__(self, aps: Sequence[str], state: WorldState):
        self.evals = {}
        for ap in aps:
            self.evals[ap] = self._compile(ap, state)

    def _compile(self, ap: str, state: WorldState):
        if ap in FLAGS:
            return lambda e, w, name=ap: _flag(name, e, w)
        m = ltl.COMPARISON_AP.match(ap)
        if m:
            counter, op, value = m.group(1), m.group(2), int(m.group(3))
            get = self._counter(counter, state)
            if get is None:
                raise self._unknown(ap, state)
            return lambda e, w: _compare(get(w.state), op, value)
        pred = _parse_pred(ap)
        if pred is not None:
            return lambda e, w: _safe_holds(pred, w.state)
        raise self._unknown(ap, state)

    @staticmethod
    def _counter(name: str, state: WorldState):
        if name == "holding_count":
            return lambda s: 0 if s.held is None else 1
        if name.startswith("objects_in_"):
            area = name[len("objects_in_") :]
            return lambda s: len(s.objects_in(s.area(area))) if area in s.areas else 0
        return None

    @staticmethod
    def _unknown(ap: str, state: WorldState) -> InputError:
        return InputError(
            f"unknown proposition {ap!r} (known: {', '.join(FLAGS)}; counters "
            f"{', '.join(COUNTERS)}, objects_in_<area> in comparisons like "
            "'holding_count <= 1'; predicates such as \"IsObjectAt(O1, L1)\")",
            field="--property",
        )

    def label(self, executor, world: BranchingWorld) -> frozenset[str]:
        return frozenset(ap for ap, ev in self.evals.items() if ev(executor, world))


def _flag(name: str, e, w: BranchingWorld) -> bool:
    if name == "goal":
        return e.result is Status.SUCCESS
    if name == "failed":
        return e.result is Status.FAILURE
    if name == "running":
        return e.result is None
    if name == "action_failed":
        return w.last_failed
    if name == "holding":
        return w.state.held is not None
    if name == "placed_in_occupied":
        return w.last_placed_in_occupied
    raise KeyError(name)


def _compare(a: int, op: str, b: int) -> bool:
    return {
        "<=": a <= b,
        ">=": a >= b,
        "==": a == b,
        "!=": a != b,
        "<": a < b,
        ">": a > b,
    }[op]


def _safe_holds(pred: Predicate, state: WorldState) -> bool:
    try:
        return pred.holds(state)
    except KeyError:  # an object or area that does not exist (yet) in this state
        return False


# -- exploration --------------------------------------------------------------------------------


@dataclass
class Exploration:
    system: TransitionSystem
    complete: bool
    terminal: int
    ticks: int


def explore(
    executor,
    state: WorldState,
    aps: Sequence[str],
    *,
    events: Iterable = (),
    may_fail: Iterable[str] | None = None,
    max_failures: int = 1,
    max_states: int = 50_000,
) -> Exploration:
    """Breadth-first over every execution of ``executor`` from ``state`` (see module doc)."""
    labeller = Labeller(aps, state)
    world = BranchingWorld(state, events=events, may_fail=may_fail, failures_left=max_failures)
    exe = copy.deepcopy(executor)
    ts = TransitionSystem()
    index: dict[tuple, int] = {}

    def add(e, w, how: str) -> tuple[int, bool]:
        label = labeller.label(e, w)
        key = (
            tree_fingerprint(e),
            w.fingerprint(),
            label,
            w.last_failed,
            w.last_placed_in_occupied,
        )
        if key in index:
            return index[key], False
        i = ts.add_state(label, how)
        index[key] = i
        return i, True

    root, _ = add(exe, world, "start")
    ts.init = root
    queue = deque([(root, exe, world)])
    complete = True
    terminal = 0
    ticks = 0
    while queue:
        i, e, w = queue.popleft()
        if e.result is not None:
            terminal += 1
            continue
        pending: list[list[Status]] = [[]]
        while pending:
            choices = pending.pop()
            e2, w2 = _copy_pair(e, w)
            w2.choices = list(choices)
            w2.decisions = []
            w2.step()
            e2.tick(w2)
            ticks += 1
            for k in range(len(choices), len(w2.decisions)):
                pending.append(w2.decisions[:k] + [Status.FAILURE])
            how = _describe_tick(w, w2, e2, choices)
            j, new = add(e2, w2, how)
            ts.add_edge(i, j)
            if new:
                if ts.num_states >= max_states:
                    complete = False
                    ts.unexpanded = {j, *(q[0] for q in queue)}
                    queue.clear()
                    break
                queue.append((j, e2, w2))
    return Exploration(ts, complete, terminal, ticks)


def _copy_pair(e, w: BranchingWorld):
    """Deep copy of (executor, world) sharing the immutable parts (actions, states).

    The executor's report-only history (growth log, closed action records) is dropped
    from the copies: it never influences a tick, and copying it made each step O(depth).
    """
    e.log = []
    e.attempts = [r for r in e.attempts if r.status is None]
    memo: dict[int, object] = {id(w.state): w.state}
    for r in e.attempts:
        memo[id(r.action)] = r.action
    for sk in w.skills.values():
        memo[id(sk.action)] = sk.action
    return copy.deepcopy((e, w), memo)


def _describe_tick(before: BranchingWorld, after: BranchingWorld, e, choices) -> str:
    parts = list(after.tick_events)
    if choices and Status.FAILURE in choices:
        parts.append("(outcome chosen: failure)")
    if e.result is not None:
        parts.append(f"tree {e.result.value}" + (f" ({e.reason})" if e.reason else ""))
    return "; ".join(parts) if parts else "tick"


# -- checking ------------------------------------------------------------------------------------


def check_executor(
    executor,
    state: WorldState,
    properties: Sequence[str | spot.formula] = DEFAULT_PROPERTIES,
    *,
    events: Iterable = (),
    may_fail: Iterable[str] | None = None,
    max_failures: int = 1,
    max_states: int = 50_000,
    subject: str = "BT",
) -> Report:
    """Model-check every explored execution of ``executor`` against each property."""
    formulas = [
        p if isinstance(p, spot.formula) else ltl.parse_formula(p, field="--property")
        for p in properties
    ]
    aps = sorted({a for f in formulas for a in ltl.ap_names(f)})
    ex = explore(
        executor,
        state,
        aps,
        events=events,
        may_fail=may_fail,
        max_failures=max_failures,
        max_states=max_states,
    )
    bound = "" if ex.complete else f", BOUNDED at {max_states} states"
    name = (
        f"{subject} ({ex.system.num_states} states, {ex.system.num_edges} transitions, "
        f"≤{max_failures} failure(s){bound})"
    )
    verdicts: list[Verdict] = []
    for f in formulas:
        verdicts.append(model_check(ex.system, f, subject=name))
    return Report(verdicts, explored=ex.system.num_states)


def executor_for(demo, order: Sequence[str] | None = None, *, domain=None):
    """A fresh `PaBtExecutor` for a demonstration's order (``tamp plan``'s when None)."""
    from tamp.bt import PaBtExecutor

    if order is None:
        from tamp.rg import plan

        order = plan(demo).order
    c_goal = [IsObjectAt(demo.goal(g).object, demo.goal(g).area.name) for g in order]
    return PaBtExecutor(c_goal, domain or demo.domain(), free_areas=list(demo.free_areas))


def appear_event(obj: str, where: Point, at_tick: int | None = None):
    from tamp.world.symbolic import Appear

    return Appear(obj, where, at_tick)


def move_event(obj: str, where: Point, at_tick: int):
    from tamp.world.symbolic import Move

    return Move(obj, where, at_tick)
