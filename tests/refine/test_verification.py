"""The LTL gate on programs: every execution is checked; a bad refinement is refused."""

from __future__ import annotations

from dataclasses import replace

import pytest

from tamp.refine.steps import parallelize
from tests.refine.helpers import task
from verification.gate import gate, gate_program
from verification.refine import check_program, check_run, executions
from verification.verdict import VerificationError

T4 = {"R1.lower_arm": 57.0, "R1.approach": 68.0}


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_packaged_tasks_and_their_refinements_hold(n):
    p = task(n)
    assert gate_program(p).holds
    durations = {e: float(i + 1) for i, e in enumerate(p.events())}  # n shorter than n + 1
    refined, done = parallelize(p, durations)
    assert done, "every packaged task has a parallelizable pair"
    assert check_program(refined).holds


def test_refinement_that_breaks_the_property_is_refused():
    """'the lift is down before the approach ends' holds sequentially, not in parallel."""
    p = replace(task(4), ordering="G(R1.approach -> R1.lower_arm)")
    assert check_program(p).holds
    refined, _ = parallelize(p, T4)
    with pytest.raises(VerificationError) as exc:
        gate_program(refined)
    verdict = exc.value.report.failed[0]
    ce = verdict.counterexample
    assert ce is not None
    # the counterexample is an execution where the approach fired first
    i = next(i for i in range(len(ce.word)) if "R1.approach" in ce.word.letter(i))
    assert "R1.lower_arm" not in ce.word.letter(i)
    assert exc.value.exit_code == 1


def test_executions_system_size():
    ts = executions(task(4))
    assert ts.num_states == 13
    assert ts.labels[0] == frozenset() and ts.labels[-1] == frozenset(task(4).events())


def test_measured_run_order():
    p = task(4)
    good = ["R2.approach", "R1.lower_arm", "R2.grip", "R1.approach", "R1.pull_out"]
    good += ["R2.release", "R1.raise_arm"]
    assert check_run(p, good).holds
    bad = ["R1.lower_arm", "R1.approach", "R1.pull_out", "R2.approach", "R2.grip"]
    v = check_run(p, bad)
    assert not v.holds and v.counterexample.position == 2


def test_gate_dispatches_on_programs():
    """`verification.gate` knows programs: the same Report as `gate_program`."""
    report = gate(task(4))
    assert report.holds and len(report.verdicts) == 1
    assert report.verdicts[0].subject == "program task4"
