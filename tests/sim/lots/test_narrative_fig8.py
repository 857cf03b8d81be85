"""Narrative fig8 end to end in the workcell (`tests/sim/lots/narratives.py`)."""

from __future__ import annotations

import pytest

from tests.sim.lots.narratives import DETECTORS, kinds, run_narrative


@pytest.mark.slow
@pytest.mark.paper  # a whole narrative of the paper (2-5 min): make test-paper
@pytest.mark.parametrize("detector", DETECTORS)
def test_fig8_scissors_moved_by_the_person_are_used_and_the_robots_pair_is_discarded(detector):
    """The person moves the other scissors to W^B while the robot carries one; the robot
    drops its pair into the waste basket and brings the hammer. Carrying the hammer, it
    looks at W^B with the person's scissors hidden under the hammer's band: perception keeps
    them (occluded), so the robot places the hammer instead of taking the scissors for gone."""
    r = run_narrative("fig8", detector)
    assert r.satisfied and r.exit_code == 0
    (moved,) = r.person_actions
    assert moved.outcome == "done" and moved.uid.startswith("scissors")
    assert (moved.src, moved.dst) == ("A", "B")
    assert kinds(r) == [("move", "p1"), ("discard_held", "scissors"), ("move", "p3")]
    assert r.final_counts["B"] == {"saw": 1, "scissors": 1, "hammer": 1}
    assert r.final_counts["waste"] == {"scissors": 1}
    assert r.final_counts["A"] == {}
