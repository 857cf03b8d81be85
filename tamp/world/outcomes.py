"""Where a symbolic skill's outcome comes from: a script of failures, or a branch to explore.

`SymbolicWorld` asks its outcome source once for each skill that finishes with its
preconditions still holding (a skill whose preconditions fail needs no decision: it fails).

- `ScriptedOutcomes`: `Fail` entries (``--fail``); the first ``times`` attempts of a
  matching action fail, every other attempt succeeds.
- `BranchingOutcomes`: what the explorer of every execution (`tamp.verification.bt`) configures.
  Before a tick it sets the outcomes to use (`choose`); each finishing skill that may fail
  takes the next one (SUCCESS when none is left) and records it in ``decisions``, so the
  explorer can branch on every decision. A skill may fail when it matches one of
  ``may_fail`` (every skill when None) and fewer than ``max_failures`` failures happened in
  this execution; `Fail.times` is not used here (the bound is per execution).
"""

from __future__ import annotations

import copy
from collections.abc import Hashable, Iterable
from typing import Protocol

from tamp.world.actions import Action
from tamp.world.events import Fail
from tamp.world.interface import Status


class OutcomeSource(Protocol):
    """Decides SUCCESS or FAILURE for a finishing skill; copied with the world."""

    #: why a FAILURE it decided happened (the world's history names it)
    reason: str

    def outcome(self, action: Action) -> Status:
        """SUCCESS or FAILURE for this attempt of ``action`` (may update the source)."""
        ...

    def key(self) -> Hashable:
        """What of the source decides future outcomes (states with equal keys merge)."""
        ...

    def copy(self) -> OutcomeSource:
        """An independent copy (the world's deep copy uses it)."""
        ...


class ScriptedOutcomes:
    """The first ``times`` attempts of each `Fail` entry's action fail; the rest succeed."""

    reason = "scripted failure"

    def __init__(self, failures: Iterable[Fail] = ()) -> None:
        self.failures = tuple(failures)
        self.left = [f.times for f in self.failures]

    def outcome(self, action: Action) -> Status:
        for i, f in enumerate(self.failures):
            if self.left[i] > 0 and f.matches(action.name, action.args):
                self.left[i] -= 1
                return Status.FAILURE
        return Status.SUCCESS

    def key(self) -> Hashable:
        return tuple(self.left)

    def copy(self) -> ScriptedOutcomes:
        new = copy.copy(self)
        new.left = list(self.left)
        return new


class BranchingOutcomes:
    """Outcomes set by an explorer, a bounded number of failures per execution."""

    reason = "failure chosen by the explorer"

    def __init__(self, may_fail: Iterable[Fail] | None = None, max_failures: int = 1) -> None:
        self.may_fail = None if may_fail is None else tuple(may_fail)
        self.failures_left = max_failures
        self.choices: list[Status] = []
        self.decisions: list[Status] = []

    def choose(self, choices: Iterable[Status]) -> None:
        """Use ``choices`` for the decisions of the next tick (then SUCCESS)."""
        self.choices = list(choices)
        self.decisions = []

    def may_fail_now(self, action: Action) -> bool:
        if self.failures_left <= 0:
            return False
        return self.may_fail is None or any(
            f.matches(action.name, action.args) for f in self.may_fail
        )

    def outcome(self, action: Action) -> Status:
        if not self.may_fail_now(action):
            return Status.SUCCESS
        k = len(self.decisions)
        out = self.choices[k] if k < len(self.choices) else Status.SUCCESS
        self.decisions.append(out)
        if out is Status.FAILURE:
            self.failures_left -= 1
        return out

    def key(self) -> Hashable:
        return self.failures_left

    def copy(self) -> BranchingOutcomes:
        new = copy.copy(self)
        new.choices = list(self.choices)
        new.decisions = list(self.decisions)
        return new
