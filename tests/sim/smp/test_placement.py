"""Where objects stand, in 3-D (`tamp.sim.smp.placement`), which objects a run left
disturbed (`disturbances`), and the one verdict of a run (`tamp.sim.smp.runner.judge`): no
simulation needed."""

from __future__ import annotations

import math

import pytest

from tamp.sim.core.outcome import CAUSES, run_cause
from tamp.sim.smp.placement import (
    MOVE_TOL,
    ON_FLOOR_TOL,
    TILT_TOL,
    Body,
    blocker,
    disturbances,
    free_spot,
    why_not_in,
)
from tamp.sim.smp.robot import OBJECT_KINDS
from tamp.world.geometry import Area, Point
from tamp.world.interface import Status

BOTTLE = OBJECT_KINDS["bottle"]
BOX = OBJECT_KINDS["obstacle"]
L0 = Area("L0", Point(1.0, 0.7), 0.15)
WORKSPACE = (-1.0, 2.5, -1.5, 2.0)


def test_an_object_on_top_of_another_is_not_in_the_area():
    """Issue 17: O0 pushed up onto O_a rests at z = 0.25 m inside L0's circle: not at L0."""
    oa = Body("Oa", 1.02, 0.7, BOX.half_height, BOX)
    o0 = Body("O0", 1.0, 0.71, 2 * BOX.half_height + BOTTLE.half_height, BOTTLE)
    why = why_not_in(o0, L0, [oa, o0])
    assert why is not None and "not resting on the floor" in why and "on top of Oa" in why
    assert "z = 0.250 m" in why
    assert why_not_in(Body("O0", 1.0, 0.71, BOTTLE.half_height, BOTTLE), L0) is None
    assert why_not_in(Body("O0", 1.0, 0.71, 0.1 + ON_FLOOR_TOL * 0.9, BOTTLE), L0) is None
    fallen = Body("O0", 1.0, 0.7, BOTTLE.radius, BOTTLE)  # lying on its side
    assert "not resting on the floor" in why_not_in(fallen, L0)
    outside = Body("O0", 1.0, 0.7 + 0.151, BOTTLE.half_height, BOTTLE)
    assert why_not_in(outside, L0) == "O0 ended outside L0"


def test_a_bottle_leaning_in_the_area_is_not_in_it():
    """A bottle tilted 32° on its bottom rim (as a slipped friction grasp leaves it) has its
    centre 3 mm above its upright height: on the floor by height alone, not upright."""
    tilt = math.radians(32)
    z = BOTTLE.half_height * math.cos(tilt) + BOTTLE.radius * math.sin(tilt)
    assert abs(z - BOTTLE.half_height) < ON_FLOOR_TOL
    leaning = Body("O1", 1.0, 0.7, z, BOTTLE, tilt=tilt)
    assert why_not_in(leaning, L0) == "O1 is not upright in L0 (tilt 32°)"
    assert why_not_in(Body("O1", 1.0, 0.7, z, BOTTLE, tilt=TILT_TOL), L0) is None
    assert _reasons([leaning], {}, picked={"O1"}) == {"O1": "O1 knocked over (tilt 32°)"}


def test_blocker_sees_footprints_the_robot_and_not_what_is_carried_above():
    o1 = Body("O1", 1.0, 0.7, BOTTLE.half_height, BOTTLE)
    assert blocker(1.0, 0.7, BOX, [o1]) == "O1"
    assert blocker(1.05, 0.7, BOX, [o1]) == "O1"  # footprints overlap (0.035 + 0.049)
    assert blocker(1.2, 0.7, BOX, [o1]) is None
    carried = Body("O1", 1.0, 0.7, 2 * BOX.half_height + BOTTLE.half_height + 0.01, BOTTLE)
    assert blocker(1.0, 0.7, BOX, [carried]) is None  # held high: the box fits under it
    lifted = Body("O1", 1.0, 0.7, BOTTLE.half_height + 0.06, BOTTLE)  # just lifted
    assert blocker(1.0, 0.7, BOX, [lifted]) == "O1"
    assert blocker(1.0, 0.7, BOX, [], robot=(1.2, 0.7, 0.345)) == "the robot"
    assert blocker(1.0, 0.7, BOX, [], robot=(1.5, 0.7, 0.345)) is None


def test_free_spot_is_the_nearest_outside_every_area_and_footprint():
    o0 = Body("O0", 1.0, 0.7, BOTTLE.half_height, BOTTLE)
    other = Area("L1", Point(1.35, 0.7), 0.15)  # blocks the +x side
    areas = {"L0": L0, "L1": other}
    spot = free_spot(1.0, 0.7, BOX, bodies=[o0], areas=areas, workspace=WORKSPACE)
    assert spot is not None
    x, y = spot
    for a in areas.values():
        assert math.hypot(x - a.pos.x, y - a.pos.y) >= a.radius + BOX.radius
    assert math.hypot(x - o0.x, y - o0.y) >= BOTTLE.radius + BOX.radius
    d = math.hypot(x - 1.0, y - 0.7)
    assert d == pytest.approx(0.25)  # first ring clear of L0 (0.15 + 0.049 + 0.01 gap)
    # on that ring, +x (0 deg) to 30 deg fall in L1; 45 deg is the first clear angle
    c = math.cos(math.pi / 4) * 0.25
    assert (x, y) == pytest.approx((1.0 + c, 0.7 + c))
    tiny = (0.9, 1.1, 0.6, 0.8)  # a workspace with no room outside L0
    assert free_spot(1.0, 0.7, BOX, bodies=[o0], areas=areas, workspace=tiny) is None


def test_one_verdict_decides_status_reason_and_exit():
    from tamp.sim.smp.runner import SimResult, judge

    assert judge(Status.SUCCESS, "every goal reached", [], 60) == ("SUCCESS", "every goal reached")
    status, reason = judge(Status.SUCCESS, "every goal reached", ["O0 is not resting"], 60)
    assert status == "FAILURE" and "the tree succeeded but on the plant O0 is not" in reason
    assert judge(Status.FAILURE, "", [], 60) == ("FAILURE", "tree failed")
    assert judge(None, "", [], 60)[0] == "TIMEOUT"
    for status in ("SUCCESS", "FAILURE", "TIMEOUT"):
        r = SimResult(
            scenario="x",
            status=status,
            sim_time=1.0,
            wall_time=1.0,
            grasp="weld",
            perception="truth",
        )
        data = r.to_json()
        assert data["status"] == status and data["ok"] is (status == "SUCCESS")
        assert r.exit_code == (0 if status == "SUCCESS" else 1)
        assert data["warnings"] == []


def _reasons(bodies, put, picked=()) -> dict[str, str]:
    return {d.id: d.reason for d in disturbances(bodies, put, picked)}


def test_an_obstacle_knocked_over_and_pushed_is_disturbed_though_the_goals_hold():
    """The noisy-detector false success: O1 rests in L1, O_a (never picked) lies on its side
    next to it, 3.4 cm up and 12 cm from where the person put it down."""
    o1 = Body("O1", 2.19, 0.79, BOTTLE.half_height, BOTTLE)
    oa = Body("Oa", 2.32, 0.81, 0.034, BOX, tilt=math.radians(91))
    put = {"O1": (2.0, 0.0), "Oa": (2.2, 0.8)}
    assert why_not_in(o1, Area("L1", Point(2.2, 0.8), 0.15), [o1, oa]) is None
    why = _reasons([o1, oa], put, picked={"O1"})
    assert why == {
        "Oa": "Oa knocked over (tilt 91°), moved 12.0 cm though the robot never picked it"
    }
    (d,) = disturbances([o1, oa], put, {"O1"})
    assert d.to_json() == {
        "object": "Oa",
        "reason": why["Oa"],
        "tilt_deg": 91.0,
        "on": [],
        "moved": pytest.approx(0.1204, abs=1e-4),
    }


def test_tilt_and_displacement_tolerances():
    put = {"Oa": (1.0, 0.7)}
    leaning = Body("Oa", 1.0, 0.7, BOX.half_height, BOX, tilt=TILT_TOL + 0.01)
    assert _reasons([leaning], put) == {"Oa": "Oa knocked over (tilt 11°)"}
    standing = Body("Oa", 1.0, 0.7, BOX.half_height, BOX, tilt=TILT_TOL - 0.01)
    assert _reasons([standing], put) == {}
    settled = Body("Oa", 1.0 + MOVE_TOL * 0.9, 0.7, BOX.half_height, BOX)
    assert _reasons([settled], put) == {}
    pushed = Body("Oa", 1.0, 0.7 + MOVE_TOL * 1.1, BOX.half_height, BOX)
    assert _reasons([pushed], put) == {"Oa": "Oa moved 3.3 cm though the robot never picked it"}
    assert _reasons([pushed], {}) == {}  # nobody put it anywhere known: nothing to compare


def test_objects_the_robot_relocated_pass_when_upright_on_the_floor():
    """PA-BT's obstacle relocation: O_a picked and put 1.5 m away is fine; the same object
    picked but left lying or on top of another is not."""
    put = {"Oa": (2.2, 0.8)}
    moved = Body("Oa", 0.3, 1.8, BOX.half_height, BOX)
    assert _reasons([moved], put, picked={"Oa"}) == {}
    lying = Body("Oa", 0.3, 1.8, BOX.radius, BOX, tilt=math.radians(88))
    assert _reasons([lying], put, picked={"Oa"}) == {"Oa": "Oa knocked over (tilt 88°)"}


def test_an_object_on_top_of_another_is_disturbed_and_names_what_it_stands_on():
    oa = Body("Oa", 1.02, 0.7, BOX.half_height, BOX)
    o0 = Body("O0", 1.0, 0.71, 2 * BOX.half_height + BOTTLE.half_height, BOTTLE)
    assert _reasons([oa, o0], {}, picked={"O0", "Oa"}) == {"O0": "O0 on top of Oa"}
    # on a box lying on its side: the box's reach is its half-diagonal, not its radius
    lying = Body("Oa", 1.1, 0.7, BOX.radius, BOX, tilt=math.pi / 2)
    up = Body("O0", 1.0, 0.7, 2 * BOX.radius + BOTTLE.half_height, BOTTLE)
    assert 0.1 > BOX.radius + BOTTLE.radius
    assert _reasons([lying, up], {}, picked={"O0", "Oa"}) == {
        "Oa": "Oa knocked over (tilt 90°)",
        "O0": "O0 on top of Oa",
    }
    # carried high with nothing under it: not on top of anything
    held = Body("O0", 1.5, 0.7, 0.4, BOTTLE)
    assert _reasons([oa, held], {}, picked={"O0"}) == {}


def test_the_judge_fails_a_run_that_left_an_object_disturbed():
    from tamp.sim.smp.runner import judge

    why = "Oa knocked over (tilt 91°), moved 12.3 cm though the robot never picked it"
    status, reason = judge(Status.SUCCESS, "every goal reached", [], 60, [why])
    assert status == "FAILURE" and reason == f"the tree succeeded but on the plant {why}"
    status, reason = judge(Status.SUCCESS, "", ["O1 ended outside L1"], 60, [why])
    assert reason == f"the tree succeeded but on the plant O1 ended outside L1; {why}"
    assert judge(Status.SUCCESS, "every goal reached", [], 60, [])[0] == "SUCCESS"
    assert judge(Status.FAILURE, "Pick(O1) failed", [], 60, [why]) == (
        "FAILURE",
        "Pick(O1) failed",
    )
    assert "disturbed" in CAUSES
    assert run_cause("FAILURE", [], False, disturbed=True) == "disturbed"
    assert run_cause("FAILURE", [], True, disturbed=True) == "placement_off"  # goals first
    assert run_cause("FAILURE", ["grasp_missed"], False) == "grasp_missed"


def test_picked_objects_are_the_successful_picks():
    from tamp.sim.core.executor import ActionLog
    from tamp.sim.smp.runner import picked_objects

    log = [
        ActionLog(0, "Pick(O1)", 0.0, 1.0, "SUCCESS"),
        ActionLog(1, "Pick(Oa)", 1.0, 2.0, "FAILURE"),
        ActionLog(2, "Place(O1, L1)", 2.0, 3.0, "SUCCESS"),
        ActionLog(3, "MoveTo(O0)", 3.0, 4.0, "HALTED"),
    ]
    assert picked_objects(log) == {"O1"}
