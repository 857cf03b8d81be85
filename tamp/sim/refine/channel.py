"""Channel: one robot's communication architecture inside the diagram (Table 1, Fig. 2, Fig. 8).

The system holds the exact FIFO network of `tamp.refine.queues` in its abstract state and
changes it only in its periodic update, once per plant step Δ (the workcell's tick):

1. each sensor (force, IMU, odometry) is sampled at its own rate: every sample time
   k / rate in (t − Δ, t] gives one message created at that time, carrying the reading of
   `SensorReadings` at that time (the plant's state is held between its steps, so a
   sample between two steps carries the previous step's reading, kept in the state);
2. the command the state machine published at its last tick enters the network at its
   creation time, on the stream of its load (the sections it moves,
   `tamp.refine.architecture.Architecture.command_stream`);
3. the network advances to now; what it delivers becomes visible: the latest delivered
   sample of each sensor (``delivered`` output, what the state machine reads) and the latest
   delivered command, whose setpoints the actuators' sub-CPU applies (``actuation``
   output: the plant's desired state).

So a sample that queued behind other messages arrives late, and the state machine decides on
stale data; a command that queued reaches the actuators late. Nothing here is a formula
of the delay: the delay is what the queues did.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from tamp.refine.architecture import COMMAND
from tamp.refine.machine import Command
from tamp.refine.program import SENSORS
from tamp.refine.queues import Delivery, Network, QueueState
from tamp.sim.refine.messages import Readings


@dataclass(frozen=True)
class ChannelState:
    """The queues, the latest delivered message of each stream and this period's sensor
    deliveries (``recent``: what the supervisor judges)."""

    queue: QueueState
    latest: dict[str, Delivery] = field(default_factory=dict)
    recent: tuple[Delivery, ...] = ()
    injected: int = 0  # number of the last command put into the network
    samples: tuple[int, ...] = ()  # per sensor (`SENSORS` order): sample times k / rate taken
    previous: Readings = Readings()  # the reading of the last tick

    def __deepcopy__(self, memo: dict) -> ChannelState:
        return self  # immutable: Drake's state copies cost nothing

    def sample(self, sensor: str) -> Delivery | None:
        return self.latest.get(sensor)


class Channel(LeafSystem):
    """Sensor samples and commands of one robot through its FIFO network."""

    def __init__(
        self,
        name: str,
        network: Network,
        sensor_rates: Mapping[str, float],
        q_start: np.ndarray,
        tick: float,
        command_stream: Callable[[tuple[str, ...]], str] = lambda _: COMMAND,
    ):
        """``sensor_rates``: each sensor's sample rate (Hz); ``command_stream``: the stream
        a command moving these sections takes (its load)."""
        super().__init__()
        self.set_name(f"channel_{name}")
        self._network = network
        self._rates = tuple(float(sensor_rates[x]) for x in SENSORS)
        self._stream_of = command_stream
        self._streams: dict[tuple[str, ...], str] = {}
        #: per stream: the key of its latest delivery (every command stream is `COMMAND`)
        self._latest_key = {x: COMMAND if x.startswith(COMMAND) else x for x in network.routes}
        self._actuation_start = np.concatenate([q_start, np.zeros_like(q_start)])
        self._last: tuple[Delivery | None, np.ndarray] = (None, self._actuation_start)
        self.period = tick
        self.readings_port = self.DeclareAbstractInputPort(
            "readings", AbstractValue.Make(Readings())
        )
        self.command_port = self.DeclareAbstractInputPort("command", AbstractValue.Make(Command()))
        self._state = self.DeclareAbstractState(AbstractValue.Make(ChannelState(network.initial())))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update)
        ticket = {self.abstract_state_ticket(self._state)}
        self.delivered_port = self.DeclareAbstractOutputPort(
            "delivered",
            lambda: AbstractValue.Make(ChannelState(network.initial())),
            lambda ctx, out: out.set_value(self.state(ctx)),
            prerequisites_of_calc=ticket,
        )
        self.actuation_port = self.DeclareVectorOutputPort(
            "actuation",
            BasicVector(len(self._actuation_start)),
            self._calc_actuation,
            prerequisites_of_calc=ticket,
        )

    def state(self, context) -> ChannelState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_actuation(self, context, output) -> None:
        """The desired state of the robot's PD actuators: the latest delivered command's
        setpoints, zero velocities (the start pose before any command arrived)."""
        d = self.state(context).latest.get(COMMAND)
        if d is None:
            output.SetFromVector(self._actuation_start)
            return
        if d is not self._last[0]:  # the plant reads it every step; a command lasts many
            q = np.asarray(d.message.value.setpoints, dtype=float)
            self._last = (d, np.concatenate([q, np.zeros_like(q)]))
        output.SetFromVector(self._last[1])

    def _update(self, context, state) -> EventStatus:
        s = self.state(context)
        t = context.get_time()
        r: Readings = self.readings_port.Eval(context)
        previous = s.previous
        items = []
        taken = s.samples or (0,) * len(SENSORS)
        samples = []
        for x, rate, k in zip(SENSORS, self._rates, taken, strict=True):
            while k / rate <= t + 1e-9:
                created = k / rate
                items.append((x, created, (r if created >= t - 1e-9 else previous).value(x)))
                k += 1
            samples.append(k)
        items.sort(key=_created)  # one time order across the sensors
        cmd: Command = self.command_port.Eval(context)
        injected = s.injected
        if cmd.number > injected:
            stream = self._streams.get(cmd.sections)
            if stream is None:
                stream = self._streams[cmd.sections] = self._stream_of(cmd.sections)
            items.append((stream, min(cmd.created, t), cmd))
            injected = cmd.number
        queue, _ = self._network.inject(s.queue, items)
        queue, out = self._network.advance(queue, t)
        latest = s.latest
        recent = []
        if out:
            latest = dict(latest)
            key = self._latest_key
            for d in out:
                k = key[d.message.stream]
                latest[k] = d
                if k != COMMAND:
                    recent.append(d)
        new = ChannelState(queue, latest, tuple(recent), injected, tuple(samples), r)
        state.get_mutable_abstract_state(self._state).set_value(new)
        return EventStatus.Succeeded()


def _created(item: tuple) -> float:
    """The creation time of a message ``(stream, created, value)`` to be injected."""
    return item[1]
