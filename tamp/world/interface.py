"""The interface every executor (BT, LOTS) ticks against, and its skill status values.

Two implementations exist: ``tamp.world.symbolic.SymbolicWorld`` (effects applied after a
configurable number of ticks; scripted failures and interference) and the Drake world in
``tamp.sim`` (state read from the MultibodyPlant, skills drive joints). The same
controller object runs on both, so what is verified symbolically is what the simulated
robot runs.
"""

from __future__ import annotations

from enum import Enum
from typing import Protocol, runtime_checkable

from tamp.world.actions import Action
from tamp.world.state import WorldState


class Status(Enum):
    """Result of ticking a BT node, and of polling a running skill."""

    SUCCESS = "SUCCESS"
    FAILURE = "FAILURE"
    RUNNING = "RUNNING"

    def __str__(self) -> str:
        return self.value


@runtime_checkable
class World(Protocol):
    """What a controller may do: observe, start one skill, poll it, cancel it.

    ``start`` returns a handle; at most one skill runs at a time (the robot does one thing
    at a time), so starting a second while one runs is a programming error that
    implementations report with ``RuntimeError``.
    """

    def observe(self) -> WorldState:
        """The current symbolic state (in Drake: estimated from the plant / cameras)."""
        ...

    def start(self, action: Action) -> int:
        """Begin executing ``action``; returns a handle for `poll` and `cancel`."""
        ...

    def poll(self, handle: int) -> Status:
        """RUNNING while the skill runs, then SUCCESS or FAILURE (sticky)."""
        ...

    def cancel(self, handle: int) -> None:
        """Stop the skill now (halt): the world keeps whatever state it reached."""
        ...
