"""Campaigns on a local Ray with 2 CPUs (slow: Ray starts, workers import Drake): a crashing
run, a dying worker and a hanging run are results, not fatal; a real Drake campaign is
reproducible per seed."""

from __future__ import annotations

import json

import pytest

from tamp.campaign import CampaignSpec, RayEngine, run_campaign
from tamp.commands.main import main
from tests.campaign.faulty import CRASH, DIE, HANG, outcome

ray = pytest.importorskip("ray")
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def local_ray():
    """One local Ray (2 CPUs) for the module; every engine below uses it as it is."""
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        object_store_memory=128 * 1024 * 1024,
    )
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()


def test_crash_death_and_hang_are_recorded(local_ray, fake_kind, fake_file, tmp_path):
    seeds = [CRASH - 1, CRASH, HANG, DIE, DIE + 1]
    records = {}
    for first in (CRASH - 1, HANG, DIE):  # 12-13, 15, 21-22
        runs = 2 if first != HANG else 1
        # a limit a fresh Ray worker meets even on a loaded 2-core machine (restarting a dead
        # worker imports the package again: > 8 s was seen under CI load)
        spec = CampaignSpec(fake_kind, fake_file, runs, seed=first, time_limit=15.0)
        engine = RayEngine(workers=2)
        result = run_campaign(spec, engine, out=None, progress=False)
        assert (result.engine, result.address, result.workers) == ("ray", local_ray, 2)
        records.update({r.seed: r for r in result.records})
    assert sorted(records) == seeds
    assert records[CRASH].status == "crash"
    assert records[CRASH].cause == f"RuntimeError: boom at seed {CRASH}"
    assert "Traceback" in records[CRASH].error
    assert records[DIE].status == "crash" and "WorkerCrashedError" in records[DIE].cause
    assert records[HANG].status == "timeout" and "15 s wall-time limit" in records[HANG].cause
    assert 15.0 <= records[HANG].wall_time < 30.0
    for seed in (CRASH - 1, DIE + 1):  # the campaign went on around them
        assert records[seed].status == outcome(seed)[0].lower()
        assert records[seed].task_time == 30.0 + 0.5 * seed


def test_drake_campaign_reproducible_per_seed(local_ray, tmp_path, capsys):
    """Two campaigns of the same seeds of Case 1 on 2 workers (assigned to workers in
    whatever order Ray picks): same statuses, task times and final plant poses."""
    docs, poses = [], []
    for name in ("a", "b"):
        out = tmp_path / name
        argv = ["campaign", "case1.yaml", "--runs", "3", "--seed", "7", "--workers", "2"]
        assert main([*argv, "--max-sim-time", "12", "--out", str(out), "--json"]) == 0
        doc = json.loads(capsys.readouterr().out)
        assert (doc["engine"], doc["address"], doc["workers"]) == ("ray", local_ray, 2)
        docs.append([(r["seed"], r["status"], r["cause"], r["task_time"]) for r in doc["runs"]])
        poses.append(
            [
                json.loads((out / "runs" / f"seed_{s}.json").read_text())["result"]["final_poses"]
                for s in (7, 8, 9)
            ]
        )
    assert docs[0] == docs[1]
    assert [s for s, *_ in docs[0]] == [7, 8, 9]
    assert poses[0] == poses[1]
