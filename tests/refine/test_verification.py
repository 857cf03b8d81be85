"""The LTL gate on programs: every execution is checked; a bad refinement is refused."""

from __future__ import annotations

from dataclasses import replace

import pytest

from tamp.refine.steps import Parallelization, join, parallelize
from tamp.verification.gate import gate, gate_program
from tamp.verification.refine import check_program, check_run, executions
from tamp.verification.verdict import VerificationError
from tests.refine.helpers import task

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


WRONG = {
    # past the manipulation boundary: the fork would push before it lifted, the lever
    # would follow before the push
    1: [("R1", "lift", "push"), ("R1", "push", "follow")],
    2: [("R1", "lift", "push"), ("R1", "push", "follow")],
    # the fingers would close with the approach; the fork would lift before the pull
    4: [("R2", "approach", "grip"), ("R1", "pull_out", "raise_arm")],
}


@pytest.mark.parametrize(
    "n,wrong", [(n, w) for n, ws in WRONG.items() for w in ws], ids=lambda x: str(x)
)
def test_each_task_property_refuses_a_wrong_parallelization(n, wrong):
    """Each packaged task states what a parallelization past its manipulation boundary
    breaks; the paper-style parallelization (Step 1 + Step 2) satisfies it."""
    p = task(n)
    refined, done = parallelize(p, {e: float(i + 1) for i, e in enumerate(p.events())})
    assert done and check_program(refined).holds
    bad = join(p, Parallelization(*wrong))
    verdict = check_program(bad)
    assert not verdict.holds and verdict.counterexample is not None
    robot, absorbed, host = wrong
    # the counterexample is an execution where the host's event fired first
    word = verdict.counterexample.word
    i = next(i for i in range(len(word)) if f"{robot}.{host}" in word.letter(i))
    assert f"{robot}.{absorbed}" not in word.letter(i)


def test_task3_property_refuses_lifting_before_the_hold_and_the_approach():
    """Task 3's wrong refinement: R1's lift no longer waits for R2's hold (a cross-robot
    wait relaxed) and runs with the approach: both properties of the task break."""
    p = task(3)
    lift = p.robot("R1").index("lift")
    relaxed = p.with_behavior("R1", lift, replace(p.robot("R1").behaviors[lift], waits_for=()))
    assert not check_program(relaxed).holds
    bad = join(relaxed, Parallelization("R1", "approach", "lift"))
    with pytest.raises(VerificationError) as exc:
        gate_program(bad)
    assert "R1.lift" in str(exc.value)


def test_without_the_manipulation_boundary_the_gate_refuses_what_step_2_proposes():
    """Task 4 with its `manipulates` marks removed: Step 1 locates every behavior and
    Step 2 proposes R2's grip with its approach; the task's property refuses it."""
    p = task(4)
    loose = replace(
        p,
        robots=tuple(
            replace(r, behaviors=tuple(replace(b, manipulates=False) for b in r.behaviors))
            for r in p.robots
        ),
    )
    durations = {"R2.approach": 28.6, "R2.grip": 37.5} | T4
    refined, done = parallelize(loose, durations)
    assert "R2: approach runs in parallel with grip" in [d.describe() for d in done]
    with pytest.raises(VerificationError):
        gate_program(refined)


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
    """`tamp.verification.gate` knows programs: the same Report as `gate_program`."""
    report = gate(task(4))
    assert report.holds and len(report.verdicts) == 1
    assert report.verdicts[0].subject == "program task4"
