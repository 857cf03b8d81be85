"""A run is judged on what happened: its word, read by the task automaton (no false success).

Random tasks (formula shapes with orders, alternatives and recurrences over three
propositions, random classes and objects, with and without our return action) meet random
interference that respects Zhou et al.'s Assumption 1 (`test_theorem1.make_policy`: moves
between W^A and W^B, additions, removals of spare objects only). Whatever the run does, a run
that claims success has a word the task accepts — checked by the verification module and,
when no person brought anything into W^B, against the formula directly on the robot's own
deliveries (an oracle that does not use `tamp.lots.word`).
"""

from __future__ import annotations

from dataclasses import replace

from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.errors import InfeasibleError
from tamp.lots.controller import LotsController
from tamp.lots.run import run_task
from tamp.verification.lots import judge_word
from tamp.verification.traces import check_trace
from tamp.verification.words import Word

from .helpers import random_tasks
from .test_theorem1 import abstract_event, make_policy

SHAPES = (
    "F({0} & F({1} & F {2}))",
    "F({0} & F {1}) & F {2}",
    "(F {0} | F {1}) & F {2}",
    "F({0} & F {2}) | F {1}",
    "GF {0} & GF {1} & GF {2}",
    "GF({0} | {1}) & GF {2}",
    "F({0} & F({1} & F {0})) | F {2}",
)


@settings(max_examples=80, deadline=None)
@given(
    task=random_tasks(SHAPES),
    returns=st.booleans(),
    abstract=st.lists(abstract_event, min_size=1, max_size=4),
    seed=st.integers(0, 3),
)
def test_no_run_claims_success_with_a_rejected_word(task, returns, abstract, seed):
    task = replace(task, returns=returns)
    try:
        c0 = LotsController(task)
    except InfeasibleError:
        return  # no accepting run with these objects and actions: nothing to run
    final = c0.lots.named(c0.lots.final)
    policy = make_policy(task, final, abstract)
    r = run_task(task, mode="random", seed=seed, policy=policy)
    c = r.controller
    if not r.satisfied:
        assert r.reason  # infeasible with the reason, never a silent failure
        return
    verdict = judge_word(c)
    assert verdict.holds, (verdict.text(), c.word.events)
    into_b = [e for _, _, e in r.person.log if e.kind == "add" and e.side == "B"]
    into_b += [e for _, _, e in r.person.log if e.kind == "move" and e.dst == "B"]
    if not into_b:
        robot = [frozenset({a.prop}) for a in r.actions if a.kind == "move"]
        word = Word.lasso(robot, c.plan.cycle)
        assert check_trace(c.aut.spot_formula, word).holds, (word, r.reason)


def test_the_judge_rejects_a_run_that_skipped_a_delivery():
    """The issue's false success: only p2 and p3 happened; the word is rejected."""
    from tamp.lots.task import Proposition, Task

    task = Task(
        "F(p1 & F(p2 & F p3))",
        (Proposition("p1", "block"), Proposition("p2", "block"), Proposition("p3", "cap")),
        {"block": 2, "cap": 1},
        {"block": 1},
    )
    c = LotsController(task)
    c.word.deliver("p2")
    c.word.deliver("p3")
    verdict = judge_word(c)
    assert not verdict.holds
    assert "does not satisfy the task" in verdict.counterexample.reason
