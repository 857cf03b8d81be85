"""A fresh executor for a demonstration: what ``tamp-verify bt`` and the notebooks check."""

from __future__ import annotations

from collections.abc import Sequence

from tamp.bt.executor import PaBtExecutor
from tamp.world.actions import Domain
from tamp.world.predicates import IsObjectAt


def executor_for(
    demo, order: Sequence[str] | None = None, *, domain: Domain | None = None
) -> PaBtExecutor:
    """A `PaBtExecutor` for a demonstration's goal ``order`` (``tamp plan``'s when None)."""
    if order is None:
        from tamp.rg import plan

        order = plan(demo).order
    c_goal = [IsObjectAt(demo.goal(g).object, demo.goal(g).area.name) for g in order]
    return PaBtExecutor(c_goal, domain or demo.domain(), free_areas=list(demo.free_areas))
