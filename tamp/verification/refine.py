"""Refined programs (Figueroa Heredia et al., J. Robot. Mechatron. 2018): the ordering
property holds on every execution of a program before it is simulated, or the refinement is
refused with the counterexample.

The executions of a program are the paths through the downsets of its event order
(`tamp.refine.order.downsets`): each state is the set of events fired so far, which is
also its label ("has fired" semantics), and the full set repeats forever. That system goes
to `tamp.verification.kripke.model_check`; a finished run (the measured event order) goes to
`tamp.verification.traces.check_trace` as a finite word of the same labels.
"""

from __future__ import annotations

from collections.abc import Sequence

from tamp.refine.order import downsets
from tamp.refine.program import Program
from tamp.verification.kripke import TransitionSystem, model_check
from tamp.verification.traces import check_trace
from tamp.verification.verdict import Verdict
from tamp.verification.words import Word


def executions(program: Program) -> TransitionSystem:
    """Every execution of ``program`` as a transition system over fired-event sets."""
    states, succ = downsets(program)
    ts = TransitionSystem()
    for fired in states:
        ts.add_state(fired, "{" + ", ".join(sorted(fired)) + "}")
    for s, nxt in enumerate(succ):
        for d in nxt:
            ts.add_edge(s, d)
    return ts


def check_program(program: Program, *, subject: str | None = None) -> Verdict:
    """Verdict "every execution of ``program`` satisfies its ordering property"."""
    return model_check(
        executions(program), program.ordering, subject=subject or f"program {program.name}"
    )


def check_run(program: Program, order: Sequence[str]) -> Verdict:
    """The measured event order of one run against the ordering property (finite trace)."""
    fired: set[str] = set()
    letters = []
    for e in order:
        fired.add(e)
        letters.append(frozenset(fired))
    return check_trace(program.ordering, Word.finite(letters), subject=f"run of {program.name}")
