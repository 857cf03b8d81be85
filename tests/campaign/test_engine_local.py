"""The campaign's engine logic on the in-process engine with test-only runners (no Drake,
no Ray): statuses, crash and hang handling, files, summary, reproducibility."""

from __future__ import annotations

import json

import pytest

from tamp.campaign import CampaignSpec, LocalEngine, run_campaign
from tamp.errors import InputError
from tests.campaign.faulty import CRASH, HANG, outcome


def _campaign(kind, path, out, seed=0, runs=8, plots=False, **kw):
    spec = CampaignSpec(kind, path, runs, seed=seed, **kw)
    return run_campaign(spec, LocalEngine(), out=out, progress=False, plots=plots)


def test_statuses_causes_and_summary(fake_kind, fake_file, tmp_path):
    result = _campaign(fake_kind, fake_file, None, runs=10)
    doc = result.to_json()
    want = {s: outcome(s) for s in range(10)}
    assert [r["seed"] for r in doc["runs"]] == list(range(10))
    for r in doc["runs"]:
        status, cause = want[r["seed"]]
        assert r["status"] == status.lower() and r["cause"] == cause
        assert r["task_time"] == 30.0 + 0.5 * r["seed"]
        assert r["perturbation"] == pytest.approx(0.01 * r["seed"])
    # seeds 3, 7 fail; 4, 9 time out in sim; the other 6 succeed
    assert (doc["n_runs"], doc["successes"], doc["success_rate"]) == (10, 6, 0.6)
    assert doc["wilson_95"] == [0.3127, 0.8318]
    assert doc["statuses"] == {"success": 6, "failure": 2, "timeout": 2, "crash": 0}
    assert doc["task_time"]["n"] == 6 and doc["task_time"]["median"] == 31.75
    assert [(c["cause"], c["seeds"]) for c in doc["causes"]] == [
        ("dropped O1", [3, 7]),
        ("no result within 9 s of sim time", [4, 9]),
    ]
    assert doc["engine"] == "local" and doc["address"] is None
    assert sum(b["n"] for b in doc["by_perturbation"]) == 10


def test_files_under_out(fake_kind, fake_file, tmp_path):
    out = tmp_path / "out"
    (out / "runs").mkdir(parents=True)
    (out / "runs" / "seed_99.json").write_text("{}")  # a previous campaign's run
    (out / "runs" / "notes.txt").write_text("mine")  # not ours: kept
    result = _campaign(fake_kind, fake_file, out, runs=5, plots=True)
    assert sorted(p.name for p in (out / "runs").iterdir()) == [
        "notes.txt",
        *(f"seed_{s}.json" for s in range(5)),
    ]
    run3 = json.loads((out / "runs" / "seed_3.json").read_text())
    assert run3["status"] == "failure" and run3["replay"] == f"fake {fake_file} --seed 3"
    assert run3["result"]["cause"] == "dropped O1"
    # recordings of the unsuccessful runs only (3 fails, 4 times out)
    assert sorted(p.name for p in (out / "recordings").iterdir()) == ["seed_3.html", "seed_4.html"]
    assert run3["recording"] == str(out / "recordings" / "seed_3.html")
    assert json.loads((out / "summary.json").read_text())["n_runs"] == 5
    for stem in ("task_time", "success_by_perturbation"):
        for ext in ("png", "svg"):
            assert (out / f"{stem}.{ext}").stat().st_size > 1000
    assert len(result.plots) == 4


def test_no_record(fake_kind, fake_file, tmp_path):
    _campaign(fake_kind, fake_file, tmp_path / "out", runs=5, record=False)
    assert list((tmp_path / "out" / "recordings").iterdir()) == []


def test_crash_is_a_result_not_fatal(fake_kind, fake_file, tmp_path):
    result = _campaign(fake_kind, fake_file, tmp_path / "out", seed=CRASH - 1, runs=3)
    by_seed = {r.seed: r for r in result.records}
    crash = by_seed[CRASH]
    assert crash.status == "crash" and crash.cause == f"RuntimeError: boom at seed {CRASH}"
    assert "Traceback" in crash.error and crash.task_time is None
    assert by_seed[CRASH + 1].status == "timeout"  # the campaign went on (14: sim timeout)
    saved = json.loads((tmp_path / "out" / "runs" / f"seed_{CRASH}.json").read_text())
    assert saved["status"] == "crash" and "boom" in saved["error"]


def test_hang_hits_the_time_limit(fake_kind, fake_file, tmp_path):
    result = _campaign(fake_kind, fake_file, None, seed=HANG, runs=2, time_limit=0.5)
    hung, after = result.records
    assert hung.seed == HANG and hung.status == "timeout"
    assert hung.cause == "killed after the 0.5 s wall-time limit"
    assert 0.5 <= hung.wall_time < 3.0
    assert after.status == "success"


def test_reproducible_per_seed(fake_kind, fake_file, tmp_path):
    a = _campaign(fake_kind, fake_file, None, seed=2, runs=6).to_json()["runs"]
    b = _campaign(fake_kind, fake_file, None, seed=2, runs=6).to_json()["runs"]
    keys = ("seed", "status", "cause", "task_time", "perturbation")
    assert [[r[k] for k in keys] for r in a] == [[r[k] for k in keys] for r in b]


def test_worst_run(fake_kind, fake_file, tmp_path):
    assert _campaign(fake_kind, fake_file, None, runs=8).worst().seed == 3
    assert _campaign(fake_kind, fake_file, None, seed=0, runs=3).worst().seed == 2  # slowest


def test_bad_spec_and_bad_file(fake_kind, fake_file, tmp_path):
    with pytest.raises(InputError, match="--runs"):
        CampaignSpec(fake_kind, fake_file, 0)
    with pytest.raises(InputError, match="--time-limit"):
        CampaignSpec(fake_kind, fake_file, 1, time_limit=float("nan"))
    with pytest.raises(InputError, match="no such file"):  # validated before any run
        _campaign(fake_kind, tmp_path / "missing.yaml", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_kind_options_reach_the_runner_and_the_replay(fake_kind, fake_file):
    result = _campaign(fake_kind, fake_file, None, runs=1, options=(("note", "hi"),))
    assert result.records[0].result["note"] == "hi"
    assert result.spec.replay(0) == f"fake {fake_file} --seed 0 --note hi"
    assert result.to_json()["options"] == {"note": "hi"}
    with pytest.raises(InputError, match="not an option of kind test-fake") as e:
        CampaignSpec(fake_kind, fake_file, 1, options=(("interference", "x.yaml"),))
    assert e.value.field == "--interference"


def test_a_cell_option_named_cell_reaches_the_cell(fake_file):
    """The LOTS cell's ``--cell`` option (its workcell file) is a keyword ``cell``; the
    generic seeded run must pass it on, not take it for its own first argument (every LOTS
    campaign with ``--cell`` crashed with "got multiple values for argument 'cell'")."""
    from tamp.sim.core.workcell import Option, run_seeded
    from tests.campaign.faulty import FakeWorkcell

    class WithCell(FakeWorkcell):
        options = (Option("cell", "the workcell file", campaign=True),)

        def load(self, name_or_path, cell: str | None = None):
            return super().load(name_or_path, note=cell)

    out = run_seeded(WithCell(), fake_file, 0, cell="tower_perturbed")
    assert out["status"] == "SUCCESS" and out["note"] == "tower_perturbed"
