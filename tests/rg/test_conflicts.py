"""Conflicting arcs (`tamp.rg.conflicts`): never adjacent in any order, and the bound that
prices them stays admissible and the search exact (checked against the brute-force oracle)."""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings

import tamp.rg.search as search
from tamp.demo import cyclic_swap
from tamp.demo.model import Demonstration
from tamp.rg import OrderProblem, astar
from tamp.rg.conflicts import conflicting, never_adjacent
from tamp.rg.costs import CostModel
from tamp.world import default_domain
from tests.rg.oracle import dp_optimum
from tests.rg.strategies import demonstrations

SWAPS = [cyclic_swap(3), cyclic_swap(4), cyclic_swap(4, layout="ring")]


def _problem(demo: Demonstration) -> OrderProblem:
    return OrderProblem(demo, CostModel.of("distance", default_domain()))


def _closure(demo: Demonstration) -> np.ndarray:
    """x ≤* y over the goal indices, from C by networkx (apart from the search's own)."""
    ids = list(demo.goal_ids)
    pos = {g: i for i, g in enumerate(ids)}
    dag = nx.transitive_closure_dag(nx.DiGraph(list(demo.constraints)))
    le = np.eye(len(ids), dtype=bool)
    for a, b in dag.edges:
        le[pos[a], pos[b]] = True
    return le


def _orders(demo: Demonstration):
    """Every goal order that respects C, as goal indices."""
    ids = list(demo.goal_ids)
    pos = {g: i for i, g in enumerate(ids)}
    need = [(pos[a], pos[b]) for a, b in demo.constraints]
    for order in itertools.permutations(range(len(ids))):
        at = {g: i for i, g in enumerate(order)}
        if all(at[a] < at[b] for a, b in need):
            yield order


def _check_no_order_takes_both(demo: Demonstration) -> None:
    le = _closure(demo)
    k = len(le)
    a, b = (x.ravel() for x in np.meshgrid(np.arange(k), np.arange(k), indexing="ij"))
    keep = (a != b) & ~le[b, a]  # arcs that may occur: b is not before a
    a, b = a[keep], b[keep]
    clash = conflicting(a, b, le)
    never = never_adjacent(le)
    index = {(x, y): i for i, (x, y) in enumerate(zip(a.tolist(), b.tolist(), strict=True))}
    for order in _orders(demo):
        taken = [index[s] for s in itertools.pairwise(order)]
        assert not clash[np.ix_(taken, taken)].any(), order
        assert not any(never[x, y] for x, y in itertools.pairwise(order)), order


@pytest.mark.parametrize("demo", SWAPS, ids=["swap3", "swap4", "ring4"])
def test_conflicting_arcs_are_never_both_taken_on_cyclic_swaps(demo) -> None:
    _check_no_order_takes_both(demo)
    assert _problem(demo).conflicts is not None  # the swaps do price conflicts


@settings(max_examples=40, deadline=None)
@given(demonstrations(max_objects=4, max_steps=7))
def test_conflicting_arcs_are_never_both_taken(demo) -> None:
    _check_no_order_takes_both(demo)


def _check_admissible_and_exact(demo: Demonstration) -> None:
    problem = _problem(demo)
    best = dp_optimum(demo)
    assert problem.heuristic(0, -1) <= best + 1e-9
    r = astar(problem)
    assert r is not None and r.cost == pytest.approx(best, abs=1e-9)
    assert astar(_problem(demo), symmetry=False).cost == pytest.approx(best, abs=1e-9)


@pytest.mark.parametrize(
    "demo",
    [*SWAPS, cyclic_swap(5), cyclic_swap(5, layout="ring"), cyclic_swap(6, layout="staging")],
    ids=["swap3", "swap4", "ring4", "swap5", "ring5", "staging6"],
)
def test_priced_bound_is_admissible_and_the_search_exact_on_swaps(demo) -> None:
    _check_admissible_and_exact(demo)


@settings(max_examples=60, deadline=None)
@given(demonstrations(max_objects=4, max_steps=7))
def test_priced_bound_is_admissible_and_the_search_exact(demo) -> None:
    _check_admissible_and_exact(demo)


def test_priced_bound_is_admissible_in_every_state_of_a_swap() -> None:
    demo = cyclic_swap(4)
    problem = _problem(demo)
    for order in _orders(demo):
        to_go, mask, last = problem.order_cost([demo.goal_ids[g] for g in order]), 0, -1
        for g in order:
            assert problem.heuristic(mask, last) <= to_go + 1e-9
            to_go -= problem.step_cost(last, g)
            mask, last = mask | 1 << g, g


def test_pricing_raises_the_first_bound(monkeypatch) -> None:
    demo = cyclic_swap(6)
    priced = _problem(demo).heuristic(0, -1)
    monkeypatch.setattr(search, "CONFLICT_LIMIT", 0)
    plain = _problem(demo).heuristic(0, -1)
    assert plain < priced <= dp_optimum(demo) + 1e-9


def test_symmetric_tasks_get_invariant_multipliers() -> None:
    problem = _problem(cyclic_swap(6, layout="ring"))
    priced, sym = problem.conflicts, problem.symmetry()
    assert priced is not None and sym is not None and len(sym) > 1
    quads = list(
        zip(
            priced.r1.tolist(),
            priced.c1.tolist(),
            priced.r2.tolist(),
            priced.c2.tolist(),
            strict=True,
        )
    )
    lam = dict(zip(quads, priced.lam.tolist(), strict=True))
    for p in sym.perms:
        for (a, b, c, d), w in lam.items():
            one, two = (p[a], p[b]), (p[c], p[d])
            assert lam[(*one, *two) if one < two else (*two, *one)] == pytest.approx(w)
