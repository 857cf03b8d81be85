"""Narrative example1 end to end in the workcell (`tests/sim/lots/narratives.py`): Zhou et
al.'s Example 1 as the paper writes it (Fig. 3-4): no person, only the paper's actions."""

from __future__ import annotations

import pytest

from tests.sim.lots.narratives import DETECTORS, kinds, run_narrative


@pytest.mark.slow
@pytest.mark.paper  # a whole narrative of the paper (2-5 min): make test-paper
@pytest.mark.parametrize("detector", DETECTORS)
def test_example1_round_in_the_papers_order_hammer_screw_screwdriver_screw(detector):
    """GF p1 & GF p2 & GF p3 & GF p4 with p1 the hammer, p2 and p4 the first and the second
    screw, p3 the screwdriver: the robot delivers one round in the paper's order, p1, p2, p3,
    p4, each a pick in W^A and a place in W^B's basket, with no replan, nothing discarded or
    put back; the run's word is accepted and W^A ends empty."""
    r = run_narrative("example1", detector)
    assert r.satisfied and r.exit_code == 0 and r.word_accepted
    assert r.person_actions == [] and r.safety_stops == []  # nobody in the cell
    assert r.replans == 0
    assert kinds(r) == [("move", "p1"), ("move", "p2"), ("move", "p3"), ("move", "p4")]
    classes = [a.cls for a in r.robot_actions]
    assert classes == ["hammer", "screw", "screwdriver", "screw"]
    assert r.final_counts["B"] == {"hammer": 1, "screw": 2, "screwdriver": 1}
    assert r.final_counts["A"] == {} and r.final_counts["waste"] == {}
