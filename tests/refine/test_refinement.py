"""The phases' logic: collisions revert a parallelization, the gate refuses a bad refinement.

The simulation is replaced by a stand-in that returns measured-looking runs, so these
tests check the pipeline's decisions, not the physics (test_simulation and the CLI test do).
"""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest

from tamp.errors import InfeasibleError
from tamp.refine.architecture import default_architecture
from tamp.refine.steps import RateSearch
from tamp.refine.timeline import BehaviorRecord, Timeline
from tamp.sim.refine import refinement
from tamp.sim.refine.runner import Run
from tests.refine.helpers import task
from verification.verdict import VerificationError

DUR = {
    "R1.lower_arm": 50.0,
    "R1.approach": 60.0,
    "R1.pull_out": 40.0,
    "R1.raise_arm": 50.0,
    "R2.approach": 20.0,
    "R2.grip": 30.0,
    "R2.release": 30.0,
}


def fake_run(program, collide=False, finished=True):
    """Sequential records with the DUR durations (absorbed ones start with their host)."""
    records = []
    for r in program.robots:
        t = 0.0
        for i, b in enumerate(r.behaviors):
            d = DUR[f"{r.name}.{b.name}"] * program.communication.command_rate_hz / program.rate(b)
            end = t + d if finished or i == 0 else None
            records.append(BehaviorRecord(r.name, b.name, b.section, t, end, r.gating(i)))
            t = t if not r.gating(i) else t + d
    run = Run(program, Timeline(tuple(records)))
    if collide:
        run.collisions = {("R1.arm_link", "folding_chair.frame_b"): 12.0}
    return run


@pytest.fixture
def simulated(monkeypatch):
    fake = SimpleNamespace(calls=[], collide=False)

    def simulate(program, architecture, *, tune=False, record=None, **kw):
        fake.calls.append((program, tune))
        if tune:
            s = RateSearch(10.0, 1.0, 0.03, 200.0, found=23.0)
            run = fake_run(program)
            run.searches = {r.name: s for r in program.robots}
            return run
        parallel = any(b.parallel_with for _, _, b in program.behaviors())
        return fake_run(program, collide=parallel and fake.collide)

    monkeypatch.setattr(refinement, "simulate", simulate)
    return fake


def test_phases_and_rate(simulated):
    out = refinement.refine(task(4), default_architecture())
    assert [p.name for p in out.phases] == list(refinement.PHASES)
    assert out.rate_hz == 23.0
    assert [p.describe() for p in out.parallelized] == [
        "R1: lower_arm runs in parallel with approach"
    ]
    assert out.program.robot("R1").behaviors[0].rate_hz == 23.0
    assert [t for _, t in simulated.calls] == [False, False, False, True, False]
    assert out.reduction > 0.5
    doc = out.to_json()
    assert doc["rate_hz"] == 23.0 and doc["category"] == "II"
    assert [p["name"] for p in doc["phases"]] == list(refinement.PHASES)
    # the stand-in's robots ignore each other (R2 releases at 80 s, before R1 pulls out):
    # the check of the measured order notices
    assert [p["run_satisfies_ordering"] for p in doc["phases"]] == [False] * 4


def test_a_colliding_parallelization_is_reverted(simulated):
    simulated.collide = True
    out = refinement.refine(task(4), default_architecture())
    assert out.parallelized == []
    ((bad, collisions),) = out.reverted
    assert bad.absorbed == "lower_arm"
    assert collisions == [("R1.arm_link", "folding_chair.frame_b", 12.0)]  # with its time
    assert out.phases[1].program == task(4)  # run again without it


def test_a_refinement_that_breaks_the_ordering_is_refused(simulated):
    p = replace(task(4), ordering="G(R1.approach -> R1.lower_arm)")
    with pytest.raises(VerificationError) as exc:
        refinement.refine(p, default_architecture())
    assert "parallelized program task4" in str(exc.value)
    assert exc.value.report.counterexample is not None
    assert len(simulated.calls) == 1  # only the original ran


def test_a_program_that_does_not_finish_is_infeasible(monkeypatch):
    monkeypatch.setattr(refinement, "simulate", lambda p, a, **kw: fake_run(p, finished=False))
    with pytest.raises(InfeasibleError, match="never fired"):
        refinement.refine(task(4), default_architecture())
