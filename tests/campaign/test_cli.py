"""`tamp campaign` refusals (exit 2 naming the field, before any run) and, slow, a short
in-process campaign of Case 1 through the CLI."""

from __future__ import annotations

import json
import sys

import pytest

from tamp.commands.main import main


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["case1.yaml", "--runs", "0"], "--runs"),
        (["case1.yaml", "--runs", "2", "--seed", "-1"], "--seed"),
        (["case1.yaml", "--runs", "2", "--seed", str(2**63 - 1)], "--seed"),
        (["case1.yaml", "--runs", "2", "--workers", "-1"], "--workers"),
        (["case1.yaml", "--runs", "2", "--engine", "local", "--workers", "2"], "--workers"),
        (["case1.yaml", "--runs", "2", "--engine", "ray", "--workers", "0"], "--workers"),
        (["case1.yaml", "--runs", "2", "--workers", "0", "--address", "h:6379"], "--address"),
        (["case1.yaml", "--runs", "2", "--time-limit", "0"], "--time-limit"),
        (["case1.yaml", "--runs", "2", "--max-sim-time", "inf"], "--max-sim-time"),
        (["case1.yaml", "--runs", "2", "--min-success", "1.5"], "--min-success"),
        (["no_such_scenario", "--runs", "2"], "SCENARIO"),
        (["case1.yaml", "--runs", "2", "--interference", "tower_interference"], "--interference"),
        (["case1.yaml", "--runs", "2", "--cell", "tower_perturbed"], "--cell"),
        (["tower.yaml", "--runs", "2", "--cell", "model_building"], "objects"),
    ],
)
def test_bad_input_exits_2_naming_the_field(argv, field, capsys, tmp_path):
    code = main(["campaign", *argv, "--out", str(tmp_path / "out"), "--json"])
    assert code == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["exit"] == 2 and doc["field"] == field
    assert not (tmp_path / "out").exists()  # nothing half-done


def test_a_lots_campaign_runs_in_the_workcell_it_names():
    """``--cell CELL`` reaches the check, every run and the replay command."""
    from tamp.campaign import CampaignSpec, resolve_scenario
    from tamp.scenarios import resolve

    kind, task = resolve_scenario("tower.yaml", None)
    cell = str(resolve("tower_perturbed", "lots_sim"))
    kind.load(str(task), cell=cell)  # the perturbed cell matches the task
    spec = CampaignSpec(kind, task, 2, seed=4, options=(("cell", cell),))
    assert spec.replay(5) == f"tamp simulate lots {task} --seed 5 --cell {cell}"
    assert all(dict(job.options)["cell"] == cell for job in spec.jobs())


def test_out_must_be_a_folder(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["campaign", "case1.yaml", "--runs", "1", "--out", str(f)]) == 2
    assert "--out" in capsys.readouterr().err


def test_missing_ray_exits_2_with_the_install_hint(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError
    code = main(["campaign", "case1.yaml", "--runs", "2", "--out", str(tmp_path / "o")])
    assert code == 2
    err = capsys.readouterr().err
    assert "'ray' is not installed" in err and "pip install 'tamp-hrc[campaign]'" in err
    # the in-process engine needs no Ray: it is refused only for bad flags, not for Ray
    assert main(["campaign", "case1.yaml", "--runs", "0", "--workers", "0"]) == 2
    assert "--runs" in capsys.readouterr().err


def test_unreachable_address_exits_2(tmp_path, capsys):
    pytest.importorskip("ray")
    out = tmp_path / "out"
    argv = ["campaign", "case1.yaml", "--runs", "1", "--address", "127.0.0.1:1", "--json"]
    assert main([*argv, "--out", str(out)]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["field"] == "--address" and "no Ray cluster answers at 127.0.0.1:1" in doc["error"]
    assert not (out / "runs").exists()


def test_runs_is_required(capsys):
    assert main(["campaign", "case1.yaml"]) == 2


@pytest.mark.slow
def test_in_process_campaign_of_case1(tmp_path, capsys):
    out = tmp_path / "c1"
    argv = ["campaign", "case1.yaml", "--runs", "2", "--seed", "5", "--workers", "0"]
    code = main([*argv, "--max-sim-time", "2", "--out", str(out), "--json"])
    assert code == 0  # a campaign whose runs all time out still completed
    doc = json.loads(capsys.readouterr().out)
    assert (doc["engine"], doc["address"], doc["n_runs"], doc["successes"]) == ("local", None, 2, 0)
    assert [(r["seed"], r["status"], r["task_time"]) for r in doc["runs"]] == [
        (5, "timeout", 2.0),
        (6, "timeout", 2.0),
    ]
    assert doc["causes"] == [
        {
            "status": "timeout",
            "cause": "timeout",
            "count": 2,
            "seeds": [5, 6],
        }
    ]
    assert sorted(p.name for p in (out / "recordings").iterdir()) == ["seed_5.html", "seed_6.html"]
    run = json.loads((out / "runs" / "seed_5.json").read_text())
    assert run["replay"].startswith("tamp simulate smp-mro ") and "--seed 5" in run["replay"]
    assert run["result"]["final_poses"]  # the simulation's own JSON is kept
    # --min-success turns the measurement into a gate (exit 1), and says so
    code = main(
        [*argv, "--max-sim-time", "2", "--out", str(out), "--no-record", "--min-success", "0.5"]
    )
    assert code == 1
    text = capsys.readouterr().out
    assert "success 0/2 = 0.0%" in text and "below --min-success 0.5" in text


def test_no_verify_reaches_every_run_and_the_replay(capsys):
    """``--no-verify`` is the same flag as on ``tamp simulate``: every job skips the gate,
    the replay command says so, and the summary records it."""
    from tamp.campaign import CampaignSpec, resolve_scenario

    kind, path = resolve_scenario("case1.yaml", None)
    spec = CampaignSpec(kind, path, 2, verify=False)
    assert [job.verify for job in spec.jobs()] == [False, False]
    assert spec.replay(1).endswith(" --no-verify")
    assert all(job.verify for job in CampaignSpec(kind, path, 2).jobs())
