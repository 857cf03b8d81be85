"""Narrative fig10 end to end in the workcell (`tests/sim/lots/narratives.py`)."""

from __future__ import annotations

import pytest

from tests.sim.lots.narratives import DETECTORS, kinds, run_narrative


@pytest.mark.slow
@pytest.mark.paper  # a whole narrative of the paper (2-5 min): make test-paper
@pytest.mark.parametrize("detector", DETECTORS)
def test_fig10_tower_stacked_three_high_despite_the_persons_changes_to_the_stack(detector):
    """Fig. 10: the robot stacks the tower in W^B (the cell declares ``stack: [bottom, body,
    peak]``). The person builds the body on the bottom (10.4), takes it off the stack while
    the robot carries the peak (10.7), moves the robot's body from the stack back to W^A
    (10.9), adds a toy car in W^A (10.13). The robot drops its surplus body, puts the peak
    back, builds the body twice and tops it with the peak; the toy car stays. At the end the
    tower stands three high on the plant: the body resting on the bottom, the peak on the
    body (`tamp.sim.lots.stack.judge_stack`: each level's underside within 1 cm of the top
    of the one below, its centre over that one's footprint, within 10 deg of upright)."""
    r = run_narrative("fig10", detector)
    assert r.satisfied and r.exit_code == 0
    assert [a.outcome for a in r.person_actions] == ["done"] * 4
    built, taken, moved, car = r.person_actions
    assert (built.uid.startswith("person_body"), built.dst) == (True, "B")
    assert (taken.uid, taken.src) == (built.uid, "B")  # the person's body, off the stack
    assert (moved.uid.startswith("body"), moved.src, moved.dst) == (True, "B", "A")
    assert r.never_happened == []
    actions = kinds(r)
    assert actions[:4] == [
        ("move", "p1"),
        ("discard_held", "body"),  # the body the person built is there: the held one is surplus
        ("return_held", "peak"),  # the body was taken away while the robot carried the peak
        ("move", "p2"),  # rebuilt
    ]
    assert actions.count(("move", "p2")) == 2 and actions[-1] == ("move", "p3")
    # the tower stacked three high on the plant, not laid side by side
    assert r.stack["complete"] and r.stack["height"] == 3
    assert [u.rsplit("_", 1)[0] for u in r.stack["levels"]] == ["bottom", "body", "peak"]
    assert r.final_counts["B"] == {"bottom": 1, "body": 1, "peak": 1}
    assert r.final_counts["A"] == {"toy_car": 1}  # ignored
    assert r.final_counts["waste"] == {"body": 1}
