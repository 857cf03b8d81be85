"""The refinement cell as a registered `Workcell`: one run of a program as given, judged by
its events and its measured event order; listing it imports no Drake."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tamp.errors import InputError
from tamp.refine.measure import Goal, Outcome, Run
from tamp.refine.timeline import BehaviorRecord, Timeline
from tamp.scenarios import resolve
from tamp.sim.core.workcell import Workcell, get, run_seeded
from tamp.sim.refine import WORKCELL
from tamp.sim.refine.simulate import judge
from tests.refine.helpers import task

ROOT = Path(__file__).resolve().parents[3]


def test_it_is_the_registered_refine_workcell_and_imports_no_drake():
    assert isinstance(WORKCELL, Workcell) and get("refine") is WORKCELL
    assert "{scenario}" in WORKCELL.replay and "{seed}" in WORKCELL.replay
    code = "import sys, tamp.sim.refine; assert 'pydrake' not in sys.modules"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr


class Verdict:
    def __init__(self, holds):
        self.holds = holds


def _run(ends):
    program = task(4)
    records = []
    for r in program.robots:
        for b in r.behaviors:
            end = ends.get(f"{r.name}.{b.name}", 1.0)
            records.append(BehaviorRecord(r.name, b.name, b.section, 0.0, end))
    return program, Run(program, Timeline(tuple(records)), sim_time=30.0)


def test_judge_by_events_and_order():
    program, run = _run({})
    assert judge(program, run, lambda p, o: Verdict(True))[:2] == ("SUCCESS", None)
    status, cause, reason, holds = judge(program, run, lambda p, o: Verdict(False))
    assert (status, cause, holds) == ("FAILURE", "order_violated", False)
    program, run = _run({"R2.release": None})
    status, cause, reason, holds = judge(program, run, lambda p, o: Verdict(True))
    assert (status, cause, holds) == ("TIMEOUT", "timeout", None)
    assert reason == "R2.release never fired"


def test_judge_needs_the_goal_on_the_plant_and_no_new_collision():
    """A run whose order is fine still fails when the chair stays shut, or when it has a
    collision the unperturbed run did not (one both runs have is no failure)."""
    goal = Goal("folding_chair.hinge", 0.35, "the chair is open")
    ok = lambda p, o: Verdict(True)  # noqa: E731
    program, run = _run({})
    run.outcome = Outcome({"folding_chair.hinge": 0.2}, (goal,))
    status, cause, reason, holds = judge(program, run, ok)
    assert (status, cause, holds) == ("FAILURE", "goal_missed", True)
    assert (
        reason == "goal not met on the plant: the chair is open: folding_chair.hinge = 0.200 < 0.35"
    )
    run.outcome = Outcome({"folding_chair.hinge": 0.48}, (goal,))
    _, reference = _run({})
    reference.collisions = {("R1.arm_link", "folding_chair.frame_b"): 3.0}
    run.collisions = {("R1.arm_link", "folding_chair.frame_b"): 4.0}
    assert judge(program, run, ok, reference)[0] == "SUCCESS"
    run.collisions[("R1.base_link", "R2.base_link")] = 9.5
    status, cause, reason, _ = judge(program, run, ok, reference)
    assert (status, cause) == ("FAILURE", "new_collision")
    assert reason.endswith("R1.base_link with R2.base_link at 9.5 s")


def test_a_short_seeded_run_through_the_registry(tmp_path):
    """``run_seeded("refine", ...)``: the common keys, the program's timeline and outcome."""
    out = run_seeded("refine", "table_collision", 3, max_sim_time=2.0)
    json.dumps(out)
    assert out["workcell"] == "refine" and out["seed"] == 3
    assert out["status"] == "TIMEOUT" and out["cause"] == "timeout"
    assert out["task_time"] == out["sim_time"] == pytest.approx(2.0, abs=0.06)
    assert out["verified"] == {"ordering": True}
    assert out["program"] == "table_collision" and out["outcome"]["goals"] == []
    assert [b["event"] for b in out["timeline"]][0] == "R1.lower_arm"


def test_load_refuses_a_perturbation_it_does_not_simulate(tmp_path):
    data = yaml.safe_load(resolve("task4", "refine").read_text())
    data["perturbation"] = {"friction": [0.5, 0.6]}
    f = tmp_path / "task4.yaml"
    f.write_text(yaml.safe_dump(data))
    with pytest.raises(InputError) as e:
        WORKCELL.load(str(f))
    assert e.value.field == "perturbation.friction" and "refinement workcell" in str(e.value)


def test_a_perturbed_run_is_judged_against_the_unperturbed_runs_collisions(tmp_path, monkeypatch):
    """`RefineWorkcell.run` with a seed that moves the robots: the run of the program as
    given (simulated once) is the reference; a collision only the perturbed run has fails
    it with cause new_collision."""
    import tamp.sim.refine.simulate as workcell

    data = yaml.safe_load(resolve("task4", "refine").read_text())
    data["perturbation"] = {"robot": {"distribution": "uniform", "xy": 0.02, "yaw": 0.0}}
    f = tmp_path / "task4.yaml"
    f.write_text(yaml.safe_dump(data))
    scenario = WORKCELL.load(str(f))
    goal = Goal("folding_chair.hinge", 0.35, "the chair is open")
    calls = []

    def simulate(program, architecture, *, max_sim_time=None, record=None, scene=None, tune=False):
        calls.append(program.robot("R1").start)
        order = ["R2.approach", "R1.lower_arm", "R1.approach", "R2.grip", "R1.pull_out"]
        _, run = _run(
            {e: float(i + 1) for i, e in enumerate([*order, "R1.raise_arm", "R2.release"])}
        )
        run.program = program
        run.outcome = Outcome({"folding_chair.hinge": 0.48}, (goal,))
        if program.robot("R1").start != scenario.program.robot("R1").start:
            run.collisions = {("R1.arm_link", "folding_chair.frame_b"): 12.0}
        return run

    monkeypatch.setattr(workcell, "simulate", simulate)
    workcell._REFERENCE.clear()
    result = WORKCELL.run(scenario, seed=4, verify=False)
    assert (result.status, result.cause) == ("FAILURE", "new_collision")
    assert calls[1] == scenario.program.robot("R1").start  # the reference: as given
    assert "R1.arm_link with folding_chair.frame_b at 12.0 s" in result.reason
    WORKCELL.run(scenario, seed=5, verify=False)
    assert len(calls) == 3  # the reference is simulated once per process
