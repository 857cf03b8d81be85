"""RG orders and graphs, LOTS runs and tables, BT executions; the gate stops corrupted plans."""

from __future__ import annotations

import dataclasses
import itertools

import networkx as nx
import pytest
import spot

from tamp.demo import load_demonstration
from tamp.errors import InfeasibleError, InputError
from tamp.rg import build_rg, plan
from tamp.scenarios import path
from tamp.verification import VerificationError, gate
from tamp.verification.bt import check_tree, executor_for
from tamp.verification.rg import check_graph, check_order, constraint_formula, order_word
from tamp.world.events import Appear, Fail
from tests.verification.ltlf_oracle import lasso_violates


@pytest.fixture(scope="module")
def case2():
    return load_demonstration(path("case2.yaml"))


# -- RG -------------------------------------------------------------------------------------


def _respects(order, constraints) -> bool:
    pos = {g: k for k, g in enumerate(order)}
    return all(pos[i] < pos[j] for i, j in constraints)


@pytest.mark.parametrize("case", ["case1.yaml", "case2.yaml", "case3.yaml"])
def test_every_order_verdict_matches_the_constraints(case) -> None:
    """Each permutation holds iff it respects C (the peer oracle is the constraint set)."""
    demo = load_demonstration(path(case))
    f = constraint_formula(demo.goal_ids, demo.constraints)
    for order in itertools.permutations(demo.goal_ids):
        v = check_order(demo, list(order))
        assert v.holds == _respects(order, demo.constraints), order
        w = order_word(order)
        assert v.holds == (not lasso_violates(f, list(w.prefix), list(w.cycle)))
        if not v.holds:
            ce = v.counterexample
            # the bad prefix ends exactly where a constrained goal is reached too early
            late = ce.word.prefix[ce.position] - ce.word.prefix[ce.position - 1]
            (g,) = late
            gid = "G" + g[1:]
            assert any(j == gid and i not in order[: ce.position] for i, j in demo.constraints)
            assert _respects(
                [
                    "G" + next(iter(b - a))[1:]
                    for a, b in itertools.pairwise(ce.accepting_word.prefix)
                ],
                demo.constraints,
            )


def test_planned_order_and_graph_hold(case2) -> None:
    result = plan(case2)
    report = gate(result)
    assert report.holds
    graph = report.verdicts[1]
    rg = build_rg(case2)
    assert graph.states_explored == rg.number_of_nodes()


def test_corrupted_order_is_stopped_by_the_gate(case2) -> None:
    result = plan(case2)
    bad_order = list(reversed(result.order))
    assert not _respects(bad_order, case2.constraints)
    corrupted = dataclasses.replace(result, order=bad_order)
    with pytest.raises(VerificationError) as err:
        gate(corrupted)
    assert isinstance(err.value, InfeasibleError)
    ce = err.value.counterexample
    assert ce is not None and ce.position == 1
    assert "violates" in str(err.value)


def test_missing_goal_violates_eventually(case2) -> None:
    v = check_order(case2, ["G0", "G1", "G2"])
    assert not v.holds
    assert v.counterexample.violated == ["Fg3"]
    assert v.counterexample.position is None  # liveness: no finite bad prefix


def test_unknown_or_repeated_goal_is_bad_input(case2) -> None:
    with pytest.raises(InputError):
        check_order(case2, ["G0", "G7"])
    with pytest.raises(InputError):
        check_order(case2, ["G0", "G0", "G1", "G2", "G3"])


def test_whole_graph_check_finds_a_corrupted_edge_and_a_dead_end(case2) -> None:
    rg = build_rg(case2)
    assert check_graph(case2, rg).holds
    bad = rg.copy()
    bad.add_edge(frozenset({"G1"}), frozenset({"G1", "G2"}), goal="G2")  # G0 <= G2 broken
    v = check_graph(case2, bad)
    assert not v.holds
    steps = v.counterexample.steps
    assert "{G1, G2}" in steps
    dead = rg.copy()
    dead.remove_edges_from(list(dead.out_edges(frozenset({"G0"}))))
    v = check_graph(case2, dead)
    assert not v.holds and "{G0}" in v.counterexample.steps


def test_graph_with_many_goals_uses_small_negated_conjuncts() -> None:
    """12 unconstrained goals: 2^12 RG states; the whole formula would be exponential."""
    from tamp.demo import make_demonstration
    from tamp.world import Point

    objects = {f"O{i}": Point(float(i), 0.0) for i in range(12)}
    steps = [(f"O{i}", Point(float(i), 3.0)) for i in range(12)]
    demo = make_demonstration(objects, steps, 0.15)
    assert not demo.constraints
    rg = build_rg(demo)
    assert rg.number_of_nodes() == 2**12
    v = check_graph(demo, rg)
    assert v.holds and v.states_explored == 2**12
    bad = rg.copy()
    bad.remove_edges_from(list(bad.out_edges(frozenset({"G0", "G5"}))))
    v = check_graph(demo, bad)
    assert not v.holds
    assert nx.has_path(rg, frozenset(), frozenset({"G0", "G5"}))


# -- LOTS -----------------------------------------------------------------------------------


def _controller(name):
    from tamp.lots.controller import LotsController
    from tamp.lots.task import load_task

    return LotsController(load_task(path(f"lots/{name}")))


@pytest.mark.parametrize("name", ["example1.yaml", "model_building.yaml", "tower.yaml"])
def test_lots_plans_and_tables_hold(name) -> None:
    c = _controller(name)
    report = gate(c)
    assert report.holds and len(report.verdicts) == 2
    prefix, cycle = c.plan_letters()
    assert not lasso_violates(spot.formula(c.task.formula), prefix, cycle)


def test_lots_table_entry_leading_away_is_stopped() -> None:
    """Tower: a table that stacks body, bottom, peak is consistent in W^B but not accepted."""
    from tamp.lots.planner import Entry, Table

    c = _controller("tower.yaml")
    t = c.table
    run = t.run
    order = ["p2", "p1", "p3"]
    b = run[0].b
    entries = []
    for k, p in enumerate(order):
        nb = c.lots.deliver(b, frozenset({p}))
        entries.append(Entry("move", run[k].q, b, k, p, c.lots.prop_class[p], None, nb))
        b = nb
    entries.append(Entry("done", run[-1].q, b, len(order)))
    bad = Table(c.lots, {e.b: e for e in entries}, entries)
    c.table = bad
    with pytest.raises(VerificationError) as err:
        gate(c)
    v = err.value.report.failed[0]
    assert "table" in v.subject
    assert "not accepted" in v.counterexample.reason


def test_lots_table_entry_into_uncovered_state_is_stopped() -> None:
    c = _controller("tower.yaml")
    first = c.table.run[0]
    wrong = dataclasses.replace(first, prop="p3", cls=c.lots.prop_class["p3"])
    c.table.entries[first.b] = wrong
    c.table.run[0] = wrong
    with pytest.raises(VerificationError) as err:
        gate(c)
    assert "no entry" in err.value.counterexample.reason


def test_lots_planned_run_corrupted_is_stopped() -> None:
    c = _controller("tower.yaml")
    p = c.plan
    moves = [s for s in p.steps if s.kind == "move"]
    swapped = [moves[1], moves[0]] + p.steps[2:]
    c.plan = dataclasses.replace(p, steps=swapped)
    with pytest.raises(VerificationError) as err:
        gate(c)
    assert "planned run" in err.value.report.failed[0].subject


# -- BT -------------------------------------------------------------------------------------


def _no_area_free_domain(demo):
    dom = demo.domain()
    place = dom.templates["Place"]
    con = tuple(c for c in place.con if c.predicate != "IsAreaFree")
    return dataclasses.replace(dom, templates={**dom.templates, "Place": place_with(place, con)})


def place_with(place, con):
    return dataclasses.replace(place, con=con)


def test_bt_case3_with_obstacle_holds_and_counts_states() -> None:
    demo = load_demonstration(path("case3.yaml"))
    exe = executor_for(demo)
    events = [Appear("Oa", demo.goal("G1").area.pos)]
    r0 = check_tree(exe, demo.initial_world(), events=events, max_failures=0)
    r1 = check_tree(exe, demo.initial_world(), events=events, max_failures=1)
    assert r0.holds and r1.holds
    assert r1.states_explored > r0.states_explored
    # the robot grasps the obstacle on its way (Case 3 recovery) -- shown by a counterexample
    r = check_tree(
        exe, demo.initial_world(), ['G !"IsGraspedObject(Oa)"'], events=events, max_failures=0
    )
    assert not r.holds
    assert any("Pick(Oa)" in s for s in r.counterexample.steps)


@pytest.mark.parametrize("case", ["case1.yaml", "case2.yaml", "case3.yaml"])
def test_bt_single_execution_matches_the_symbolic_world_run(case) -> None:
    """Peer oracle: with no failures the explored path performs exactly the actions that
    the BT layer's own SymbolicWorld run performs."""
    from tamp.bt import SymbolicWorld

    demo = load_demonstration(path(case))
    events = [Appear("Oa", demo.goal("G1").area.pos)] if case == "case3.yaml" else []
    r = check_tree(
        executor_for(demo), demo.initial_world(), ["G !goal"], events=events, max_failures=0
    )
    assert not r.holds
    mine = [
        part.split(" -> ")[0].strip()
        for step in r.counterexample.steps
        for part in step.split(";")
        if part.strip().endswith("-> SUCCESS")
    ]
    world = SymbolicWorld(demo.initial_world(), skill_ticks=1, events=events)
    exe = executor_for(demo)
    assert exe.run(world, step=world.step).value == "SUCCESS"
    assert mine == [str(a) for a in world.executed()]


def test_bt_executions_without_failures_form_one_path() -> None:
    demo = load_demonstration(path("case1.yaml"))
    ex = check_tree(executor_for(demo), demo.initial_world(), max_failures=0)
    v = ex.verdicts[0]
    assert "transitions" in v.subject
    n = ex.explored
    assert f"{n} states, {n - 1} transitions" in v.subject


def test_bt_corrupted_domain_is_stopped(case2) -> None:
    """A Place without IsAreaFree puts O0 onto O1 when G2 comes first."""
    exe = executor_for(case2, ["G2", "G0", "G1", "G3"], domain=_no_area_free_domain(case2))
    with pytest.raises(VerificationError) as err:
        gate(exe, state=case2.initial_world(), max_failures=0)
    ce = err.value.counterexample
    assert "Place(O0, L2)" in ce.steps[ce.position]
    # the correct domain recovers (moves O1 away first)
    assert gate(
        executor_for(case2, ["G2", "G0", "G1", "G3"]), state=case2.initial_world(), max_failures=0
    ).holds


def test_bt_unbounded_failures_break_liveness(case2) -> None:
    r = check_tree(
        executor_for(case2),
        case2.initial_world(),
        ["F goal", "F failed | F goal"],
        max_failures=4,
        failures=[Fail("Pick")],
    )
    assert not r.verdicts[0].holds  # Pick can fail more often than the executor retries
    assert r.verdicts[1].holds  # but every execution ends, one way or the other


def test_bt_unknown_proposition_is_bad_input(case2) -> None:
    with pytest.raises(InputError):
        check_tree(executor_for(case2), case2.initial_world(), ["G !nonsense"])


def test_gate_rejects_unknown_plan_types() -> None:
    with pytest.raises(TypeError):
        gate(object())


def test_bt_failures_name_the_skills_that_may_fail() -> None:
    """`Fail` entries restrict branching to matching skills (arguments included)."""
    demo = load_demonstration(path("case1.yaml"))
    state = demo.initial_world()
    none = check_tree(executor_for(demo), state, ["F goal"], max_failures=0)
    one = check_tree(executor_for(demo), state, ["F goal"], failures=[Fail("Pick", ("O1",))])
    picks = check_tree(executor_for(demo), state, ["F goal"], failures=[Fail("Pick")])
    assert none.explored < one.explored < picks.explored
    r = check_tree(
        executor_for(demo), state, ["G !action_failed"], failures=[Fail("Pick", ("O1",))]
    )
    assert not r.holds
    assert any("Pick(O1) -> FAILURE" in s for s in r.counterexample.steps)
    assert not any("Pick(O0) -> FAILURE" in s for s in r.counterexample.steps)


def test_bt_appearance_after_an_action_is_explored() -> None:
    """`after:` events fire in the tick the skill succeeds; the tree still recovers."""
    from tamp.world.events import AfterAction

    demo = load_demonstration(path("case3.yaml"))
    events = [Appear("Oa", "L1", AfterAction("Pick", ("O1",)))]
    r = check_tree(
        executor_for(demo), demo.initial_world(), ['G !"IsGraspedObject(Oa)"', "F goal"],
        events=events, max_failures=0,
    )  # fmt: skip
    assert not r.verdicts[0].holds and r.verdicts[1].holds
    steps = r.counterexample.steps
    k = next(i for i, s in enumerate(steps) if "Pick(O1) -> SUCCESS" in s)
    assert "Oa appears at (2.2, 0.8)" in steps[k]


def test_order_scan_agrees_with_the_automata() -> None:
    """The order is decided by one scan: the same verdict, violated conjuncts and bad-prefix
    end as checking the encoding's automata."""
    import random

    from tamp.demo import cyclic_swap
    from tamp.verification.traces import check_trace
    from tamp.verification.words import Word

    demo = cyclic_swap(3)  # 6 goals, 6 constraints: 12 conjuncts
    ids = demo.goal_ids
    f = constraint_formula(ids, demo.constraints)
    rng = random.Random(7)
    seen_bad = 0
    for _ in range(60):
        order = rng.sample(ids, rng.randint(0, len(ids)))
        fast = check_order(demo, order)
        slow = check_trace(f, order_word(order), finite=False)
        assert fast.holds == slow.holds == _respects_all(order, ids, demo.constraints), order
        assert fast.states_explored == len(order) + 2
        if fast.holds:
            continue
        seen_bad += 1
        a, b = fast.counterexample, slow.counterexample
        assert sorted(a.violated) == sorted(b.violated)
        assert a.position == b.position
        assert isinstance(a.accepting_word, Word) and a.steps[0] == "start"
    assert seen_bad > 30


def _respects_all(order, ids, constraints) -> bool:
    return len(order) == len(ids) and _respects(order, constraints)
