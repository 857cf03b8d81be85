"""RateTuningSupervisor: Fig. 5 online, one search per robot, on the Channels' deliveries.

Step 1: each robot starts from its current command rate P. Step 2: the supervisor sets P
(its ``rates`` output, read by the state machines) to the search's probe rate and watches the
robot's triggering sensors (those its behaviors' events read) for one probe window of sim
time; the probe's measurement is the longest *wait* any of their samples had in the
Channel (delivery - creation - service times: the queueing the architecture caused). A
wait under the threshold (`tamp.refine.architecture.Architecture.wait_threshold`) raises P
by a step; the first delayed probe ends the search with the P before the last increment
(`tamp.refine.steps.RateSearch`). Step 3 needs nothing here: a section advances one step
per command, so the base (and every section) moves faster by the same ratio as P while
the search runs, and `tamp.refine.steps.apply_rate` writes it into the program.

With ``tune=False`` the supervisor only watches: it records the longest wait per robot (the
check that the refined program's rate really delivers without delay) and leaves the rates
to the program.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.refine.steps import RateSearch
from tamp.sim.refine.channel import ChannelState
from tamp.sim.refine.messages import RateOverride


@dataclass(frozen=True)
class RobotWatch:
    """One robot: its search (None: not tuning), the current probe and the longest wait."""

    watched: tuple[str, ...]
    search: RateSearch | None = None
    probe_start: float = 0.0
    probe_wait: float = 0.0
    max_wait: float = 0.0

    def __deepcopy__(self, memo: dict) -> RobotWatch:
        return self


@dataclass(frozen=True)
class SupervisorState:
    robots: dict[str, RobotWatch]

    def __deepcopy__(self, memo: dict) -> SupervisorState:
        return self

    @property
    def done(self) -> bool:
        """Every search has ended (True when not tuning)."""
        return all(w.search is None or w.search.done for w in self.robots.values())

    def rates(self) -> dict[str, float]:
        out = {}
        for name, w in self.robots.items():
            if w.search is not None:
                out[name] = w.search.found if w.search.done else w.search.rate
        return out


class RateTuningSupervisor(LeafSystem):
    """Fig. 5 per robot (``searches``) or a watcher of the waits (``searches`` None)."""

    def __init__(
        self,
        watched: Mapping[str, Sequence[str]],
        period: float,
        window: float,
        empty: ChannelState,
        searches: Mapping[str, RateSearch] | None = None,
    ):
        super().__init__()
        self.set_name("rate_tuning_supervisor")
        self.window = window
        self.names = tuple(watched)
        self.delivered_ports = {
            n: self.DeclareAbstractInputPort(f"delivered_{n}", AbstractValue.Make(empty))
            for n in self.names
        }
        initial = SupervisorState(
            {
                n: RobotWatch(tuple(watched[n]), None if searches is None else searches[n])
                for n in self.names
            }
        )
        self._state = self.DeclareAbstractState(AbstractValue.Make(initial))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        self.rates_port = self.DeclareAbstractOutputPort(
            "rates",
            lambda: AbstractValue.Make(RateOverride()),
            lambda ctx, out: out.set_value(RateOverride(self.state(ctx).rates())),
            prerequisites_of_calc={self.abstract_state_ticket(self._state)},
        )

    def state(self, context) -> SupervisorState:
        return context.get_abstract_state(self._state).get_value()

    def _update(self, context, state) -> EventStatus:
        t = context.get_time()
        s = self.state(context)
        robots = {}
        for name, w in s.robots.items():
            ch: ChannelState = self.delivered_ports[name].Eval(context)
            waits = [d.wait for d in ch.recent if d.message.stream in w.watched]
            worst = max(waits, default=0.0)
            w = replace(w, probe_wait=max(w.probe_wait, worst), max_wait=max(w.max_wait, worst))
            if w.search is not None and not w.search.done and t - w.probe_start >= self.window:
                w = replace(w, search=w.search.observe(w.probe_wait), probe_start=t, probe_wait=0.0)
            robots[name] = w
        state.get_mutable_abstract_state(self._state).set_value(SupervisorState(robots))
        return EventStatus.Succeeded()
