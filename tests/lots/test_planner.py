"""Lemma 1, the initial run (Alg. 2), the table T, the tree update (Alg. 3), the baseline."""

from __future__ import annotations

import itertools
from dataclasses import replace

import pytest

from tamp.lots.automaton import EMPTY
from tamp.lots.controller import LotsController
from tamp.lots.planner import Table, Tree, follow_table
from tamp.lots.product import ProductPlanner
from tamp.lots.task import Proposition, Task


def L(*props):
    return frozenset(props)


def test_lemma1_example1_has_12_wb_states(example1):
    c = LotsController(example1)
    names = c.lots.named(c.lots.final)
    assert names == {"hammer": 1, "screw": 2, "screwdriver": 1}
    assert c.lots.num_wb_states() == 12 == (1 + 1) * (2 + 1) * (1 + 1)
    assert len(set(c.lots.wb_states())) == 12
    assert all(c.lots.in_box(b) for b in c.lots.wb_states())


@pytest.mark.parametrize("n", [2, 3, 5])
def test_lemma1_counts_follow_the_round(n):
    props = tuple(Proposition(f"p{i}", "block") for i in range(1, n + 1))
    chain = " & ".join(f"GF p{i}" for i in range(1, n + 1))
    task = Task(chain, props, {"block": n + 2})
    c = LotsController(task)
    assert c.lots.final == (n,)  # one class, n deliveries in one round
    assert c.lots.num_wb_states() == n + 1


def test_example1_round_order_comes_from_the_automaton(example1):
    c = LotsController(example1)
    plan = c.initial_plan
    # the paper's round (p2 the first screw, p4 the second): the task file writes the
    # conjuncts reversed so that Spot serves them in this order
    assert [s.prop for s in plan.steps] == ["p1", "p2", "p3", "p4"]
    assert plan.cycle == [L("p1"), L("p2"), L("p3"), L("p4")]
    assert c.aut.accepts_lasso(plan.prefix, plan.cycle)
    assert all(len(x) <= 1 for x in plan.prefix + plan.cycle)  # one thing at a time


def test_tower_round_and_table(tower):
    c = LotsController(tower)
    assert [s.prop for s in c.initial_plan.steps if s.kind == "move"] == ["p1", "p2", "p3"]
    assert c.initial_plan.cycle == [EMPTY]
    assert c.aut.accepts_lasso(c.initial_plan.prefix, c.initial_plan.cycle)
    assert c.table.as_mapping() == {
        (0, 0, 0): "p1",
        (1, 0, 0): "p2",
        (1, 1, 0): "p3",
        (1, 1, 1): "done",
    }
    assert follow_table(c.table, (1, 0, 0)) == [L("p2"), L("p3")]
    assert follow_table(c.table, (0, 0, 0)) == [L("p1"), L("p2"), L("p3")]


def _all_pairs(c):
    return itertools.product(range(c.aut.num_states), list(c.lots.wb_states()))


@pytest.mark.parametrize("name", ["example1", "tower", "model_building"])
def test_plans_match_the_product_baseline(name, request):
    """Peers as oracles: same optimum from every pair (q, s^B), given enough objects in W^A.

    ``plan_from`` without a stock assumes W^A holds what the run needs; the product's W^A
    is ``final - b``, so a run that takes an object out and delivers it again needs our
    return action there too: both planners run with it."""
    task = replace(request.getfixturevalue(name), returns=True)
    c = LotsController(task)
    base = ProductPlanner(c.aut, c.lots, task, c.lots.final)
    feasible = 0
    for q, b in _all_pairs(c):
        a = tuple(f - x for f, x in zip(c.lots.final, b, strict=True))
        ours, theirs = c.planner.plan_from(q, b), base.replan(q, a, b)
        assert (ours is None) == (theirs is None), (q, b)
        if ours is not None:
            feasible += 1
            assert ours.cost == pytest.approx(theirs.cost), (q, b)
            # the plan ends in the goal pair and never leaves Lemma 1's box
            assert ours.end[1] == c.lots.final and ours.end[0] in c.aut.accepting
            assert all(c.lots.in_box(s.b_next) for s in ours.steps)
    assert feasible > 0


@pytest.mark.parametrize("name", ["example1", "tower", "model_building"])
def test_plans_from_reachable_pairs_are_accepted_runs(name, request):
    """Root-to-pair letters (TR path) + plan prefix + cycle is a word of the task."""
    task = request.getfixturevalue(name)
    c = LotsController(task)
    tree = Tree(c.planner, (c.aut.initial, c.lots.vector(task.initial_b)), mode="bfs")
    for b in c.lots.wb_states():
        tree.update(b)
    while tree._frontier:  # close the tree
        tree.update((-1,) * len(c.lots.classes))
    checked = 0
    for pair in list(tree.parent)[:40]:
        plan = c.planner.plan_from(*pair)
        if plan is None:
            continue
        path = []
        node = pair
        while tree.parent[node] is not None:
            prev = tree.parent[node]
            step = next(s for s in c.planner.moves(*prev) if (s.q_next, s.b_next) == node)
            path.append(step.letter)
            node = prev
        path.reverse()
        assert c.aut.accepts_lasso(path + plan.prefix, plan.cycle), pair
        checked += 1
    assert checked > 5


@pytest.mark.parametrize("name", ["example1", "tower", "model_building"])
@pytest.mark.parametrize("seed", [0, 1, 7])
def test_random_and_bfs_tree_updates_reach_the_same_verdicts(name, seed, request):
    task = request.getfixturevalue(name)
    c = LotsController(task)
    root = (c.aut.initial, c.lots.vector(task.initial_b))
    verdicts = {}
    for mode in ("bfs", "random"):
        c2 = LotsController(task)
        tree = Tree(c2.planner, root, mode=mode, seed=seed)
        tree.add_plan(c2.initial_plan)
        verdicts[mode] = {b: tree.update(b) is not None for b in c2.lots.wb_states()}
    assert verdicts["bfs"] == verdicts["random"]
    # outside Lemma 1's box there is no pair at all
    assert Tree(c.planner, root).update(tuple(f + 1 for f in c.lots.final)) is None


def test_random_tree_update_is_seedable(example1):
    def expansions(seed):
        c = LotsController(example1, mode="random", seed=seed)
        c.tree.update((0, 0, 1))
        return c.tree.expansions, sorted(c.tree.parent)

    assert expansions(5) == expansions(5)


def test_table_lookup_is_a_dict_on_tuples(tower):
    c = LotsController(tower)
    t = c.table
    assert isinstance(t, Table) and isinstance(t.entries, dict)
    e = t.get((1, 0, 0))
    assert (e.kind, e.prop, e.b_next) == ("move", "p2", (1, 1, 0))
    assert t.get((0, 1, 0)) is None


def test_every_box_state_of_the_tower_is_recoverable(tower):
    """Removals (back to W^A or into the waste basket) reach every W^B state of the box."""
    c = LotsController(tower)
    for b in c.lots.wb_states():
        assert c.tree.update(b) is not None
    assert c.tree.update((2, 0, 0)) is None  # outside Lemma 1's box: no pair


ORDERED = Task(
    "F(p2 & F p1) & G(p1 -> G !p2)",  # p2 before p1, and never p2 once p1 happened
    (Proposition("p1", "cup"), Proposition("p2", "plate")),
    {"cup": 1, "plate": 1},
)


@pytest.mark.parametrize("mode", ["bfs", "random"])
def test_state_that_cannot_lead_to_completion(mode):
    """A cup delivered first can never be fixed: Alg. 3 exhausts TR (Alg. 1 line 23)."""
    c = LotsController(ORDERED, mode=mode, seed=3)
    assert [s.prop for s in c.initial_plan.steps if s.kind == "move"] == ["p2", "p1"]
    b_cup = c.lots.vector({"cup": 1})
    assert c.tree.update(b_cup) is None
    n = len(c.tree)
    assert n <= c.aut.num_states * c.lots.num_wb_states()  # the bound of Alg. 3 line 7
    assert c.tree.update(b_cup) is None and len(c.tree) == n  # verdict is stable, no regrowth
    assert c.planner.plan_from(c.aut.initial, c.lots.vector({"plate": 1})) is not None
