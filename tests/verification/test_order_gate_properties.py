"""The SMP plan gate's direct check against the explicit automaton method (Spot), on random
orders, constraint sets and goal-set graphs of growing size: the same verdicts, violated
conjuncts and bad-prefix ends wherever the explicit method runs; beyond it, the direct
check keeps its verdicts (checked against the constraint set itself) in linear time."""

from __future__ import annotations

import itertools
import random
import sys
from types import SimpleNamespace

import networkx as nx
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.verification.rg import (
    GoalGraph,
    check_goal_graph,
    check_graph,
    check_graph_explicit,
    check_order,
    constraint_formula,
    goal_prop,
    order_word,
)
from tamp.verification.traces import check_trace


def _demo(n: int, constraints) -> SimpleNamespace:
    ids = [f"G{k}" for k in range(n)]
    return SimpleNamespace(goal_ids=ids, constraints=set(constraints), constraint_reasons={})


@st.composite
def order_problems(draw, max_goals: int = 5, max_constraints: int = 6):
    """Goals, any constraints between distinct goals (cycles included), and an order of
    some of the goals."""
    n = draw(st.integers(1, max_goals))
    ids = [f"G{k}" for k in range(n)]
    pairs = [(a, b) for a in ids for b in ids if a != b]
    cons = (
        draw(st.lists(st.sampled_from(pairs), max_size=max_constraints, unique=True))
        if pairs
        else []
    )
    order = draw(st.permutations(ids))
    cut = draw(st.integers(0, n))
    return _demo(n, cons), list(order[:cut])


@settings(max_examples=80, deadline=None)
@given(order_problems())
def test_order_check_equals_the_automaton_method(problem) -> None:
    demo, order = problem
    direct = check_order(demo, order)
    f = constraint_formula(demo.goal_ids, demo.constraints)
    explicit = check_trace(f, order_word(order), finite=False)
    assert direct.holds == explicit.holds
    if direct.holds:
        return
    a, b = direct.counterexample, explicit.counterexample
    if len(demo.constraints) + len(demo.goal_ids) > 1:
        assert sorted(a.violated) == sorted(b.violated)
    assert a.position == b.position


@st.composite
def goal_graphs(draw, max_goals: int = 4):
    """A random graph of goal sets whose edges never lose a goal (some keep the set:
    self-loops and cycles of equal sets), rooted at the empty set, with random constraints."""
    n = draw(st.integers(1, max_goals))
    ids = [f"G{k}" for k in range(n)]
    masks = draw(st.sets(st.integers(1, (1 << n) - 1), max_size=8))
    nodes = [0, *sorted(masks)]
    edges = []
    for u in nodes:
        for v in nodes:
            if u & ~v == 0 and draw(st.integers(0, 3)) == 0:
                edges.append((u, v))
    g = nx.DiGraph()
    names = {m: frozenset(ids[k] for k in range(n) if m >> k & 1) for m in nodes}
    g.add_nodes_from(names.values())
    g.add_edges_from((names[u], names[v]) for u, v in edges)
    pairs = [(a, b) for a in ids for b in ids if a != b]
    cons = draw(st.lists(st.sampled_from(pairs), max_size=4, unique=True)) if pairs else []
    return _demo(n, cons), g


@settings(max_examples=60, deadline=None)
@given(goal_graphs())
def test_graph_check_equals_the_automaton_method(problem) -> None:
    demo, g = problem
    direct = check_graph(demo, g)
    explicit = check_graph_explicit(demo, g)
    assert direct.holds == explicit.holds
    if direct.holds:
        return
    ce = direct.counterexample
    # the counterexample is a run of the graph that really violates the encoding
    f = constraint_formula(demo.goal_ids, demo.constraints)
    assert not check_trace(f, ce.word, finite=False).holds
    states = [frozenset(s.strip("{}").split(", ")) - {""} for s in ce.steps]
    assert states[0] == frozenset()
    assert all(g.has_edge(a, b) for a, b in zip(states, states[1:], strict=False))
    last, entry = states[-1], states[len(ce.word.prefix)]
    assert g.has_edge(last, entry) or (last == entry and g.out_degree(last) == 0)


def test_a_graph_losing_a_goal_goes_to_the_automaton_method() -> None:
    demo = _demo(2, {("G0", "G1")})
    g = nx.DiGraph([(frozenset(), frozenset({"G0"})), (frozenset({"G0"}), frozenset())])
    gg = GoalGraph.of_networkx(demo.goal_ids, g)
    assert check_goal_graph(demo, gg) is None
    assert not check_graph(demo, g).holds  # F g1 never holds: the explicit method decides


def _chain(n: int, cut: int | None, rng: random.Random) -> tuple[SimpleNamespace, list[str]]:
    """n goals with a random forest of constraints; a random linear extension, perhaps
    with one swap and a cut."""
    ids = [f"G{k}" for k in range(n)]
    cons = {(ids[rng.randrange(k)], ids[k]) for k in range(1, n)}
    order = list(ids)
    if rng.random() < 0.5:
        k = rng.randrange(n - 1)
        order[k], order[k + 1] = order[k + 1], order[k]
    return _demo(n, cons), order[:cut] if cut is not None else order


def test_growing_sizes_stay_linear_and_exact() -> None:
    """Up to 5,000 goals: verdicts match the constraint set itself; the work per goal of the
    order check (Python function calls, counted: deterministic, unlike a clock) does not
    grow with the size."""
    rng = random.Random(3)
    per_goal = {}
    for n, wrong in itertools.product((10, 100, 1000, 5000), (False, True)):
        demo, order = _chain(n, n - 1 if wrong else None, rng)
        goal_prop.cache_clear()  # count the work of this check alone, not what earlier ones cached
        v, calls = _calls(check_order, demo, order)
        per_goal[n, wrong] = calls / n
        pos = {g: k for k, g in enumerate(order)}
        respects = len(order) == n and all(pos[i] < pos[j] for i, j in demo.constraints)
        assert v.holds == respects
        if not v.holds:
            assert v.counterexample.violated
            assert " <= " in v.counterexample.reason or "never reached" in v.counterexample.reason
        # the path graph of that order: its one path is the order's run
        masks = [0]
        for g in order:
            masks.append(masks[-1] | 1 << int(g[1:]))
        succ = [[k + 1] for k in range(len(order))] + [[]]
        gv = check_goal_graph(demo, GoalGraph(tuple(demo.goal_ids), masks, succ))
        assert gv is not None and gv.holds == v.holds
    for wrong in (False, True):  # n log n at most (a sort), never quadratic
        assert per_goal[5000, wrong] < 2 * per_goal[100, wrong]


def _calls(f, *args):
    """``f(*args)`` and the number of Python function calls it made."""
    count = 0

    def profile(frame, event, arg):
        nonlocal count
        if event == "call":
            count += 1

    sys.setprofile(profile)
    try:
        out = f(*args)
    finally:
        sys.setprofile(None)
    return out, count


def test_tamp_verify_plan_on_a_300_goal_chain(tmp_path, capsys) -> None:
    """The whole RG and a wrong order of 300 goals: verdicts, not the size guard's exit 2."""
    from tamp.commands.verify import main as verify_main
    from tests.demo.generate import write_demo

    demo = str(write_demo(tmp_path / "chain300.yaml", 300, "one"))
    assert verify_main(["plan", demo]) == 0
    assert "RG (301 states, 300 edges): holds" in capsys.readouterr().out
    order = ",".join(["G1", "G0"] + [f"G{k}" for k in range(2, 300)])
    assert verify_main(["plan", demo, "--order", order, "--no-graph"]) == 1
    out = capsys.readouterr().out
    assert "G1 is reached at position 1 before G0, but C has G0 <= G1" in out
    assert len(max(out.splitlines(), key=len)) < 400  # long formulas and runs are shortened
