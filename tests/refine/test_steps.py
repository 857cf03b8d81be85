"""Refinement steps: Step 1 locate, Step 2 parallelize/revert, speed adjustment, Fig. 5."""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.refine.order import direct_predecessors, precedence
from tamp.refine.steps import (
    Parallelization,
    RateSearch,
    adjust_base_speed,
    apply_rate,
    locate,
    obstruction,
    parallelize,
    refine_rate,
    relax,
    restore,
    revert,
    slack_waits,
)

from .helpers import reload, task

# Task 4 as the paper measured it (Fig. 11/12): the arm lowers in 57 s, the base approaches
# in 68 s, so parallelizing saves 57 s and ending the base with the arm 11 s more.
T4 = {
    "R1.lower_arm": 57.0,
    "R1.approach": 68.0,
    "R1.pull_out": 50.0,
    "R1.raise_arm": 60.0,
    "R2.approach": 45.0,
    "R2.grip": 12.0,
    "R2.release": 10.0,
}


def test_step1_locates_behaviors_before_manipulation():
    assert locate(task(4)) == {"R1": (0, 1), "R2": (0,)}
    assert locate(task(3)) == {"R1": (0, 1), "R2": (0, 1)}


def test_step2_parallelizes_task4_robot1_only(tmp_path):
    p, done = parallelize(task(4), T4)
    assert done == [Parallelization("R1", "lower_arm", "approach")]
    r1 = p.robot("R1")
    assert r1.groups() == [(0, 1), (2,), (3,)]
    assert not r1.gating(0) and r1.gating(1)
    assert p.robot("R2") == task(4).robot("R2")  # one behavior before manipulation
    assert reload(p, tmp_path) == p  # the refined program is a valid file
    assert revert(p, done[0]) == task(4)


def test_step2_conditions():
    # n must be shorter than n + 1
    p, done = parallelize(task(4), T4 | {"R1.lower_arm": 70.0})
    assert done == [] and p == task(4)
    # missing measurements: nothing is assumed
    assert parallelize(task(4), {})[1] == []
    # n + 1 waiting for the other robot obstructs
    r1 = task(4).robot("R1")
    blocked = replace(r1.behaviors[1], waits_for=("R2.approach",))
    r1b = replace(r1, behaviors=(r1.behaviors[0], blocked, *r1.behaviors[2:]))
    assert "waits for R2.approach" in obstruction(r1b, 0)
    same = replace(r1.behaviors[1], section="arm")
    r1c = replace(r1, behaviors=(r1.behaviors[0], same, *r1.behaviors[2:]))
    assert "share the arm" in obstruction(r1c, 0)
    assert obstruction(r1, 0) is None


def test_task3_parallelizes_both_robots():
    d = {"R1.raise_arm": 33.0, "R1.approach": 43.0, "R2.raise_arm": 33.0, "R2.approach": 43.0}
    _, done = parallelize(task(3), d)
    assert {(x.robot, x.absorbed) for x in done} == {("R1", "raise_arm"), ("R2", "raise_arm")}


def test_speed_adjustment_ends_the_base_with_the_arm():
    p, _ = parallelize(task(4), T4)
    measured = T4 | {"R1.approach": 68.0, "R1.lower_arm": 57.0}
    q, changes = adjust_base_speed(p, measured)
    assert len(changes) == 1
    c = changes[0]
    assert c.event == "R1.approach" and c.partner == "lower_arm"
    assert c.new == pytest.approx(1.05e-2 * 68.0 / 57.0)
    assert q.robot("R1").behavior("approach").motion.speed == pytest.approx(c.new)
    # nominal base time now matches the arm's measured time
    b = q.robot("R1").behavior("approach")
    assert 0.71 / b.motion.speed == pytest.approx(0.71 / 1.05e-2 * 57 / 68)
    # a base that already ends first is left alone; sequential programs are untouched
    assert adjust_base_speed(p, T4 | {"R1.approach": 50.0})[1] == []
    assert adjust_base_speed(task(4), T4)[1] == []


def test_rate_search_keeps_the_rate_before_the_first_delay():
    s = refine_rate(RateSearch(10.0, 1.0, 0.02, 200.0), lambda p: 0.01 if p <= 17 else 0.5)
    assert s.found == 17.0
    assert [r for r, _ in s.probes] == [11.0, 12.0, 13.0, 14.0, 15.0, 16.0, 17.0, 18.0]
    # delayed at once: keep the current rate; never past the limit
    assert refine_rate(RateSearch(10.0, 1.0, 0.02, 200.0), lambda p: 1.0).found == 10.0
    assert refine_rate(RateSearch(10.0, 4.0, 0.02, 20.0), lambda p: 0.0).found == 20.0
    s = RateSearch(10.0, 1.0, 0.02, 200.0)
    assert s.validated == 10.0 and s.observe(0.0).validated == 11.0
    assert s.observe(1.0).observe(0.0).found == 10.0  # done: further probes change nothing


def test_apply_rate_scales_the_base_speed_with_p_as_the_papers_step_3():
    p = apply_rate(task(4), "R1", 23.0)
    for b0, b1 in zip(task(4).robot("R1").behaviors, p.robot("R1").behaviors, strict=True):
        assert b1.rate_hz == 23.0
        factor = 2.3 if b0.section == "base" else 1.0  # the arm keeps its speed
        assert b1.motion.speed == pytest.approx(b0.motion.speed * factor)
    assert p.robot("R2") == task(4).robot("R2")
    assert p.rate(p.robot("R2").behaviors[0]) == 10.0


def test_apply_rate_can_scale_every_section_keeping_the_step_per_command():
    p = apply_rate(task(4), "R1", 23.0, scale="all")
    for b0, b1 in zip(task(4).robot("R1").behaviors, p.robot("R1").behaviors, strict=True):
        assert b1.motion.speed == pytest.approx(b0.motion.speed * 2.3)
        assert b1.motion.speed / 23.0 == pytest.approx(b0.motion.speed / 10.0)
    with pytest.raises(ValueError, match="scale"):
        apply_rate(task(4), "R1", 23.0, scale="arm")


def test_apply_rate_keeps_a_base_that_runs_with_another_section_at_its_speed():
    p, _ = parallelize(task(4), T4)  # R1's approach runs with its lowering
    q = apply_rate(p, "R1", 23.0)
    assert (
        q.robot("R1").behavior("approach").motion.speed
        == p.robot("R1").behavior("approach").motion.speed
    )
    assert q.robot("R1").behavior("pull_out").motion.speed == pytest.approx(2.15e-3 * 2.3)
    assert apply_rate(p, "R1", 23.0, scale="all").robot("R1").behavior(
        "approach"
    ).motion.speed == pytest.approx(1.05e-2 * 2.3)


def test_apply_rate_per_behavior():
    p = apply_rate(task(4), "R1", {"approach": 20.0, "pull_out": 15.0})
    r0, r1 = task(4).robot("R1"), p.robot("R1")
    assert [b.rate_hz for b in r1.behaviors] == [None, 20.0, 15.0, None]
    assert r1.behavior("approach").motion.speed == pytest.approx(
        r0.behavior("approach").motion.speed * 2.0
    )
    assert r1.behavior("lower_arm") == r0.behavior("lower_arm")


EVENTS = sorted(set(task(1).events() + task(3).events() + task(4).events()))


@given(
    n=st.sampled_from([1, 2, 3, 4]), d=st.dictionaries(st.sampled_from(EVENTS), st.floats(1, 100))
)
def test_parallelization_only_relaxes_the_order(n, d):
    """Events are kept (absorbed ones become markers), no precedence is added, and every
    explicit synchronisation (waits_for, after) still orders its events."""
    p0 = task(n)
    p1, done = parallelize(p0, d)
    assert p1.events() == p0.events()
    before, after = precedence(p0), precedence(p1)
    for e in p0.events():
        assert after[e] <= before[e]
    direct = direct_predecessors(p1)
    for r in p1.robots:
        for b in r.behaviors:
            e = f"{r.name}.{b.name}"
            assert set(b.waits_for) <= after[e]
            if b.event.after:
                assert b.event.after in direct[e]
    for x in done:
        r = p1.robot(x.robot)
        assert not r.gating(r.index(x.absorbed))
        assert d[f"{x.robot}.{x.absorbed}"] < d[f"{x.robot}.{x.host}"]


def test_slack_waits_are_those_the_measured_run_did_not_need():
    """R1's pull-out waits for R2's grip: slack when the grip fired before R1's approach
    ended, needed when after; R2's release waits for the pull-out, which fired last."""
    spans = {
        "R1.lower_arm": (0.0, 57.0),
        "R1.approach": (57.0, 123.0),
        "R1.pull_out": (123.0, 254.0),
        "R1.raise_arm": (254.0, 259.0),
        "R2.approach": (0.0, 25.0),
        "R2.grip": (25.0, 54.0),
        "R2.release": (254.0, 257.0),
    }
    (slack,) = slack_waits(task(4), spans)
    assert slack.describe() == "R1: pull_out no longer waits for R2.grip"
    relaxed = relax(task(4), slack)
    assert relaxed.robot("R1").behavior("pull_out").waits_for == ()
    assert restore(relaxed, slack) == task(4)
    late = spans | {"R2.grip": (25.0, 130.0)}
    assert slack_waits(task(4), late) == []
