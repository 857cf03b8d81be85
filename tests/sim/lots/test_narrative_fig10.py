"""Narrative fig10 end to end in the workcell (`tests/sim/lots/narratives.py`)."""

from __future__ import annotations

import pytest

from tests.sim.lots.narratives import kinds, run_narrative


@pytest.mark.slow
@pytest.mark.paper  # a whole narrative of the paper (2-5 min): make test-paper
def test_fig10_surplus_body_discarded_peak_put_back_body_rebuilt_car_ignored():
    """Fig. 10: the person builds the body, takes it away while the robot carries the peak,
    moves the robot's body back to W^A, adds a toy car. In the cell the hand's move after
    action 4 lands while the robot already carries the peak (tests/lots/test_scenarios.py
    has that timing symbolically): the peak goes back once more before the body is rebuilt."""
    r = run_narrative("fig10")
    assert r.satisfied and r.exit_code == 0
    assert [a.outcome for a in r.person_actions] == ["done"] * 4
    assert r.never_happened == []
    actions = kinds(r)
    assert actions[:4] == [
        ("move", "p1"),
        ("discard_held", "body"),  # the body the person built is there: the held one is surplus
        ("return_held", "peak"),  # the body was taken away while the robot carried the peak
        ("move", "p2"),  # rebuilt
    ]
    assert actions.count(("move", "p2")) == 2 and actions[-1] == ("move", "p3")
    assert r.final_counts["B"] == {"bottom": 1, "body": 1, "peak": 1}
    assert r.final_counts["A"] == {"toy_car": 1}  # ignored
    assert r.final_counts["waste"] == {"body": 1}
