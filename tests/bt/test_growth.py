"""Growth (Alg. 2-3), conflicts, recovery and the paper's Cases 1-3 in the symbolic world."""

from __future__ import annotations

import copy

import pytest

from tamp import scenarios
from tamp.bt import (
    Appear,
    Condition,
    Fail,
    PaBtExecutor,
    ReactiveFallback,
    SymbolicWorld,
)
from tamp.bt.free_area import choose_free_area
from tamp.bt.run import execute, execute_plan
from tamp.demo import load_demonstration
from tamp.rg import plan
from tamp.world import (
    Area,
    IsAreaFree,
    IsGraspedObject,
    IsHandFree,
    IsObjectAt,
    ObjectState,
    Point,
    Pose,
    WorldState,
    default_domain,
)
from tamp.world.actions import ActionTemplate, CondPattern, Domain
from tamp.world.events import AtTick
from tamp.world.interface import Status
from tamp.world.outcomes import ScriptedOutcomes

from .helpers import case3_by_hand


def _names(actions) -> list[str]:
    return [str(a) for a in actions]


def _moves(actions) -> list[str]:
    """Pick/Place only (MoveTo is skipped when the robot is already within reach)."""
    return [str(a) for a in actions if a.name != "MoveTo"]


def _case(name: str):
    demo = load_demonstration(scenarios.path(name))
    return demo, plan(demo)


OA = Point(2.2, 0.8, 0.1)  # Case 3's O_a, on l_1


# -- the paper's cases ---------------------------------------------------------------------
def test_case1_executes_o2_o1_o0() -> None:
    demo, result = _case("case1.yaml")
    report = execute_plan(demo, result.c_goal)
    assert report.reached
    assert _moves(report.executed) == [
        "Pick(O2)", "Place(O2, L2)", "Pick(O1)", "Place(O1, L1)", "Pick(O0)", "Place(O0, L0)",
    ]  # fmt: skip
    for c in result.c_goal:
        assert c.holds(report.final)
    assert report.stats["conflicts"] == 0 and report.stats["recoveries"] == 0


def test_case2_executes_r1_to_r4_and_keeps_earlier_goals_done() -> None:
    demo, result = _case("case2.yaml")
    report = execute_plan(demo, result.c_goal)
    assert report.reached
    # R1 O1->G1, R2 O0->G0, R3 O1->G3, R4 O0->G2 (§V-C3)
    assert _moves(report.executed) == [
        "Pick(O1)", "Place(O1, L1)", "Pick(O0)", "Place(O0, L0)",
        "Pick(O1)", "Place(O1, L3)", "Pick(O0)", "Place(O0, L2)",
    ]  # fmt: skip
    final = report.final
    assert IsObjectAt("O1", "L3").holds(final) and IsObjectAt("O0", "L2").holds(final)
    # the intermediate goals were reached and then (on purpose) undone
    assert not IsObjectAt("O1", "L1").holds(final)
    assert report.goals_reached == 4


CASE3_MOVES = [
    "Pick(O0)", "Place(O0, L0)", "Pick(O1)",
    # discovery of O_a at l_1: O_1 goes to l_free2, O_a to l_free1, then O_1 to l_1 (§V-D2)
    "Place(O1, free2)", "Pick(Oa)", "Place(Oa, free1)", "Pick(O1)", "Place(O1, L1)",
]  # fmt: skip


def test_case3_discovers_oa_and_recovers_as_in_the_paper() -> None:
    demo, result = _case("case3.yaml")
    report = execute_plan(demo, result.c_goal, events=[Appear("Oa", OA)])
    assert report.reached, report.reason
    assert _moves(report.executed) == CASE3_MOVES
    names = _names(report.executed)
    assert names.index("MoveTo(L1)") < names.index("Place(O1, free2)")  # found on arrival
    final = report.final
    assert IsObjectAt("O0", "L0").holds(final) and IsObjectAt("O1", "L1").holds(final)
    assert IsObjectAt("Oa", "free1").holds(final) and final.held is None
    s = report.stats
    assert s["recoveries"] == 1 and s["conflicts"] == 1 and s["conflict_moves"] == 2
    conflict = next(e for e in report.growth if e["kind"] == "conflict")
    assert "undoes IsGraspedObject(O1)" in conflict["why"]
    assert "moved up 2" in conflict["detail"]
    appear = [e for e in report.world_events if e["kind"] == "appear"]
    assert len(appear) == 1


def test_case3_by_hand_full_sequence_with_every_move() -> None:
    state, free = case3_by_hand()
    c_goal = [IsObjectAt("O0", "L0"), IsObjectAt("O1", "L1")]
    report = execute(state, c_goal, free_areas=free, events=[Appear("Oa", OA)])
    assert report.reached, report.reason
    assert _names(report.executed) == [
        "MoveTo(O0)", "Pick(O0)", "Place(O0, L0)",
        "MoveTo(O1)", "Pick(O1)", "MoveTo(L1)",
        "MoveTo(free2)", "Place(O1, free2)",
        "MoveTo(Oa)", "Pick(Oa)", "MoveTo(free1)", "Place(Oa, free1)",
        "MoveTo(O1)", "Pick(O1)", "MoveTo(L1)", "Place(O1, L1)",
    ]  # fmt: skip


def test_case3_obstacle_present_from_the_start_is_cleared_first() -> None:
    demo, result = _case("case3.yaml")
    report = execute_plan(demo, result.c_goal, events=[Appear("Oa", OA, AtTick(0))])
    assert report.reached
    ex = _names(report.executed)
    # the hand is free when the blocked place is first planned: no detour for O1
    place_oa = next(i for i, a in enumerate(ex) if a.startswith("Place(Oa, free"))
    assert place_oa < ex.index("Pick(O1)")
    assert "Place(O1, free1)" not in ex and "Place(O1, free2)" not in ex
    assert IsObjectAt("O1", "L1").holds(report.final)


# -- failures, retries and limits ----------------------------------------------------------
def test_pick_that_fails_once_is_retried() -> None:
    demo, result = _case("case1.yaml")
    report = execute_plan(demo, result.c_goal, failures=[Fail("Pick", ("O1",), 1)])
    assert report.reached
    picks = [a for a in report.attempts if a["action"] == "Pick" and a["args"] == ["O1"]]
    assert [p["status"] for p in picks] == ["FAILURE", "SUCCESS"]
    assert report.stats["retries"] == 1


def test_persistent_failure_stops_with_a_reason_after_max_retries() -> None:
    demo, result = _case("case1.yaml")
    report = execute_plan(demo, result.c_goal, failures=[Fail("Pick", ("O1",), 99)], max_retries=2)
    assert report.status is Status.FAILURE
    assert "Pick(O1) failed 3 times" in report.reason
    picks = [a for a in report.attempts if a["action"] == "Pick" and a["args"] == ["O1"]]
    assert len(picks) == 3


def test_cancelled_skills_are_reported_and_never_overlap() -> None:
    state, free = case3_by_hand()
    c_goal = [IsObjectAt("O1", "L1")]
    report = execute(
        state,
        c_goal,
        free_areas=free,
        events=[Appear("O1", Point(2.15, 0.85, 0.1), AtTick(3))],
        skill_ticks=3,
    )
    assert report.reached
    # the person put O1 into L1 while the robot was on its way: the guard holds, the
    # running MoveTo is cancelled and nothing else runs
    assert [a["status"] for a in report.attempts] == ["CANCELLED"]
    assert report.world.violations == 0


# -- growth details ------------------------------------------------------------------------
def test_initial_tree_is_a_memory_sequence_of_c_goal() -> None:
    goals = [IsObjectAt("O1", "L1"), IsObjectAt("O0", "L0")]
    ex = PaBtExecutor(goals)
    assert ex.root.describe() == "SequenceWithMemory"
    assert [c.pred for c in ex.root.children] == goals
    assert all(isinstance(c, Condition) for c in ex.root.children)


def test_expansion_keeps_every_achieving_template_under_a_priority_fallback() -> None:
    base = default_domain()
    push = ActionTemplate(
        "Push",
        (("o", "object"), ("l", "area")),
        (CondPattern("IsHandFree", ()), CondPattern("IsRobotCloseTo", ("o",))),
        (CondPattern("IsObjectAt", ("o", "l")),),
        duration=3.0,
        success_rate=0.5,
    )
    domain = Domain("test", {**base.templates, "Push": push})
    state, free = case3_by_hand()
    ex = PaBtExecutor([IsObjectAt("O1", "L1")], domain, free_areas=free)
    world = SymbolicWorld(state, outcomes=ScriptedOutcomes([Fail("Place", ("O1", "L1"), 99)]))
    ex.tick(world)
    rf = ex.root.children[0]
    assert isinstance(rf, ReactiveFallback)
    pf = rf.children[1]
    actions = [str(rs.children[-1].action) for rs in pf.children]
    assert actions == ["Place(O1, L1)", "Push(O1, L1)"]
    assert [pf.priorities[i] for i in pf.order] == [0.95, 0.5]
    # Place(O1, L1) always fails: its priority halves, Push ranks first next time.
    status = ex.run(world, step=world.step)
    assert status is Status.SUCCESS, ex.reason
    assert str(ex.executed[-1]) == "Push(O1, L1)"
    assert pf.priorities == [0.475, 0.5]
    assert any(e.kind == "priority" and e.why == "failed" for e in ex.log)


def test_growth_is_logged_with_what_and_why() -> None:
    demo, result = _case("case3.yaml")
    report = execute_plan(demo, result.c_goal, events=[Appear("Oa", OA)])
    kinds = [e["kind"] for e in report.growth]
    assert kinds[0] == "expand" and "recovery" in kinds and "conflict" in kinds
    rec = next(e for e in report.growth if e["kind"] == "recovery")
    assert rec["condition"] == "IsAreaFree(L1)" and rec["detail"] == "IsObjectAt(Oa, free1)"
    pre = [e for e in report.growth if e["why"].startswith("precondition of Pick(Oa)")]
    assert pre and pre[0]["detail"] == "Place(O1, free2)"


def test_parent_links_stay_consistent_after_growth_and_conflict_moves() -> None:
    demo, result = _case("case3.yaml")
    report = execute_plan(demo, result.c_goal, events=[Appear("Oa", OA)])
    root = report.executor.root
    seen = set()
    for n in root.walk():
        assert id(n) not in seen
        seen.add(id(n))
        for c in n.children:
            assert c.parent is n
    assert root.parent is None


def test_unresolvable_conflict_stops_with_an_explanation() -> None:
    """Teleport needs IsHandFree() and IsGraspedObject(o) at once: no order satisfies both."""
    base = default_domain()
    teleport = ActionTemplate(
        "Teleport",
        (("o", "object"), ("l", "area")),
        (CondPattern("IsHandFree", ()), CondPattern("IsGraspedObject", ("o",))),
        (CondPattern("IsObjectAt", ("o", "l")),),
    )
    templates = {k: v for k, v in base.templates.items() if k != "Place"}
    templates["Teleport"] = teleport
    # Place is still needed to free the hand: keep a version that does not reach IsObjectAt.
    templates["Drop"] = ActionTemplate(
        "Drop",
        (("o", "object"), ("l", "area")),
        (CondPattern("IsGraspedObject", ("o",)),),
        (CondPattern("IsHandFree", ()),),
    )
    domain = Domain("test", templates)
    state, free = case3_by_hand()
    report = execute(state, [IsObjectAt("O1", "L1")], free_areas=free, domain=domain)
    assert report.status is Status.FAILURE
    assert "unresolvable conflict" in report.reason
    assert report.ticks < 50  # stopped, did not loop


def test_condition_without_template_or_recovery_fails_cleanly() -> None:
    domain = Domain("test", {"MoveTo": default_domain().template("MoveTo")})
    state, free = case3_by_hand()
    report = execute(state, [IsGraspedObject("O1")], free_areas=free, domain=domain)
    assert report.status is Status.FAILURE
    assert "no action template achieves IsGraspedObject(O1)" in report.reason


def test_two_blockers_are_both_moved_to_distinct_free_areas() -> None:
    state, free = case3_by_hand()
    state = state.with_object_at("Ob", Pose.at(2.25, 0.8, 0.1))
    c_goal = [IsObjectAt("O1", "L1")]
    report = execute(
        state, c_goal, free_areas=free, events=[Appear("Oa", Point(2.15, 0.8, 0.1), AtTick(0))]
    )
    assert report.reached, report.reason
    final = report.final
    assert IsAreaFree("L1").holds(final.with_held("O1")) is False or final.held is None
    placed = {
        o: a
        for a in ("free1", "free2", *report.stats["free_areas_found"])
        for o in ("Oa", "Ob")
        if IsObjectAt(o, a).holds(final)
    }
    assert set(placed) == {"Oa", "Ob"} and len(set(placed.values())) == 2
    assert IsObjectAt("O1", "L1").holds(final)


def test_ring_search_when_no_demonstration_free_area_is_left() -> None:
    state, _ = case3_by_hand()
    report = execute(state, [IsObjectAt("O1", "L1")], free_areas=[], events=[Appear("Oa", OA)])
    assert report.reached, report.reason
    found = report.stats["free_areas_found"]
    assert found and all(name.startswith("free_auto") for name in found)
    for name in found:
        area = report.final.area(name)
        for goal in ("L0", "L1"):
            assert not area.overlaps(report.final.area(goal))


def test_executor_deepcopy_resumes_identically() -> None:
    demo, result = _case("case3.yaml")
    world = SymbolicWorld(demo.initial_world(), events=[Appear("Oa", OA)])
    ex = PaBtExecutor(result.c_goal, free_areas=[a.name for a in demo.free_areas])
    while ex.tick_id < 12 or ex.running is None:
        world.step()
        ex.tick(world)
    twin_ex, twin_world = copy.deepcopy((ex, world))
    assert twin_ex.root is not ex.root and twin_ex.domain is ex.domain
    assert twin_ex.running is not ex.running
    assert any(n is twin_ex.running for n in twin_ex.root.walk())
    for n in twin_ex.root.walk():
        for c in n.children:
            assert c.parent is n
    a = ex.run(world, step=world.step)
    b = twin_ex.run(twin_world, step=twin_world.step)
    assert a is b is Status.SUCCESS
    assert _names(ex.executed) == _names(twin_ex.executed)


# -- free-area rule ------------------------------------------------------------------------
def test_free_area_rule_nearest_valid_demonstration_area() -> None:
    state, free = case3_by_hand()
    state = state.with_robot_at(Pose.at(2.2, 0.8))
    area = choose_free_area(state, candidates=free, goal_areas=["L0", "L1"], freeing="L1")
    assert area.name == "free2"
    area = choose_free_area(
        state, candidates=free, goal_areas=["L0", "L1"], freeing="L1", reserved=["free2"]
    )
    assert area.name == "free1"
    # an object on free1 makes it invalid
    busy = state.with_object_at("Ox", Pose.at(0.8, 1.7))
    area = choose_free_area(
        busy, candidates=free, goal_areas=["L0", "L1"], freeing="L1", reserved=["free2"]
    )
    assert area.name.startswith("free_auto")


def test_free_area_overlapping_a_goal_area_is_never_chosen() -> None:
    r = 0.15
    state = WorldState(
        robot=Pose.at(0, 0),
        objects={"O1": ObjectState("O1", Pose.at(3.0, 0.0))},
        areas={
            "L1": Area("L1", Point(1.0, 0.0), r),
            "bad": Area("bad", Point(1.2, 0.0), r),
            "good": Area("good", Point(-2.0, 0.0), r),
        },
    )
    area = choose_free_area(state, candidates=["bad", "good"], goal_areas=["L1"])
    assert area.name == "good"


@pytest.mark.parametrize("ticks", [0, 1, 3])
def test_case3_result_does_not_depend_on_skill_duration(ticks: int) -> None:
    demo, result = _case("case3.yaml")
    report = execute_plan(demo, result.c_goal, events=[Appear("Oa", OA)], skill_ticks=ticks)
    assert report.reached
    assert _moves(report.executed) == CASE3_MOVES


def test_hand_free_is_achieved_by_placing_the_held_object() -> None:
    state, free = case3_by_hand()
    state = state.with_held("O0")
    report = execute(state, [IsHandFree()], free_areas=free)
    assert report.reached
    assert report.executed[-1].name == "Place" and report.executed[-1].args[0] == "O0"


def test_livelock_between_two_places_is_detected_and_stops() -> None:
    """Weld(o, a, b) needs the robot close to areas a and b at once, and they are ~2 m apart:
    MoveTo(b) undoes IsRobotCloseTo(a), which the predicates cannot see as a conflict
    (proximity is geometry); the executor notices the same action starting again from a
    state it already succeeded from, and stops instead of looping."""
    weld = ActionTemplate(
        "Weld",
        (("o", "object"), ("a", "area"), ("b", "area")),
        (CondPattern("IsRobotCloseTo", ("a",)), CondPattern("IsRobotCloseTo", ("b",))),
        (CondPattern("IsGraspedObject", ("o",)),),
    )
    domain = Domain("test", {"MoveTo": default_domain().template("MoveTo"), "Weld": weld})
    state, _ = case3_by_hand()
    # the unbound areas a, b are filled by the free-area rule: here L0 first, then L1
    report = execute(state, [IsGraspedObject("O1")], free_areas=["L0", "L1"], domain=domain)
    assert report.status is Status.FAILURE
    assert report.reason.startswith("livelock: MoveTo(")
    moves = _names(report.executed)
    assert moves[:3] == ["MoveTo(L0)", "MoveTo(L1)", "MoveTo(L0)"]
    assert len(moves) <= 6


def test_snapshot_restore_replays_the_same_run_and_state_key_tracks_it() -> None:
    demo, result = _case("case3.yaml")
    world = SymbolicWorld(demo.initial_world(), events=[Appear("Oa", OA)])
    ex = PaBtExecutor(result.c_goal, free_areas=[a.name for a in demo.free_areas])
    while ex.tick_id < 12:
        world.step()
        ex.tick(world)
    snap, key, at = ex.snapshot(history=False), ex.state_key(), copy.deepcopy(world)
    assert ex.log and not snap.executor.log  # report-only history left out
    first = ex.run(world, step=world.step)
    done = [str(a) for a in ex.executed]
    assert ex.state_key() != key
    ex.restore(snap)
    assert ex.state_key() == key and ex.result is None
    again = ex.run(at, step=at.step)
    assert first is again is Status.SUCCESS
    assert done[-len(ex.executed) :] == [str(a) for a in ex.executed]
    assert at.observe() == world.observe()
    ex.restore(snap)  # a snapshot restores any number of times
    assert ex.state_key() == key
