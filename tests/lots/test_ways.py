"""Issue 17, LOTS completes what Theorem 1 promises: every accepting way is considered.

An independent brute-force oracle explores the product of the count abstraction (W^B counts,
objects that exist) and the Büchi automaton with plain sets, no pruning and no minimality:

* a *round* of the task from an empty W^B is a prefix to an accepting state ``q_F`` and
  one non-empty cycle back to ``q_F``; a step is ∅, a delivery ``{p}`` of an object still in
  W^A, or — when every object of p's class is in W^B — taking one out (∅) and delivering it
  again (``{p}``); its *end* is W^B after the cycle; the ends that count are, per ``q_F``,
  the minimal ends of plain rounds and the redelivering ends minimal among all its ends;
* the task can be completed from ``(q, W^B)`` with ``cap`` objects per class when some
  sequence of ∅, deliveries and removals from W^B (∅) leads to a live accepting state whose
  W^B is the end of some round, W^B staying in the count abstraction (Lemma 1's box of the
  ends, and ``cap``).

Checked with hypothesis: the planner finds a plan from exactly the pairs the oracle accepts,
and the controller ends satisfied exactly when the oracle says the task could still be
completed after a person took objects away (else it exits 1 with the reason). Plus the two
regression cases: a way that delivers one object twice, and a recurring choice ``GF(p | q)``
whose planned class is taken away.
"""

from __future__ import annotations

import itertools
import json
import os
from collections import deque

from hypothesis import example, given, settings
from hypothesis import strategies as st

from tamp.commands.main import main
from tamp.errors import InfeasibleError
from tamp.lots.automaton import EMPTY
from tamp.lots.cell import objects_of, side_counts
from tamp.lots.controller import LotsController
from tamp.lots.person import actions_done
from tamp.lots.run import run_task
from tamp.lots.task import Event, Proposition, Task, load_events, load_task
from tamp.verification.lots import check_run_of

from .helpers import CLASSES, TWO_CLASSES, random_tasks, take_away, write_files

# -- the oracle -------------------------------------------------------------------------------


def _class_of(task: Task) -> dict[str, int]:
    idx = {c: i for i, c in enumerate(task.classes)}
    return {p.name: idx[p.cls] for p in task.propositions}


def _add(b: tuple, i: int, d: int) -> tuple:
    out = list(b)
    out[i] += d
    return tuple(out)


def oracle_round_ends(task: Task, aut, *, minimal: bool = True) -> set[tuple]:
    """The ends of every round of the task, by brute force: all of them (``minimal=False``),
    or the ones that count as ways: per accepting state ``q_F``, the minimal ends of its plain
    rounds (no object delivered twice) and the ends of its redelivering rounds that are
    minimal among all its ends (more in W^B by a round of the same kind through the same
    ``q_F`` is surplus, which the robot takes out)."""
    cls = _class_of(task)
    avail = tuple(task.initial_a.get(c, 0) + task.initial_b.get(c, 0) for c in task.classes)

    def succ(q, b, sat):
        out = {(n, b, sat) for n in aut.successors(q, EMPTY)}
        for p, i in cls.items():
            letter = frozenset({p})
            if b[i] < avail[i]:
                out |= {(n, _add(b, i, 1), sat) for n in aut.successors(q, letter)}
            elif avail[i] > 0:
                for m in aut.successors(q, EMPTY):
                    out |= {(n, b, True) for n in aut.successors(m, letter)}
        return out

    def closure(sources):
        seen, todo = set(sources), deque(sources)
        while todo:
            for nxt in succ(*todo.popleft()):
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    def mins(ends):
        return {e for e in ends if not any(f != e and all(map(int.__le__, f, e)) for f in ends)}

    reach = closure([(aut.initial, (0,) * len(avail), False)])
    out = set()
    for qf in aut.accepting:
        firsts = [n for (q, b, sat) in reach if q == qf for n in succ(q, b, sat)]
        ends = {(b, sat) for (q, b, sat) in closure(firsts) if q == qf}
        if not minimal:
            out |= {b for b, _ in ends}
            continue
        every = mins({b for b, _ in ends})
        out |= mins({b for b, sat in ends if not sat}) | {b for b, sat in ends if sat} & every
    return out


def oracle_can_complete(task: Task, aut, ends: set, q: int, b: tuple, cap: tuple) -> bool:
    """Some ∅ / delivery / removal sequence from (q, b) reaches a live accepting state whose
    W^B is a round's end, with W^B inside the count abstraction: at most ``cap`` objects of a
    class, and at most Lemma 1's n' (the componentwise maximum of the ends)."""
    cls = _class_of(task)
    box = tuple(max(e[i] for e in ends) for i in range(len(b))) if ends else (0,) * len(b)
    cap = tuple(map(min, cap, box))
    # live accepting: on a cycle of executable letters (∅ or one proposition)
    letters = [EMPTY, *(frozenset({p}) for p in cls)]

    def on_cycle(f):
        seen, todo = set(), [f]
        while todo:
            x = todo.pop()
            for letter in letters:
                for n in aut.successors(x, letter):
                    if n == f:
                        return True
                    if n not in seen:
                        seen.add(n)
                        todo.append(n)
        return False

    live = {f for f in aut.accepting if on_cycle(f)}
    seen, todo = {(q, b)}, deque([(q, b)])
    while todo:
        x, w = todo.popleft()
        if x in live and w in ends:
            return True
        nxt = {(n, w) for n in aut.successors(x, EMPTY)}
        for p, i in cls.items():
            if w[i] < cap[i]:
                nxt |= {(n, _add(w, i, 1)) for n in aut.successors(x, frozenset({p}))}
        for i, k in enumerate(w):
            if k:
                nxt |= {(n, _add(w, i, -1)) for n in aut.successors(x, EMPTY)}
        for y in nxt - seen:
            seen.add(y)
            todo.append(y)
    return False


# -- regression cases -------------------------------------------------------------------------

TWICE = """version: 1
name: twice
formula: "F(p & F(q & F p)) | F r"
actions: {return: true}   # the way 'p q p' delivers one cup twice: our return action
propositions:
  p: {class: cup}
  q: {class: mug}
  r: {class: jar}
initial:
  A: {cup: 1, mug: 1, jar: 1}
"""
CHOICE = TWO_CLASSES.format(name="choice", formula="GF(p | q)")
_take, _files = take_away, write_files


def test_a_way_that_delivers_one_object_twice_is_taken_when_the_planned_one_is_gone(
    tmp_path, capsys
):
    f = _files(tmp_path, task=TWICE, take=_take("jar"))
    task = load_task(f["task"])
    plain = run_task(task)
    assert plain.satisfied and [a.key() for a in plain.actions] == [("move", "r")]
    lots = plain.controller.lots
    # the way p, q, p with one cup ends with cup and mug in W^B (classes: cup, mug, jar)
    assert lots.classes == ("cup", "mug", "jar")
    assert set(lots.goals) == {(0, 0, 1), (1, 1, 0)}
    report = run_task(task, load_events(f["take"], task))
    assert report.satisfied, report.reason
    assert [a.key() for a in report.actions] == [
        ("move", "p"),
        ("move", "q"),
        ("remove", "cup"),
        ("move", "p"),
    ]
    assert report.actions[2].dest == "A"  # back to W^A: the way delivers it again
    assert report.counts()["B"] == {"cup": 1, "mug": 1}
    assert check_run_of(task, load_events(f["take"], task)).holds  # every table gated
    assert main(["lots", str(f["task"]), "--interference", str(f["take"])]) == 0
    assert "task satisfied" in capsys.readouterr().out


def test_a_recurring_choice_takes_the_other_class_when_the_planned_one_is_gone(tmp_path, capsys):
    f = _files(tmp_path, task=CHOICE, take=_take("cup"))
    task = load_task(f["task"])
    plain = run_task(task)
    assert [a.key() for a in plain.actions] == [("move", "p")]  # the cheaper class
    assert set(plain.controller.lots.goals) == {(1, 0), (0, 1)}
    report = run_task(task, load_events(f["take"], task))
    assert report.satisfied, report.reason
    assert [a.key() for a in report.actions] == [("move", "q")]
    assert check_run_of(task, load_events(f["take"], task)).holds
    assert main(["lots", str(f["task"]), "--interference", str(f["take"]), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["satisfied"] and data["final"]["B"] == {"mug": 1}
    # both classes gone: no way is left, exit 1 with the reason
    both = tmp_path / "both.yaml"
    both.write_text(_take("cup") + "  - {after: 0, kind: remove, class: mug, side: A}\n")
    assert main(["lots", str(f["task"]), "--interference", str(both)]) == 1
    assert "infeasible" in capsys.readouterr().out.lower()


# -- the property: planner and controller agree with the oracle -------------------------------

SHAPES = (
    "F {0} | F {1}",
    "GF({0} | {1})",
    "GF({0} | {1}) & GF {2}",
    "F({0} & F({1} & F {0})) | F {2}",
    "F({0} & X F {0}) | F {1}",
    "(F {0} | F {1}) & F {2}",
    "GF {0} & GF {1}",
    "F({0} & F {2}) | GF {1}",
)


def random_task():
    return random_tasks(SHAPES)


AROUND = "F(p0 & F p2) | GF p1"
PLAIN = "(F p0 & F p2) | F(p1 & F p2)"


def _task(formula, classes, a, b):
    props = tuple(Proposition(f"p{i}", c, cost) for i, (c, cost) in enumerate(classes))
    init_a, init_b = (dict(zip(CLASSES, n, strict=True)) for n in (a, b))
    return Task(formula, props, init_a, init_b, returns=True)


@settings(max_examples=int(os.environ.get("TAMP_WAYS_EXAMPLES", "40")), deadline=None)
@given(task=random_task())
# found by this test: a way through another accepting state whose end is above another way's
@example(_task(AROUND, [("cup", 1.0), ("cup", 1.0), ("mug", 2.0)], (0, 1, 0), (1, 0, 0)))
@example(_task(AROUND, [("mug", 1.0), ("cup", 1.0), ("jar", 1.0)], (0, 0, 1), (0, 1, 0)))
# a plain way (cup, mug) beside a redelivering one with a smaller end (the mug twice)
@example(_task(PLAIN, [("cup", 1.0), ("mug", 1.0), ("mug", 1.0)], (1, 0, 0), (1, 1, 0)))
def test_the_planner_plans_from_exactly_the_pairs_the_oracle_accepts(task):
    try:
        c = LotsController(task)
    except InfeasibleError:  # no round at all: the oracle finds no end either
        from tamp.lots.automaton import Automaton

        assert not oracle_round_ends(task, Automaton(task.formula, task.props))
        return
    ends = oracle_round_ends(task, c.aut)
    every = oracle_round_ends(task, c.aut, minimal=False)
    assert c.lots.final in every  # the planned round (from the true initial W^B) is a round
    if task.formula == PLAIN and task.initial_a["cup"] == 1:
        assert {(1, 1), (0, 1)} <= set(c.lots.goals)  # classes cup, mug
    # every way, and nothing that is not one (the planned round may carry surplus)
    assert ends <= set(c.lots.goals) <= every
    ends |= {c.lots.final}
    avail = tuple(task.initial_a.get(k, 0) + task.initial_b.get(k, 0) for k in task.classes)
    caps = list(itertools.product(*(range(n + 1) for n in avail)))
    for q in range(c.aut.num_states):
        for b in c.lots.wb_states():
            for cap in caps:
                if any(x > n for x, n in zip(b, cap, strict=True)):
                    continue
                planned = c.planner.plan_from(q, b, cap)
                expect = oracle_can_complete(task, c.aut, ends, q, b, cap)
                assert (planned is not None) == expect, (task.formula, q, b, cap)
                if planned is not None:  # an accepted lasso that ends a round
                    assert c.aut.accepts_lasso(planned.prefix, planned.cycle, start=q)
                    assert c.lots.is_goal(planned.end[1])


@settings(max_examples=int(os.environ.get("TAMP_WAYS_EXAMPLES", "40")) // 2, deadline=None)
@given(task=random_task(), extra=st.integers(1, 3))
def test_more_objects_than_a_way_can_deliver_give_the_oracles_ways(task, extra):
    """Counts stay counts: with more objects of a class than a kept round end can deliver
    (``2·|Q|·(|Q_F|+1)``, the planner's search bound), the planner's ways are still exactly
    the oracle's, which searches every count without a bound."""
    from dataclasses import replace

    from tamp.lots.automaton import Automaton

    aut = Automaton(task.formula, task.props)
    bound = 2 * aut.num_states * (len(aut.live_accepting) + 1)
    cls = task.classes[0]
    task = replace(task, initial_a={**task.initial_a, cls: bound + 1 + extra})
    try:
        c = LotsController(task)
    except InfeasibleError:
        assert not oracle_round_ends(task, aut)
        return
    ends = oracle_round_ends(task, c.aut)
    assert ends <= set(c.lots.goals) <= oracle_round_ends(task, c.aut, minimal=False)


takeaway = st.tuples(st.sampled_from(("A", "B")), st.integers(0, 2), st.integers(1, 2))


@settings(max_examples=int(os.environ.get("TAMP_WAYS_EXAMPLES", "60")), deadline=None)
@given(task=random_task(), when=st.integers(0, 2), takes=st.lists(takeaway, max_size=3))
def test_the_robot_completes_exactly_when_some_way_is_left(task, when, takes):
    """After a person takes objects away (W^A or W^B), the run ends satisfied iff the oracle
    says a round can still be completed from there; otherwise it exits 1 with the reason."""
    try:
        LotsController(task)
    except InfeasibleError:
        return
    seen: dict = {}

    def policy(n, phase, world):
        if n != when or phase != "idle" or seen:
            return
        for side, k, count in takes:
            cls = CLASSES[k]
            have = len(objects_of(world.state, cls, side))
            if have:
                yield Event(after=n, kind="remove", cls=cls, side=side, count=min(count, have))
        seen.update(side_counts(world.state), done=actions_done(world))

    r = run_task(task, policy=policy, max_waits=2)
    if not seen:  # the run ended before the person acted
        assert r.satisfied, r.reason
        return
    c = r.controller
    qs = {c.aut.initial}
    for a in r.actions[: seen["done"]]:
        letter = frozenset({a.prop}) if a.kind == "move" else EMPTY
        qs = {n for q in qs for n in c.aut.successors(q, letter)}
    a_now, b_now = c.lots.vector(seen["A"]), c.lots.vector(seen["B"])
    cap = tuple(x + y for x, y in zip(a_now, b_now, strict=True))
    ends = oracle_round_ends(task, c.aut) | {c.lots.final}  # the planned round counts too
    feasible = any(oracle_can_complete(task, c.aut, ends, q, b_now, cap) for q in qs)
    assert r.satisfied == feasible, (task.formula, r.reason, [a.text() for a in r.actions], seen)
    if not r.satisfied:
        assert r.reason
    else:
        assert c.lots.is_goal(c.lots.vector(r.counts()["B"]))
