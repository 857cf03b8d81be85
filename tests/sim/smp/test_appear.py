"""An object a person puts down at a time: unseen before, seen after, and the tree recovers
(with no free area in the demonstration, the tree finds free areas itself)."""

from __future__ import annotations

import math

import pytest

from .helpers import verified_runner, write_one_bottle

pytestmark = pytest.mark.slow  # Drake simulation runs


def test_obstacle_appearing_at_a_time_is_cleared_from_the_goal(tmp_path):
    path = write_one_bottle(
        tmp_path, "objects:\n  - {id: Oa, model: obstacle}\nappear: ['Oa@L0@t=3']\n"
    )
    scenario, system, runner = verified_runner(path)
    seen: list[tuple[float, bool]] = []
    est_ctx = system.estimator.GetMyContextFromRoot(runner.root)

    def record(t: float) -> None:
        world = system.estimator.world_state_port.Eval(est_ctx)
        seen.append((t, "Oa" in world.objects))

    result = runner.run(on_chunk=record)
    assert result.status == "SUCCESS", result.reason
    assert abs(result.appeared["Oa"] - 3.0) < 1e-9
    assert not any(s for t, s in seen if t < 3.0 - 1e-9)
    assert all(s for t, s in seen if t >= 3.0)
    l0 = system.areas["L0"]
    o0, oa = result.final_poses["O0"], result.final_poses["Oa"]
    assert math.hypot(o0.x - l0.pos.x, o0.y - l0.pos.y) <= l0.radius
    assert abs(o0.z - 0.1) < 0.01
    assert math.hypot(oa.x - l0.pos.x, oa.y - l0.pos.y) > l0.radius + 0.05
    assert abs(oa.z - 0.075) < 0.01  # resting on the floor, upright
    placed = [a.action for a in result.actions if a.status == "SUCCESS"]
    assert any(a.startswith("Place(Oa, free_auto") for a in placed)
    assert placed[-1] == "Place(O0, L0)"


def test_object_without_when_appears_once_the_robot_is_within_reach(tmp_path):
    """``--appear Y@L0`` (no WHEN): a person puts Y on l_0 when the robot gets there (§V-D2)."""
    path = write_one_bottle(tmp_path, "objects:\n  - {id: Y, model: obstacle}\nappear: ['Y@L0']\n")
    scenario, system, runner = verified_runner(path)
    reach = scenario.demo.domain().reach
    l0 = system.areas["L0"].pos
    distance: list[tuple[float, float]] = []

    def record(t: float) -> None:
        x, y, _ = runner.robot_pose()
        distance.append((t, math.hypot(l0.x - x, l0.y - y)))

    result = runner.run(on_chunk=record)
    assert result.status == "SUCCESS", result.reason
    t_appear = result.appeared["Y"]
    first_close = next(t for t, d in distance if d <= reach)
    assert t_appear == first_close > 0  # not before: the robot starts 1.2 m away
    placed = [a.action for a in result.actions if a.status == "SUCCESS"]
    assert any(a.startswith("Place(Y, ") for a in placed) and placed[-1] == "Place(O0, L0)"
