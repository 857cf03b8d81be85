"""Narrative fig9 end to end in the workcell (`tests/sim/lots/narratives.py`)."""

from __future__ import annotations

import pytest

from tests.sim.lots.narratives import DETECTORS, kinds, run_narrative


@pytest.mark.slow
@pytest.mark.paper  # a whole narrative of the paper (2-5 min): make test-paper
@pytest.mark.parametrize("detector", DETECTORS)
def test_fig9_scissors_sent_back_are_brought_again_and_a_new_tool_is_ignored(detector):
    r = run_narrative("fig9", detector)
    assert r.satisfied and r.exit_code == 0
    assert [a.outcome for a in r.person_actions] == ["done", "done"]
    assert kinds(r).count(("move", "p2")) == 2  # the scissors, twice
    assert r.final_counts["B"] == {"saw": 1, "scissors": 1, "hammer": 1}
    assert r.final_counts["A"] == {"scissors": 1, "wrench": 1}
