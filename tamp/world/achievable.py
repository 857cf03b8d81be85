"""Which goal conditions a robot's action templates can ever make true: a structural check
that runs before any search or model checking, so that an impossible task is refused with
its cause in the user's terms (a missing action), not with a temporal-logic counterexample.

SMP-MRO (Nakamura & Sekiyama, IEEE Access, §IV-C1, Alg. 3 ``GetAllActTemplatesFor``) grows
a tree for a goal condition from the action templates whose effects contain it; when no
template does, no tree can ever achieve it. The check is the delete-free relaxation of the
domain at the level of predicate names: a predicate is *possible* when some instance holds
at the start, when it is a consequence of others (no skill makes it true directly, e.g.
``IsAreaFree``), or when it is an effect of a *usable* template (all of whose preconditions
are possible). It over-approximates what the robot can do, so a goal it calls unachievable
is unachievable (the converse does not hold: the search still decides the rest).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import cast

from tamp.world.actions import Domain
from tamp.world.predicates import PREDICATES, IsRobotCloseTo, Predicate
from tamp.world.state import WorldState

#: Ground instances of one predicate tried at the start before it is assumed possible
#: (assuming more keeps the check sound; it only finds fewer unachievable goals).
MAX_INSTANCES = 10_000


@dataclass(frozen=True)
class Unachievable:
    """A goal condition no sequence of the domain's actions can make true, and why."""

    goal: Predicate
    reason: str


def _values(state: WorldState, kind: str) -> list[str]:
    objects = sorted(state.objects)
    areas = sorted(state.areas)
    kinds = sorted({o.kind for o in state.objects.values()})
    return {"object": objects, "area": areas, "place": objects + areas, "kind": kinds}[kind]


def _true_at_start(name: str, state: WorldState, reach: float) -> bool:
    """Some ground instance of predicate ``name`` holds in ``state`` (or too many to try)."""
    cls, kinds = PREDICATES[name]
    extra = (reach,) if cls is IsRobotCloseTo else ()
    domains = [_values(state, k) for k in kinds]
    count = 1
    for d in domains:
        count *= len(d)
    if count > MAX_INSTANCES:
        return True
    # the arguments are the names PREDICATES' kinds list (plus IsRobotCloseTo's reach): a
    # call a type checker cannot match to each class's fields
    make = cast(Callable[..., Predicate], cls)
    return any(make(*args, *extra).holds(state) for args in itertools.product(*domains))


def possible_predicates(domain: Domain, state: WorldState) -> set[str]:
    """Predicate names that may become true from ``state`` (the relaxation above)."""
    possible = {
        name
        for name, (cls, _) in PREDICATES.items()
        if cls.achieve is Predicate.achieve or _true_at_start(name, state, domain.reach)
    }
    changed = True
    while changed:
        changed = False
        for t in domain.templates.values():
            if all(c.predicate in possible for c in t.con):
                new = {e.predicate for e in t.eff} - possible
                if new:
                    possible |= new
                    changed = True
    return possible


def unachievable_goals(
    domain: Domain, goals: Iterable[Predicate], state: WorldState
) -> list[Unachievable]:
    """The goal conditions that no action template of ``domain`` can make true from
    ``state``, each with the reason (no template has it as an effect, or every template
    that has needs a condition nothing makes true). Goals true at the start are fine."""
    possible: set[str] | None = None
    out: list[Unachievable] = []
    for goal in goals:
        if goal.holds(state):
            continue
        achievers = [t for t in domain.templates.values() if t.bindings_achieving(goal)]
        if not achievers:
            out.append(
                Unachievable(
                    goal,
                    f"no action template of {domain.source} has {goal.name} among its effects "
                    f"(templates: {', '.join(domain.templates) or 'none'})",
                )
            )
            continue
        if possible is None:
            possible = possible_predicates(domain, state)
        missing = {
            t.name: sorted({str(c) for c in t.con if c.predicate not in possible})
            for t in achievers
        }
        if all(missing.values()):
            needs = "; ".join(f"{n} needs {', '.join(m)}" for n, m in missing.items())
            out.append(
                Unachievable(
                    goal,
                    f"the templates that achieve {goal.name} can never run ({needs}: no "
                    f"template of {domain.source} makes that true and it is false at the start)",
                )
            )
    return out
