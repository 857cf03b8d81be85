"""The verification gate: what every front end runs before a plan executes or is simulated.

See docs/architecture.md, "The verification gate". One typed entry point per kind of plan;
each returns the `Report` (what ``--json`` front ends print) or raises `VerificationError` (an
`InfeasibleError`: the CLIs exit 1) carrying the report and its counterexample:

- `gate_order` — the RG planner's `tamp.rg.PlanResult`: the order trace against the LTL
  encoding of C, and every path of the plan's reachability graph (`tamp.verification.rg`);
- `gate_tree` — a `tamp.bt.PaBtExecutor` before it ticks: every execution of the grown tree
  from ``state`` (appearances, bounded skill failures) against the safety properties and
  ``F goal`` (`tamp.verification.bt`, explored goal subtree by goal subtree); the executor itself
  is not ticked; a tree that its state budget cannot cover is refused as unknown;
- `gate_table` — a `tamp.lots.controller.LotsController`: the planned run and every entry
  of its current table T, from where that table was built (`tamp.verification.lots`);
- `gate_program` — a refinement `tamp.refine.Program`: every execution of its state
  machines (the downsets of its event order) against its LTL ordering property
  (`tamp.verification.refine`), before the (refined) program is simulated.

`gate(plan, ...)` dispatches on the plan's type to the same three functions.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

from tamp.verification.verdict import Report, VerificationError

if TYPE_CHECKING:
    from tamp.bt.executor import PaBtExecutor
    from tamp.lots.controller import LotsController
    from tamp.refine.program import Program
    from tamp.rg.plan import PlanResult
    from tamp.world.events import Appear, Fail
    from tamp.world.state import WorldState


def _passed(report: Report) -> Report:
    """Raise on a violation; an "unknown" (bounded) report passes, its notes saying so."""
    if report.violated:
        raise VerificationError(report)
    return report


def gate_order(plan: PlanResult, *, graph: bool = True) -> Report:
    """The chosen goal order (and, when ``graph``, the whole RG) against C's encoding.

    First, structurally: every goal condition of the order must be the effect of some
    usable action template of the robot's domain (`tamp.world.achievable`); otherwise the
    task is infeasible (`InfeasibleError`, exit 1) for that reason, before any model checking.
    """
    from tamp.verification.rg import check_plan

    _achievable(plan)
    return _passed(check_plan(plan, graph=graph))


def _achievable(plan: PlanResult) -> None:
    from tamp.errors import InfeasibleError
    from tamp.world.achievable import unachievable_goals

    demo = plan.demo
    domain = demo.domain()
    bad = unachievable_goals(domain, plan.c_goal, demo.initial_world())
    if not bad:
        return
    by_reason: dict[str, list[str]] = {}
    for u in bad:
        by_reason.setdefault(u.reason, []).append(str(u.goal))
    parts = []
    for reason, goals in by_reason.items():
        shown = ", ".join(goals[:3]) + (f" and {len(goals) - 3} more" if len(goals) > 3 else "")
        parts.append(f"{shown} can never be achieved: {reason}")
    raise InfeasibleError("the robot cannot do this task: " + "; ".join(parts))


def gate_tree(
    executor: PaBtExecutor,
    state: WorldState,
    *,
    properties: Sequence[str] | None = None,
    events: Iterable[Appear] = (),
    failures: Sequence[Fail] | None = None,
    max_failures: int = 1,
    budget: int | None = None,
    allow_unknown: bool = False,
) -> Report:
    """Every execution of ``executor``'s grown tree from ``state`` (it is not ticked).

    ``properties``: LTL over the exploration's propositions (default
    `tamp.verification.bt.DEFAULT_PROPERTIES`); ``events``: appearances; ``failures``: the skills
    that may fail (None: every skill), at most ``max_failures`` per execution.
    ``budget``: the states the exploration may visit (default
    `tamp.verification.bt.DEFAULT_MAX_STATES`; ``--verify-budget``). A tree it cannot cover
    within the budget is neither passed nor refused as unsafe: `VerificationUnknown` (exit
    1) names the budget and how to raise it; ``allow_unknown`` lets such a report pass,
    its notes saying so.
    """
    from tamp.verification.bt import DEFAULT_MAX_STATES, DEFAULT_PROPERTIES, check_tree
    from tamp.verification.bt.check import VerificationUnknown

    limit = DEFAULT_MAX_STATES if budget is None else budget
    report = check_tree(
        executor,
        state,
        properties if properties is not None else DEFAULT_PROPERTIES,
        events=events,
        failures=failures,
        max_failures=max_failures,
        max_states=limit,
    )
    if report.status == "unknown" and not allow_unknown:
        raise VerificationUnknown(report, limit)
    return _passed(report)


def gate_table(controller: LotsController) -> Report:
    """The LOTS controller's planned run and every entry of its table T."""
    from tamp.verification.lots import check_controller

    return _passed(check_controller(controller))


def gate_program(program: Program, *, subject: str | None = None) -> Report:
    """Every execution of ``program`` against its ordering property (the safety of Step 2 of
    Figueroa Heredia et al. 2018, §3.2): a refinement that lets some execution break it is
    refused."""
    from tamp.verification.refine import check_program

    return _passed(Report([check_program(program, subject=subject)]))


def _tree(plan: PaBtExecutor, *, state: WorldState | None = None, **kw) -> Report:
    if state is None:
        raise ValueError("gate(executor) needs state=<the initial WorldState>")
    return gate_tree(plan, state, **kw)


#: The entry point per plan type, keyed by the type's import path: dispatching by name keeps
#: the layers unimported until a plan of theirs arrives (`tamp lots` never loads the RG planner
#: and its scipy).
_ENTRIES = {
    "tamp.rg.plan.PlanResult": gate_order,
    "tamp.refine.program.Program": gate_program,
    "tamp.lots.controller.LotsController": gate_table,
    "tamp.bt.executor.PaBtExecutor": _tree,
}


def gate(plan: object, **options) -> Report:
    """Verify ``plan`` with the entry point for its type (see the module docstring)."""
    for cls in type(plan).__mro__:
        entry = _ENTRIES.get(f"{cls.__module__}.{cls.__qualname__}")
        if entry is not None:
            return entry(plan, **options)
    raise TypeError(
        f"gate() does not know how to verify a {type(plan).__name__} "
        "(expected an RG PlanResult, a PaBtExecutor, a LotsController or a refinement Program)"
    )
