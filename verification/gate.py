"""`gate(plan)`: the check every planner front end runs before execution or simulation.

ARCHITECTURE "Verification gate": a failing check raises `VerificationError` (an
`InfeasibleError`, so the CLIs exit 1) carrying the `Report` and its counterexample; a
passing check returns the `Report` (what ``--json`` front ends can print).

Dispatch is on the plan's type, by duck typing so that importing `verification` never
imports a layer that the caller did not use:

- `tamp.rg.PlanResult` (``.order`` and ``.demo``): the order trace against the
  constraint encoding, and every path of the RG (`verification.rg.check_plan`);
- `tamp.lots.controller.LotsController` (``.plan_letters()`` and ``.table``): the planned
  run and every entry of T (`verification.lots.check_controller`);
- `tamp.bt.PaBtExecutor` (``.root`` and ``.c_goal``): every execution from ``state``
  (required) with the safety properties and ``F goal`` (`verification.bt.check_tree`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from verification.verdict import Report, VerificationError


def gate(
    plan,
    *,
    state=None,
    properties: Sequence[str] | None = None,
    events: Iterable = (),
    max_failures: int = 1,
    graph: bool = True,
) -> Report:
    """Verify ``plan``; return its `Report`, or raise `VerificationError` when it fails.

    ``state`` (BT only): the initial `WorldState` the tree will run from. ``properties``
    (BT only): LTL properties, default `verification.bt.DEFAULT_PROPERTIES`. ``events``
    (BT only): scripted interference (`tamp.world.events.Appear`).
    ``max_failures`` (BT only): skill failures per execution. ``graph`` (RG only): also
    model-check the whole reachability graph.
    """
    if hasattr(plan, "order") and hasattr(plan, "demo"):
        from verification.rg import check_plan

        report = check_plan(plan, graph=graph)
    elif hasattr(plan, "plan_letters") and hasattr(plan, "table"):
        from verification.lots import check_controller

        report = check_controller(plan)
    elif hasattr(plan, "root") and hasattr(plan, "c_goal"):
        from verification.bt import DEFAULT_PROPERTIES, check_tree

        if state is None:
            raise ValueError("gate(executor) needs state=<the initial WorldState>")
        report = check_tree(
            plan,
            state,
            properties if properties is not None else DEFAULT_PROPERTIES,
            events=events,
            max_failures=max_failures,
        )
    else:
        raise TypeError(
            f"gate() does not know how to verify a {type(plan).__name__} "
            "(expected an RG PlanResult, a LotsController or a PaBtExecutor)"
        )
    if not report.holds:
        raise VerificationError(report)
    return report
