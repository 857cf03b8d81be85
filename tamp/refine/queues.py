"""Message queues of the communication architecture: an exact, deterministic FIFO network.

Each server (a sub-CPU, the shared channel, the main CPU) handles one message at a time,
first come first served, with a service time per message kind. A message follows a route
of hops ``(server, service time)``; it leaves hop ``k`` at ``max(arrival, server free) +
service`` (Lindley's recursion) and arrives at hop ``k + 1`` then; it is *delivered* when
it leaves its last hop. Arrivals are processed in global time order (ties by injection
order), which is exactly FIFO at every server.

The state is small and explicit (`QueueState`: the future arrivals and each server's
next-free time), and `advance` is a pure function of it, so the same code runs offline
(`deliver`, `periodic_waits`) and inside the simulation's Channel LeafSystem, which
advances it once per tick.

The *wait* of a delivered message is the time it spent queued: delivery − creation − the
sum of its service times. It is zero on an idle network and grows without bound once a
server's utilisation ``ρ = Σ rate · service`` exceeds 1.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any


@dataclass(frozen=True)
class Hop:
    """One server on a route and the time it spends on each message of that route."""

    server: str
    service: float


Route = tuple[Hop, ...]


@dataclass(frozen=True)
class Message:
    """A sensor sample or a command: its stream, creation time, order and payload."""

    stream: str
    created: float
    seq: int
    value: Any = None

    def __deepcopy__(self, memo: dict) -> Message:
        return self  # immutable (payloads are numbers or frozen dataclasses)


@dataclass(frozen=True)
class Delivery:
    """A message delivered at ``time`` after queuing for ``wait`` seconds in total."""

    message: Message
    time: float
    wait: float

    @property
    def latency(self) -> float:
        return self.time - self.message.created

    def __deepcopy__(self, memo: dict) -> Delivery:
        return self


@dataclass(frozen=True)
class QueueState:
    """Future arrivals ``(time, seq, hop, message, wait so far)`` and servers' free times."""

    pending: tuple[tuple[float, int, int, Message, float], ...] = ()
    free_at: tuple[tuple[str, float], ...] = ()
    next_seq: int = 0
    now: float = 0.0


@dataclass
class Network:
    """Routes of every stream; `advance` moves a `QueueState` forward in time."""

    routes: Mapping[str, Route]
    servers: tuple[str, ...] = field(init=False)
    _hops: dict[str, tuple[tuple[str, float], ...]] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        names: list[str] = []
        for route in self.routes.values():
            if not route:
                raise ValueError("a route needs at least one hop")
            for hop in route:
                if hop.service < 0:
                    raise ValueError(f"negative service time on {hop.server}")
                if hop.server not in names:
                    names.append(hop.server)
        self.servers = tuple(names)
        # each stream's hops as plain (server, service) pairs: `advance` runs every tick
        self._hops = {k: tuple((h.server, h.service) for h in r) for k, r in self.routes.items()}

    def initial(self) -> QueueState:
        return QueueState(free_at=tuple((s, -math.inf) for s in self.servers))

    def utilisation(self, rates: Mapping[str, float]) -> dict[str, float]:
        """ρ per server for streams at ``rates`` (messages per second)."""
        rho = {s: 0.0 for s in self.servers}
        for stream, rate in rates.items():
            for hop in self.routes[stream]:
                rho[hop.server] += rate * hop.service
        return rho

    def inject(
        self, state: QueueState, items: Iterable[tuple[str, float, Any]]
    ) -> tuple[QueueState, list[Message]]:
        """Add messages ``(stream, created, value)``; creation times must not be in the past
        of what `advance` already processed."""
        pending = list(state.pending)
        seq = state.next_seq
        made = []
        routes, now, push = self.routes, state.now - 1e-12, heapq.heappush
        for stream, created, value in items:
            if stream not in routes:
                raise KeyError(f"no route for stream {stream!r}")
            if created < now:
                raise ValueError(f"message created at {created} before the queue time {state.now}")
            m = Message(stream, float(created), seq, value)
            made.append(m)
            push(pending, (m.created, seq, 0, m, 0.0))
            seq += 1
        if not made:
            return state, made
        return QueueState(tuple(pending), state.free_at, seq, state.now), made

    def advance(self, state: QueueState, until: float) -> tuple[QueueState, list[Delivery]]:
        """Process every arrival up to ``until``; returns the new state and the deliveries."""
        now = max(state.now, until)
        if not state.pending or state.pending[0][0] > until:  # nothing arrives by then
            return (state if now == state.now else replace(state, now=now)), []
        pending = list(state.pending)  # a heap already: tuples keep the list's order
        free = dict(state.free_at)
        out: list[Delivery] = []
        hops = self._hops
        pop, push = heapq.heappop, heapq.heappush
        while pending and pending[0][0] <= until:
            t, seq, hop, m, wait = pop(pending)
            route = hops[m.stream]
            if hop == len(route):
                out.append(Delivery(m, t, wait))
                continue
            server, service = route[hop]
            free_at = free[server]
            start = t if t > free_at else free_at
            done = start + service
            free[server] = done
            push(pending, (done, seq, hop + 1, m, wait + (start - t)))
        new = QueueState(
            pending=tuple(pending),
            free_at=tuple(free.items()),
            next_seq=state.next_seq,
            now=now,
        )
        return new, out


def deliver(network: Network, items: Iterable[tuple[str, float, Any]]) -> list[Delivery]:
    """Deliveries of a whole message stream (batch form of `Network.advance`)."""
    state, _ = network.inject(network.initial(), sorted(items, key=lambda x: x[1]))
    _, out = network.advance(state, math.inf)
    return out


def periodic(stream: str, rate: float, start: float, end: float) -> list[tuple[str, float, Any]]:
    """Messages of ``stream`` at ``start + k / rate`` for every such time < ``end``."""
    n = max(0, math.ceil((end - start) * rate - 1e-9))
    return [(stream, start + k / rate, None) for k in range(n)]


def periodic_waits(
    network: Network, rates: Mapping[str, float], horizon: float
) -> dict[str, list[float]]:
    """Per stream, the waits of its messages when every stream runs periodically at its
    rate from time 0 for ``horizon`` seconds (all streams start together: the critical
    instant), in delivery order."""
    items: list[tuple[str, float, Any]] = []
    for stream, rate in rates.items():
        items += periodic(stream, rate, 0.0, horizon)
    waits: dict[str, list[float]] = {s: [] for s in rates}
    for d in deliver(network, items):
        waits[d.message.stream].append(d.wait)
    return waits


def max_wait(waits: Mapping[str, Sequence[float]], streams: Iterable[str]) -> float:
    """The longest wait among ``streams`` (0 when none was delivered)."""
    return max((w for s in streams for w in waits.get(s, ())), default=0.0)
