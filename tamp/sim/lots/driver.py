"""Tick-based access to the workcell's skills over a `Simulator`: start / poll / cancel.

`CellDriver` gives scripts, tests and notebooks the `tamp.world.World` shape of the skill
layer (``start(action) -> handle``, ``poll(handle) -> Status``, ``cancel(handle)``): ``start``
sets the diagram's exported ``skill_command`` input, ``poll`` advances the simulation by one
tick and reads ``skill_status``. A controller inside the diagram (the LOTS LeafSystem) uses
the same ports instead; the driver is the diagram seen from outside.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol

from pydrake.systems.analysis import Simulator

from tamp.sim.core.messages import Observation, SkillCommand, SkillStatus
from tamp.sim.lots.station import LotsStation
from tamp.world.events import parse_call
from tamp.world.interface import Status


class ActionLike(Protocol):
    """What `start` accepts besides ``"Name(args)"``: a `tamp.world.actions.Action`."""

    @property
    def name(self) -> str: ...

    args: tuple[str, ...]


@dataclass
class DriverStats:
    """Sim time, wall time spent in `Simulator.AdvanceTo`, and frames rendered."""

    sim_time: float
    wall_time: float
    frames: int

    @property
    def rtf(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("inf")


class CellDriver:
    """The workcell's skills behind start / poll / cancel (one skill at a time)."""

    def __init__(self, cell: LotsStation, *, tick: float = 0.05):
        self.cell = cell
        self.tick = tick
        self.simulator = Simulator(cell.diagram)
        self.context = self.simulator.get_mutable_context()
        self._cmd = cell.diagram.get_input_port(0)
        self._status = cell.diagram.GetOutputPort("skill_status")
        self._obs = cell.diagram.GetOutputPort("observation")
        self._command = SkillCommand()
        self._cmd.FixValue(self.context, self._command)
        self._next = 1
        self._wall = 0.0
        self._t0 = self.context.get_time()
        self.simulator.Initialize()

    def advance(self, dt: float) -> None:
        t = time.perf_counter()
        self.simulator.AdvanceTo(self.context.get_time() + dt)
        self._wall += time.perf_counter() - t

    def start(self, action: str | ActionLike) -> int:
        if isinstance(action, str):
            name, args = parse_call(action)
        else:
            name, args = action.name, tuple(action.args)
        st = self.status()
        if self._command.id and st.id == self._command.id and st.status is Status.RUNNING:
            raise RuntimeError(f"{name}{args} started while {self._command} runs")
        self._command = SkillCommand(self._next, name, args)
        self._next += 1
        self._cmd.FixValue(self.context, self._command)
        return self._command.id

    def poll(self, handle: int) -> Status:
        st = self.status()
        if st.id == handle and st.status is not Status.RUNNING:
            return st.status
        self.advance(self.tick)
        st = self.status()
        return st.status if st.id == handle else Status.RUNNING

    def cancel(self, handle: int) -> None:
        if self._command.id == handle:
            c = self._command
            self._command = SkillCommand(c.id, c.name, c.args, cancel=True)
            self._cmd.FixValue(self.context, self._command)
            self.advance(self.cell.scenario.control.period * 2)

    def run(self, action: str | ActionLike, timeout: float = 120.0) -> SkillStatus:
        """Start ``action`` and poll it until it ends (or ``timeout`` sim seconds pass)."""
        h = self.start(action)
        t_end = self.context.get_time() + timeout
        while self.poll(h) is Status.RUNNING:
            if self.context.get_time() > t_end:
                self.cancel(h)
                break
        return self.status()

    def status(self) -> SkillStatus:
        return self._status.Eval(self.context)

    def observation(self) -> Observation:
        return self._obs.Eval(self.context)

    def skill_state(self):
        sk = self.cell.skills
        return sk.state(sk.GetMyContextFromRoot(self.context))

    def stats(self) -> DriverStats:
        p = self.cell.perception
        frames = p.state(p.GetMyContextFromRoot(self.context)).frames
        return DriverStats(self.context.get_time() - self._t0, self._wall, frames)

    def plant_context(self):
        return self.cell.plant.GetMyContextFromRoot(self.context)
