"""Narrative example1 end to end in the workcell (`tests/sim/lots/narratives.py`)."""

from __future__ import annotations

import pytest

from tests.sim.lots.narratives import kinds, run_narrative


@pytest.mark.slow
def test_example1_screwdriver_moved_early_is_replanned_and_completed():
    """The person puts the screwdriver into W^B before the first action: the robot replans
    (Alg. 3), takes the screwdriver out again, and completes the automaton's order. No
    object it placed is taken for gone while it carries the next one."""
    r = run_narrative("example1")
    assert r.satisfied and r.exit_code == 0
    (moved,) = r.person_actions
    assert moved.outcome == "done" and moved.uid.startswith("screwdriver")
    assert r.replans >= 1
    actions = kinds(r)
    assert ("remove", "screwdriver") in actions
    assert sorted(p for k, p in actions if k == "move") == ["p1", "p2", "p3", "p4"]
    assert not [k for k in actions if k[0] == "return_held"]
    assert r.final_counts["B"] == {"hammer": 1, "screw": 2, "screwdriver": 1}
    assert r.final_counts["A"] == {}
