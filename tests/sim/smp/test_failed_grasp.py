"""A lost grasp is seen on the plant, reported as FAILURE, and the tree picks again."""

from __future__ import annotations

import math

import pytest

from .helpers import Track, verified_runner, write_one_bottle

pytestmark = pytest.mark.slow  # a Drake simulation run


def test_failed_grasp_is_retried(tmp_path):
    path = write_one_bottle(tmp_path, "fail: ['Pick(O0)']\n")
    scenario, system, runner = verified_runner(path)
    track = Track()
    welds: list[tuple[float, object]] = []

    def record(t: float) -> None:
        track.times.append(t)
        track.poses.append(runner.object_poses())
        welds.append((t, runner.active))

    result = runner.run(on_chunk=record)
    assert result.status == "SUCCESS", result.reason
    picks = [a for a in result.actions if a.action == "Pick(O0)"]
    assert [p.status for p in picks][:2] == ["FAILURE", "SUCCESS"]
    assert "lost" in picks[0].detail
    failed = picks[0]
    # during the failed attempt no weld was on and the bottle stayed on the floor (plant)
    half = scenario.object("O0").kind.half_height
    during = [k for k, t in enumerate(track.times) if failed.start <= t <= failed.end]
    assert during
    assert all(welds[k][1] is None for k in during)
    assert max(track.poses[k]["O0"].z for k in during) < half + 0.01
    # the retry lifted it (weld on) and it ends resting in its goal area
    assert any(w == ("O0", 0) or w == ("O0", 1) for _, w in welds)
    area = system.areas["L0"]
    p = result.final_poses["O0"]
    assert math.hypot(p.x - area.pos.x, p.y - area.pos.y) <= area.radius
    assert abs(p.z - half) < 0.01
    tree = system.executor.policy(system.executor.GetMyContextFromRoot(runner.root))
    assert tree.stats.retries >= 1
