"""Propositions of BT properties: what a state of an execution is labelled with.

A state is an (executor, world) pair after a tick (`tamp.verification.bt.explore`). Unknown
names are bad input (``--property``).

- flags: ``goal`` (the tree returned SUCCESS: every goal of C_goal reached in order),
  ``failed`` (the executor stopped with FAILURE), ``running``, ``action_failed`` (a skill
  failed in the last tick), ``holding`` (the hand holds an object), ``placed_in_occupied``
  (the last tick placed an object into an area that already held another one); the two
  per-tick ones are the `SymbolicWorld`'s per-tick record;
- counters usable in comparisons: ``holding_count`` (objects held), ``objects_in_<area>``;
- ground predicates written as quoted propositions, e.g. ``"IsObjectAt(O1, L1)"``,
  ``"IsGraspedObject(Oa)"`` (SMP-MRO §V-A2), parsed with `tamp.world.events.parse_call`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

from tamp.errors import InputError
from tamp.ltl.formula import COMPARISON_AP
from tamp.world.events import parse_call
from tamp.world.interface import Status
from tamp.world.predicates import PREDICATES, IsRobotCloseTo, Predicate
from tamp.world.state import WorldState
from tamp.world.symbolic import SymbolicWorld

DEFAULT_PROPERTIES = ("G !placed_in_occupied", "G (holding_count <= 1)", "F goal")
FLAGS = ("goal", "failed", "running", "action_failed", "holding", "placed_in_occupied")
COUNTERS = ("holding_count",)

#: label function of one proposition: (executor, world) -> truth
Evaluator = Callable[[object, SymbolicWorld], bool]


def parse_ground_predicate(text: str) -> Predicate | None:
    """``"IsObjectAt(O1, L1)"`` -> the predicate; None when ``text`` is not one."""
    if "(" not in text:
        return None
    try:
        name, args = parse_call(text, field="--property")
    except InputError:
        return None
    if name not in PREDICATES:
        return None
    cls, kinds = PREDICATES[name]
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

    def __init__(self, aps: Sequence[str], state: WorldState, appearing: Iterable[str] = ()):
        #: names a property may mention: the objects and areas of the initial state and the
        #: objects that appear during the run; any other name is bad input (exit 2)
        self.known = set(state.objects) | set(state.areas) | set(appearing)
        self.areas = set(state.areas)
        self.evals: dict[str, Evaluator] = {ap: self._compile(ap, state) for ap in aps}

    def label(self, executor, world: SymbolicWorld) -> frozenset[str]:
        return frozenset(ap for ap, ev in self.evals.items() if ev(executor, world))

    def _compile(self, ap: str, state: WorldState) -> Evaluator:
        if ap in FLAGS:
            return lambda e, w, name=ap: _flag(name, e, w)
        m = COMPARISON_AP.match(ap)
        if m:
            counter, op, value = m.group(1), m.group(2), int(m.group(3))
            get = _counter(counter)
            if get is None:
                raise _unknown(ap)
            area = counter[len("objects_in_") :] if counter.startswith("objects_in_") else None
            if area is not None and area not in self.areas:
                raise _unknown_name(ap, area, "area", self.areas)
            return lambda e, w: _compare(get(w.state), op, value)
        pred = parse_ground_predicate(ap)
        if pred is not None:
            _, args = parse_call(ap, field="--property")
            for arg in args:
                if arg not in self.known and not _is_number(arg):
                    raise _unknown_name(ap, arg, "object or area", self.known)
            return lambda e, w: _safe_holds(pred, w.state)
        raise _unknown(ap)


def _counter(name: str) -> Callable[[WorldState], int] | None:
    if name == "holding_count":
        return lambda s: 0 if s.held is None else 1
    if name.startswith("objects_in_"):
        area = name[len("objects_in_") :]
        return lambda s: len(s.objects_in(s.area(area))) if area in s.areas else 0
    return None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _unknown_name(ap: str, name: str, kind: str, known: Iterable[str]) -> InputError:
    return InputError(
        f"{ap!r} names an unknown {kind} {name!r} (known: {', '.join(sorted(known))})",
        field="--property",
    )


def _unknown(ap: str) -> InputError:
    return InputError(
        f"unknown proposition {ap!r} (known: {', '.join(FLAGS)}; counters "
        f"{', '.join(COUNTERS)}, objects_in_<area> in comparisons like "
        "'holding_count <= 1'; predicates such as \"IsObjectAt(O1, L1)\")",
        field="--property",
    )


def _flag(name: str, e, w: SymbolicWorld) -> bool:
    if name == "goal":
        return e.result is Status.SUCCESS
    if name == "failed":
        return e.result is Status.FAILURE
    if name == "running":
        return e.result is None
    if name == "action_failed":
        return w.action_failed
    if name == "holding":
        return w.state.held is not None
    if name == "placed_in_occupied":
        return w.placed_in_occupied
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
