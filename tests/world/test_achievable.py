"""The structural check: goal conditions no action template can make true."""

from __future__ import annotations

from dataclasses import replace

from tamp.demo import load_demonstration
from tamp.scenarios import path
from tamp.world.achievable import possible_predicates, unachievable_goals
from tamp.world.actions import default_domain
from tamp.world.geometry import Pose
from tamp.world.predicates import IsObjectAt


def _case1():
    demo = load_demonstration(path("case1.yaml"))
    goals = [IsObjectAt(g.object, g.area.name) for g in demo.goals]
    return demo.initial_world(), goals


def test_the_youbot_domain_achieves_every_goal():
    state, goals = _case1()
    assert unachievable_goals(default_domain(), goals, state) == []


def test_without_place_no_template_has_the_effect():
    state, goals = _case1()
    d = default_domain()
    no_place = replace(d, templates={k: t for k, t in d.templates.items() if k != "Place"})
    bad = unachievable_goals(no_place, goals, state)
    assert [u.goal for u in bad] == goals
    assert "has IsObjectAt among its effects" in bad[0].reason


def test_without_pick_place_can_never_run():
    state, goals = _case1()
    d = default_domain()
    no_pick = replace(d, templates={k: t for k, t in d.templates.items() if k != "Pick"})
    assert "IsGraspedObject" not in possible_predicates(no_pick, state)
    bad = unachievable_goals(no_pick, goals, state)
    assert len(bad) == len(goals) and "Place needs IsGraspedObject(o)" in bad[0].reason


def test_a_goal_true_at_the_start_needs_no_action():
    state, goals = _case1()
    goal = goals[0]
    state = state.with_object_at(goal.obj, Pose(state.areas[goal.area].pos))
    assert goal.holds(state)
    d = default_domain()
    only_move = replace(d, templates={"MoveTo": d.templates["MoveTo"]})
    assert [u.goal for u in unachievable_goals(only_move, goals, state)] == goals[1:]
