"""The search's symmetry reduction and its bound, against an independent exact oracle."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings

from tamp.demo import cyclic_swap
from tamp.rg import OrderProblem, astar, plan
from tamp.rg.costs import CostModel
from tamp.world import default_domain
from tests.rg.oracle import dp_optimum
from tests.rg.strategies import demonstrations, symmetric_demonstrations


def _model() -> CostModel:
    return CostModel.of("distance", default_domain())


def _respects(order, constraints) -> bool:
    at = {g: i for i, g in enumerate(order)}
    return all(at[a] < at[b] for a, b in constraints)


def _travel(demo, order) -> float:
    robot, where, total = demo.robot_start.pos, dict(demo.objects), 0.0
    for gid in order:
        g = demo.goal(gid)
        src = where[g.object]
        total += math.hypot(robot.x - src.x, robot.y - src.y)
        total += math.hypot(src.x - g.pos.x, src.y - g.pos.y)
        where[g.object], robot = g.pos, g.pos
    return total


@settings(max_examples=40, deadline=None)
@given(symmetric_demonstrations(max_objects=2, max_goals=8))
def test_symmetric_tasks_are_merged_and_still_optimal(demo) -> None:
    problem = OrderProblem(demo, _model())
    sym = problem.symmetry()
    assert sym is not None and len(sym) >= 2  # the turn that built the task is found
    r = astar(problem)
    plain = astar(OrderProblem(demo, _model()), symmetry=False)
    best = dp_optimum(demo)
    assert r is not None and plain is not None
    assert _respects(r.order, demo.constraints) and sorted(r.order) == sorted(demo.goal_ids)
    assert r.cost == pytest.approx(best, abs=1e-9)
    assert _travel(demo, r.order) == pytest.approx(r.cost, abs=1e-9)
    assert plain.cost == pytest.approx(best, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(demonstrations(max_objects=5, max_steps=10, min_steps=6))
def test_larger_random_tasks_match_the_dynamic_programme(demo) -> None:
    """Beyond what brute force over permutations can check (up to 10 goals)."""
    r = plan(demo)
    assert _respects(r.order, demo.constraints)
    assert r.cost == pytest.approx(dp_optimum(demo), abs=1e-9)
    assert _travel(demo, r.order) == pytest.approx(r.cost, abs=1e-9)


@pytest.mark.parametrize("layout", ["shelf", "staging", "ring"])
@pytest.mark.parametrize("n", [3, 4, 5])
def test_cyclic_swaps_match_the_dynamic_programme(layout: str, n: int) -> None:
    demo = cyclic_swap(n, layout=layout)
    r = plan(demo)
    assert _respects(r.order, demo.constraints)
    assert r.cost == pytest.approx(dp_optimum(demo), abs=1e-9)


def test_the_ring_has_one_turn_per_object_and_each_keeps_every_cost() -> None:
    n = 6
    problem = OrderProblem(cyclic_swap(n, layout="ring"), _model())
    sym = problem.symmetry()
    assert sym is not None and len(sym) == n  # turns only: a mirror breaks the cycle's sense
    k = problem.k
    for perm in sym.perms:
        for a, b in itertools.product(range(-1, k), range(k)):
            pa = a if a < 0 else perm[a]
            assert problem.step_cost(pa, perm[b]) == pytest.approx(problem.step_cost(a, b))
        moved = {(perm[a], perm[b]) for b, ps in enumerate(problem.index.preds) for a in ps}
        assert moved == {(a, b) for b, ps in enumerate(problem.index.preds) for a in ps}
    merged = astar(problem)
    plain = astar(OrderProblem(cyclic_swap(n, layout="ring"), _model()), symmetry=False)
    assert merged is not None and plain is not None
    assert merged.cost == pytest.approx(plain.cost, abs=1e-9)
    assert merged.expanded * 3 < plain.expanded


def test_a_task_without_symmetry_finds_none() -> None:
    assert OrderProblem(cyclic_swap(5, layout="shelf"), _model()).symmetry() is None


def test_mask_images_are_the_permuted_bits() -> None:
    problem = OrderProblem(cyclic_swap(5, layout="ring"), _model())
    sym = problem.symmetry()
    assert sym is not None
    rng = np.random.default_rng(0)
    for mask in rng.integers(0, 1 << problem.k, size=50).tolist():
        for perm, image in zip(sym.perms, sym.images(mask), strict=True):
            assert image == sum(1 << perm[b] for b in range(problem.k) if mask >> b & 1)
