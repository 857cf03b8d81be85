"""`check_tree`: model-check every explored execution of a grown tree against LTL properties.

`VerificationUnknown` is what the gate raises when the exploration hit its budget without
finding a violation: nothing is established, and the message says how to raise the budget.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from tamp.bt.executor import PaBtExecutor
from tamp.ltl.formula import Formula, ap_names, as_formula
from tamp.verification.bt.explore import DEFAULT_MAX_STATES, explore
from tamp.verification.bt.labels import DEFAULT_PROPERTIES
from tamp.verification.kripke import model_check
from tamp.verification.verdict import Report, VerificationError
from tamp.world.events import Appear, Fail
from tamp.world.state import WorldState


def check_tree(
    executor: PaBtExecutor,
    state: WorldState,
    properties: Sequence[str | Formula] = DEFAULT_PROPERTIES,
    *,
    events: Iterable[Appear] = (),
    failures: Iterable[Fail] | None = None,
    max_failures: int = 1,
    max_states: int = DEFAULT_MAX_STATES,
    subject: str = "BT",
    reduce: bool = True,
) -> Report:
    """Every execution of ``executor`` from ``state`` against each property.

    ``events``: interference (`Appear`). ``failures``: the skills that may fail (`Fail`
    entries; None: every skill), at most ``max_failures`` failures per execution.
    ``executor`` is not ticked (the exploration works on copies). Properties use the
    propositions of `tamp.verification.bt.labels`; an unknown one is an `InputError`.
    ``reduce``: the reduced exploration (default) or the explicit one
    (`tamp.verification.bt.explore`).
    """
    formulas = [as_formula(p, field="--property") for p in properties]
    aps = sorted({a for f in formulas for a in ap_names(f)})
    ex = explore(
        executor,
        state,
        aps,
        events=events,
        failures=failures,
        max_failures=max_failures,
        max_states=max_states,
        reduce=reduce,
    )
    bound = "" if ex.complete else f", BOUNDED at {max_states} states"
    name = (
        f"{subject} ({ex.system.num_states} states, {ex.system.num_edges} transitions, "
        f"≤{max_failures} failure(s){bound})"
    )
    verdicts = [model_check(ex.system, f, subject=name) for f in formulas]
    notes = []
    if not ex.complete:
        for v in verdicts:
            v.complete = False
        notes.append(
            f"exploration bounded at {max_states} states: a property with no counterexample "
            "among them is unknown, not established (raise the bound)"
        )
    return Report(verdicts, explored=ex.system.num_states, notes=notes)


class VerificationUnknown(VerificationError):
    """The tree gate's exploration hit its budget without a violation: unknown (exit 1)."""

    def __init__(self, report: Report, budget: int, option: str = "--verify-budget") -> None:
        super().__init__(report)
        self.budget = budget
        self.summary = (
            f"verification unknown: the behavior tree has more executions than the budget of "
            f"{budget} states covers (no violation among them); raise it with "
            f"{option} N (e.g. {option} {budget * 10}), or skip the gate with --no-verify"
        )
        self.args = (self.summary,)
