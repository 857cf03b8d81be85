"""RateTuningSupervisor: Fig. 5 online, one search per robot, on the Channels' deliveries.

Step 1: each robot starts from its current command rate P. Step 2, per behavior: the
sensor that triggers a behavior's event is watched while P rises. The supervisor runs one
search per robot and triggering sensor (the sensors its behaviors' events read); P is one
per robot, so the searches probe the same rates together and each judges its own sensor:
for one probe window of sim time, the longest *wait* of that sensor's samples in the
Channel (delivery - creation - service times: the queueing the architecture caused). A
wait under the sensor's threshold (`tamp.refine.architecture.Architecture.wait_threshold`)
raises P by a step; the first delayed probe ends that sensor's search with the P before
the last increment (`tamp.refine.steps.RateSearch`); P keeps rising while another
sensor's search runs. A behavior's rate is its trigger sensor's (Step 4: every behavior
analysed; `tamp.refine.refinement.behavior_rates`). While the search runs each section
moves one step per command, so it moves faster with P; what the refined program keeps is
Step 3's (`tamp.refine.steps.apply_rate`).

With ``tune=False`` the supervisor only watches: it records the longest wait per robot and
per watched sensor (the check that the refined program's rates really deliver without
delay, `tamp.refine.refinement.delayed`) and leaves the rates to the program.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.refine.queues import Delivery
from tamp.refine.steps import RateSearch
from tamp.sim.refine.channel import ChannelState
from tamp.sim.refine.messages import RateOverride


@dataclass(frozen=True)
class RobotWatch:
    """One robot: its watched sensors, one search per sensor (empty: not tuning), the
    current probe's start and longest wait per sensor, and the longest wait of the run."""

    watched: tuple[str, ...]
    searches: dict[str, RateSearch] = field(default_factory=dict)
    probe_start: float = 0.0
    probe_waits: dict[str, float] = field(default_factory=dict)
    max_wait: float = 0.0
    sensor_waits: dict[str, float] = field(default_factory=dict)  # longest per sensor

    def __deepcopy__(self, memo: dict) -> RobotWatch:
        return self

    @property
    def done(self) -> bool:
        return all(s.done for s in self.searches.values())

    def rate(self) -> float | None:
        """The rate the robot commands at now: the probe of the searches still running
        (they step together: one P per robot), or the lowest found once all ended."""
        if not self.searches:
            return None
        running = [s.rate for s in self.searches.values() if not s.done]
        if running:
            return min(running)
        return min(s.found for s in self.searches.values() if s.found is not None)


@dataclass(frozen=True)
class SupervisorState:
    robots: dict[str, RobotWatch]

    def __deepcopy__(self, memo: dict) -> SupervisorState:
        return self

    @property
    def done(self) -> bool:
        """Every search has ended (True when not tuning)."""
        return all(w.done for w in self.robots.values())

    def rates(self) -> dict[str, float]:
        out = {}
        for name, w in self.robots.items():
            rate = w.rate()
            if rate is not None:
                out[name] = rate
        return out


class RateTuningSupervisor(LeafSystem):
    """Fig. 5 per robot and watched sensor (``searches``: robot -> sensor -> search) or a
    watcher of the waits (``searches`` None)."""

    def __init__(
        self,
        watched: Mapping[str, Sequence[str]],
        period: float,
        window: float,
        empty: ChannelState,
        searches: Mapping[str, Mapping[str, RateSearch]] | None = None,
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
                n: RobotWatch(tuple(watched[n]), {} if searches is None else dict(searches[n]))
                for n in self.names
            }
        )
        self._state = self.DeclareAbstractState(AbstractValue.Make(initial))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        self._rates: tuple[SupervisorState | None, RateOverride] = (None, RateOverride())
        self.rates_port = self.DeclareAbstractOutputPort(
            "rates",
            lambda: AbstractValue.Make(RateOverride()),
            self._calc_rates,
            prerequisites_of_calc={self.abstract_state_ticket(self._state)},
        )

    def state(self, context) -> SupervisorState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_rates(self, context, output) -> None:
        """The searches' rates (recomputed only when the state object changed)."""
        s = self.state(context)
        if s is not self._rates[0]:
            self._rates = (s, RateOverride(s.rates()))
        output.set_value(self._rates[1])

    def _update(self, context, state) -> EventStatus:
        t = context.get_time()
        s = self.state(context)
        robots = {}
        changed = False
        for name, w in s.robots.items():
            ch: ChannelState = self.delivered_ports[name].Eval(context)
            new = self._watch(w, ch.recent, t)
            changed = changed or new is not w
            robots[name] = new
        if not changed:
            return EventStatus.DidNothing()
        state.get_mutable_abstract_state(self._state).set_value(SupervisorState(robots))
        return EventStatus.Succeeded()

    def _watch(self, w: RobotWatch, recent: Sequence[Delivery], t: float) -> RobotWatch:
        """``w`` after this tick's sensor deliveries ``recent`` at time ``t`` (``w`` itself
        when no longest wait grew and no probe ended)."""
        waits = w.probe_waits
        longest = w.sensor_waits
        worst = 0.0
        for d in recent:
            sensor = d.message.stream
            if sensor in w.watched:
                if d.wait > waits.get(sensor, 0.0):
                    waits = {**waits, sensor: d.wait}
                worst = max(worst, d.wait)
                if d.wait > longest.get(sensor, 0.0):
                    longest = {**longest, sensor: d.wait}
        if waits is not w.probe_waits or longest is not w.sensor_waits or worst > w.max_wait:
            w = replace(w, probe_waits=waits, max_wait=max(w.max_wait, worst), sensor_waits=longest)
        if w.searches and not w.done and t - w.probe_start >= self.window:
            searches = {
                k: v.observe(waits.get(k, 0.0)) if not v.done else v for k, v in w.searches.items()
            }
            w = replace(w, searches=searches, probe_start=t, probe_waits={})
        return w
