"""Which events must fire before which: the partial order a program imposes on its events.

A behavior starts after the gating event of its robot's previous group, the events its
group waits for, and the event of any earlier behavior on the same section that may still
be running (a section executes one motion at a time). Its event fires after it starts and,
for ``after`` triggers, after the named event. Every execution fires the events in some
linear extension of this order, so:

- a cycle means some event can never fire (`check_can_finish` raises `InfeasibleError`);
- the executions' event sequences are the paths through the *downsets* of the order
  (`downsets`): the states a model checker explores to prove an LTL ordering property of
  every execution before any simulation (Step 2's safety, in `tamp.verification.refine`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator

from tamp.errors import InfeasibleError
from tamp.refine.program import Program, RobotProgram, event_id

#: More program states than this and the exhaustive check is refused (never in practice:
#: two chains of 10 events have 121).
MAX_STATES = 200_000


def start_predecessors(r: RobotProgram, i: int) -> set[str]:
    """Events that must have fired before behavior ``i`` of ``r`` starts (direct)."""
    groups = r.groups()
    k = next(j for j, g in enumerate(groups) if i in g)
    preds: set[str] = set()
    if k > 0:
        preds.add(event_id(r.name, r.behaviors[groups[k - 1][-1]].name))
    for j in groups[k]:
        preds.update(r.behaviors[j].waits_for)
    section = r.behaviors[i].section
    for j in range(groups[k][0]):
        if r.behaviors[j].section == section and not r.gating(j):
            preds.add(event_id(r.name, r.behaviors[j].name))
    return preds


def direct_predecessors(program: Program) -> dict[str, set[str]]:
    """Event id -> the events that must fire before it (direct precedences only)."""
    out: dict[str, set[str]] = {}
    for r in program.robots:
        for i, b in enumerate(r.behaviors):
            preds = start_predecessors(r, i)
            if b.event.after is not None:
                preds.add(b.event.after)
            out[event_id(r.name, b.name)] = preds
    return out


def _cycle(preds: dict[str, set[str]]) -> list[str] | None:
    """One cycle of the precedence graph, or None."""
    colour: dict[str, int] = {}
    stack: list[str] = []

    def visit(e: str) -> list[str] | None:
        colour[e] = 1
        stack.append(e)
        for p in sorted(preds[e]):
            if colour.get(p) == 1:
                return stack[stack.index(p) :] + [p]
            if p not in colour:
                found = visit(p)
                if found:
                    return found
        stack.pop()
        colour[e] = 2
        return None

    for e in preds:
        if e not in colour:
            found = visit(e)
            if found:
                return found
    return None


def precedence(program: Program) -> dict[str, frozenset[str]]:
    """Event id -> every event that must fire before it (transitive closure)."""
    preds = direct_predecessors(program)
    cyc = _cycle(preds)
    if cyc is not None:
        raise InfeasibleError(
            "the program cannot finish: events wait for each other in a cycle: "
            + " needs ".join(reversed(cyc))
        )
    closed: dict[str, frozenset[str]] = {}

    def close(e: str) -> frozenset[str]:
        if e not in closed:
            acc: set[str] = set()
            for p in preds[e]:
                acc.add(p)
                acc |= close(p)
            closed[e] = frozenset(acc)
        return closed[e]

    for e in preds:
        close(e)
    return closed


def check_can_finish(program: Program) -> None:
    """`InfeasibleError` with the reason when some event can never fire."""
    precedence(program)
    for r in program.robots:
        for b in r.behaviors:
            t, m = b.event, b.motion
            if t.sensor == "odometry" and t.value > abs(m.amount) + 1e-12:
                raise InfeasibleError(
                    f"the program cannot finish: {event_id(r.name, b.name)} ends when odometry "
                    f"reaches {t.value:g} but its motion covers only {abs(m.amount):g}"
                )


def downsets(program: Program) -> tuple[list[frozenset[str]], list[list[int]]]:
    """The states of all executions: sets of fired events closed under precedence, and the
    successors of each (one more event fired). State 0 is the empty set; the full set has
    no successor."""
    prec = precedence(program)
    events = program.events()
    index: dict[frozenset[str], int] = {frozenset(): 0}
    states: list[frozenset[str]] = [frozenset()]
    succ: list[list[int]] = [[]]
    todo = deque([0])
    while todo:
        s = todo.popleft()
        fired = states[s]
        for e in events:
            if e in fired or not prec[e] <= fired:
                continue
            nxt = fired | {e}
            j = index.get(nxt)
            if j is None:
                if len(states) >= MAX_STATES:
                    raise InfeasibleError(
                        f"more than {MAX_STATES} program states: the ordering check is refused"
                    )
                j = index[nxt] = len(states)
                states.append(nxt)
                succ.append([])
                todo.append(j)
            succ[s].append(j)
    return states, succ


def linear_orders(program: Program, limit: int = 10_000) -> Iterator[list[str]]:
    """Every order in which the events can fire (at most ``limit`` of them)."""
    prec = precedence(program)
    events = program.events()
    count = 0

    def rec(fired: list[str], seen: set[str]) -> Iterator[list[str]]:
        nonlocal count
        if len(fired) == len(events):
            count += 1
            yield list(fired)
            return
        for e in events:
            if e not in seen and prec[e] <= seen and count < limit:
                fired.append(e)
                seen.add(e)
                yield from rec(fired, seen)
                fired.pop()
                seen.discard(e)

    yield from rec([], set())
