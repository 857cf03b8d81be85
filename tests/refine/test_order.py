"""The event order: deadlocks and impossible events are infeasible; executions enumerated."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from tamp.errors import InfeasibleError
from tamp.refine.order import check_can_finish, downsets, linear_orders, precedence
from tamp.refine.program import Motion, Trigger
from tamp.refine.steps import parallelize

from .helpers import task


def test_task4_precedence():
    prec = precedence(task(4))
    assert prec["R1.pull_out"] == {"R1.lower_arm", "R1.approach", "R2.approach", "R2.grip"}
    assert prec["R2.release"] >= {"R1.pull_out", "R2.grip"}
    assert prec["R1.lower_arm"] == set() and prec["R2.approach"] == set()


def test_cycle_is_infeasible_with_the_cycle_named():
    p = task(4)
    r2 = p.robot("R2")
    grip = replace(r2.behavior("grip"), waits_for=("R1.raise_arm",))
    bad = p.with_behavior("R2", 1, grip)
    with pytest.raises(InfeasibleError, match="cycle") as exc:
        check_can_finish(bad)
    assert "R2.grip" in str(exc.value) and "R1.pull_out" in str(exc.value)


def test_odometry_beyond_the_motion_can_never_fire():
    p = task(4)
    b = p.robot("R1").behavior("approach")
    bad = p.with_behavior("R1", 1, replace(b, motion=replace(b.motion, amount=0.5)))
    with pytest.raises(InfeasibleError, match="odometry reaches 0.69 but its motion covers"):
        check_can_finish(bad)
    check_can_finish(p)


def test_executions_of_independent_chains():
    # Two robots without synchronisation: (n + m)! / (n! m!) interleavings.
    p = task(3)
    free = p
    for r in p.robots:
        for i, b in enumerate(r.behaviors):
            free = free.with_behavior(r.name, i, replace(b, waits_for=()))
    orders = list(linear_orders(free))
    assert len(orders) == math.comb(7, 3)
    states, succ = downsets(free)
    assert len(states) == 4 * 5  # downsets of two chains: (3 + 1) * (4 + 1)
    assert succ[states.index(frozenset(free.events()))] == []


def test_parallelized_program_allows_both_orders_of_the_absorbed_pair():
    d = {"R1.lower_arm": 57.0, "R1.approach": 68.0}
    p, _ = parallelize(task(4), d)
    firsts = {o.index("R1.lower_arm") < o.index("R1.approach") for o in linear_orders(p)}
    assert firsts == {True, False}
    seq = {o.index("R1.lower_arm") < o.index("R1.approach") for o in linear_orders(task(4))}
    assert seq == {True}


def test_after_trigger_orders_events():
    p = task(4)
    b = p.robot("R2").behavior("release")
    q = p.with_behavior("R2", 2, replace(b, waits_for=(), event=Trigger(after="R1.raise_arm")))
    assert "R1.raise_arm" in precedence(q)["R2.release"]
    assert Motion("distance", 0.5, 0.01).nominal_time == pytest.approx(50.0)
