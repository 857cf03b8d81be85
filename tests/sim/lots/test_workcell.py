"""The LOTS cell keeps the `Workcell` contract: its declarations, ``load`` (the task, the
cell scenario named like it or given, the person's script, the grasp network: checked
together), and a `LotsSimResult` that is a `RunResult` (common keys once, the old report)."""

from __future__ import annotations

import pytest

from tamp.errors import InputError
from tamp.grasp.networks import NETWORKS
from tamp.scenarios import resolve
from tamp.sim.core.executor import ActionLog
from tamp.sim.core.workcell import RunResult, Workcell, get, split_options
from tamp.sim.lots import WORKCELL
from tamp.sim.lots.simulate import LotsScenario, LotsSimResult


def test_the_cell_declares_the_contract():
    assert get("lots") is WORKCELL and isinstance(WORKCELL, Workcell)
    assert (WORKCELL.folder, WORKCELL.key) == ("lots", "formula")
    main = WORKCELL.main
    assert (main.dest, main.spelling, main.required, main.folder) == (
        "task",
        "task",
        True,
        "lots",
    )
    options = {o.dest: o for o in WORKCELL.options}
    assert {k: (o.stage, o.campaign, o.folder) for k, o in options.items()} == {
        "cell": ("load", True, "lots_sim"),
        "interference": ("load", True, "lots"),
        "grasp": ("load", False, None),
        "detector": ("load", False, None),  # campaigns: the cell file's camera.detector
        "return_action": ("load", False, None),  # campaigns: the task file's 'actions'
    }
    assert options["grasp"].choices == tuple(NETWORKS)
    assert options["detector"].choices == ("oracle", "learned")
    assert WORKCELL.replay.format(scenario="tower", seed=4) == ("tamp simulate lots tower --seed 4")
    load, run = split_options(WORKCELL, {"cell": "tower", "grasp": "ggcnn"})
    assert load == {"cell": "tower", "grasp": "ggcnn"} and run == {}


def test_load_bundles_the_task_its_cell_and_the_script():
    s = WORKCELL.load("tower")
    assert isinstance(s, LotsScenario) and s.name == "tower" and s.interference == ()
    assert s.cell.name == "tower" and s.cell.source == str(resolve("tower", "lots_sim"))
    s = WORKCELL.load("tower", cell="tower_perturbed", interference="tower_interference")
    assert s.cell.name == "tower_perturbed" and len(s.interference) == 4
    assert WORKCELL.load("tower", grasp="ggcnn").cell.grasp.network == "ggcnn"


def test_load_checks_them_together(tmp_path):
    with pytest.raises(InputError, match="W\\^A holds") as e:
        WORKCELL.load("tower", cell="model_building")
    assert e.value.field == "objects"
    with pytest.raises(InputError) as e:  # no scissors in the tower task to move
        WORKCELL.load("tower", interference="model_building_fig8")
    assert e.value.field == "events[0].class"
    task = tmp_path / "mine.yaml"
    task.write_text(resolve("tower", "lots").read_text().replace("name: tower", "name: mine"))
    with pytest.raises(InputError, match="no packaged workcell scenario") as e:
        WORKCELL.load(str(task))
    assert e.value.field == "--cell"
    assert WORKCELL.load(str(task), cell="tower").task.name == "mine"


def test_perturbed_draws_the_cell_and_the_persons_reactions():
    s = WORKCELL.load("tower", cell="tower_perturbed", interference="tower_interference")
    moved, applied = WORKCELL.perturbed(s, 3)
    assert moved.task is s.task and moved.cell.sample is not None and applied.seed == 3
    assert applied.timing and applied.friction is not None  # the person's slots, the mats
    assert WORKCELL.perturbed(s, 3)[1].to_json() == applied.to_json()


def test_the_result_is_a_run_result_with_its_own_keys_and_report():
    r = LotsSimResult(
        scenario="tower",
        task="tower",
        formula="F(p1 & F(p2 & F p3))",
        status="FAILURE",
        reason="task NOT satisfied: a skill failed",
        cause="grasp_missed",
        sim_time=12.0,
        wall_time=4.0,
        controller_status="FAILURE",
        actions=[ActionLog(1, "Pick(peak)", 1.0, 2.5, "FAILURE", "missed", "grasp_missed")],
        grasps={"attempts": 3, "successes": 0},
        final_counts={"A": {"peak": 1}, "B": {}, "waste": {}},
    )
    assert isinstance(r, RunResult) and r.exit_code == 1
    doc = r.to_json()
    assert doc["workcell"] == "lots" and doc["realtime_factor"] == 3.0 and "rtf" not in doc
    assert doc["task"] == "tower" and doc["satisfied"] is False and doc["grasp"] == "hrgnet"
    lines = r.report_lines()
    assert lines[0] == "task tower: F(p1 & F(p2 & F p3))  (workcell tower, grasp hrgnet)"
    assert lines[2].split()[:4] == ["Pick(peak)", "1.00", "2.50", "FAILURE"]
    assert "final (plant): W^A {'peak': 1}  W^B {}  waste {}" in lines
    assert "replans 0, grasps 0/3, frames 0, safety stops 0" in lines
    assert lines[-2:] == [
        "cause: grasp_missed",
        "FAILURE: task NOT satisfied: a skill failed; sim 12.00 s, wall 4.00 s, "
        "real-time factor 3.00x",
    ]


def test_the_return_action_is_off_unless_asked_for():
    """Zhou et al.'s action set by default; ``--return-action`` switches our extension on."""
    assert WORKCELL.load("tower").task.returns is False
    assert WORKCELL.load("tower", return_action=True).task.returns is True
    assert "--return-action" in [o.spelling for o in WORKCELL.options]


def test_the_result_carries_the_runs_word_and_the_automatons_verdict():
    r = LotsSimResult(
        scenario="tower",
        task="tower",
        formula="F(p1 & F(p2 & F p3))",
        status="FAILURE",
        reason="task NOT satisfied: the run's word is not accepted",
        word={"events": [], "trace": [["p2"], ["p3"]], "cycle": [[]]},
        word_accepted=False,
        word_verdict={"holds": False},
        final_w_b={"bottom": 1, "body": 1, "peak": 1},
        final_counts={"A": {}, "B": {}, "waste": {}},
        grasps={"attempts": 0, "successes": 0},
    )
    doc = r.to_json()
    assert doc["word"]["trace"] == [["p2"], ["p3"]] and doc["word_accepted"] is False
    assert doc["final_w_b"] == {"bottom": 1, "body": 1, "peak": 1}
    assert "run's word: {p2} {p3}  — rejected by the task automaton" in r.report_lines()
