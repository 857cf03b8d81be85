"""One run's record: a runner's dict normalised (statuses, causes, perturbation size)."""

from __future__ import annotations

import pytest

from tamp.campaign.engines import check_reachable
from tamp.campaign.run import from_runner, perturbation_size
from tamp.errors import InputError


def test_runner_statuses_map_to_campaign_statuses():
    ok = from_runner(3, {"status": "SUCCESS", "cause": "ignored", "task_time": 12.5}, 1.0)
    assert (ok.status, ok.cause, ok.task_time, ok.ok) == ("success", None, 12.5, True)
    bad = from_runner(4, {"status": "FAILURE", "cause": "grasp_slipped", "task_time": 9}, 1.0)
    assert (bad.status, bad.cause, bad.ok) == ("failure", "grasp_slipped", False)
    slow = from_runner(5, {"status": "TIMEOUT", "task_time": 300.0}, 2.0)
    assert (slow.status, slow.cause) == ("timeout", "TIMEOUT (no cause given)")
    odd = from_runner(6, {"status": "MAYBE"}, 0.5)
    assert (odd.status, odd.cause) == ("crash", "runner returned status 'MAYBE'")


def test_the_recording_path_is_not_kept_in_the_result():
    rec = from_runner(1, {"status": "FAILURE", "cause": "x", "recording": "/tmp/r.html"}, 1.0)
    assert "recording" not in rec.result and rec.result["cause"] == "x"


@pytest.mark.parametrize(
    ("value", "size"),
    [(0.25, 0.25), ({"size": 0.5, "objects": {}}, 0.5), ({}, 0.0), (None, 0.0), ("x", 0.0)],
)
def test_perturbation_size(value, size):
    assert perturbation_size(value) == size


def test_unreachable_address_is_bad_input():
    with pytest.raises(InputError, match="no Ray cluster answers") as e:
        check_reachable("ray://127.0.0.1:1", timeout=2.0)
    assert e.value.field == "--address"
    check_reachable("auto")  # left to Ray
