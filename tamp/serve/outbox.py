"""A client's bounded send queue: a slow or stalled reader never delays anyone else.

rosbridge servers have stalled every client behind one that does not read (rosbridge
issues #192, #212, #437). Here fan-out only *puts* text into each client's `Outbox` (never
awaits a send); one writer task per client drains it. The queue is bounded in messages and
bytes: past either bound the oldest entry is dropped and counted. A message with a
``slot`` key (the latest robot pose, ``/tf``, the BT status) replaces the previous one of
that key still waiting, so a stream never queues stale copies.
"""

from __future__ import annotations

import asyncio
import itertools
from collections import OrderedDict
from dataclasses import dataclass


@dataclass
class OutboxStats:
    """What happened to one client's outgoing messages."""

    queued: int = 0
    sent: int = 0
    dropped: int = 0
    replaced: int = 0


class Outbox:
    """Bounded, ordered, with latest-wins slots; `get` waits for the next message."""

    def __init__(self, *, max_messages: int = 256, max_bytes: int = 4 << 20):
        self.max_messages = max_messages
        self.max_bytes = max_bytes
        self._items: OrderedDict[object, str] = OrderedDict()
        self._bytes = 0
        self._seq = itertools.count()
        self._ready = asyncio.Event()
        self.stats = OutboxStats()
        self.closed = False

    def put(self, text: str, slot: str | None = None) -> None:
        """Queue ``text`` (replacing the waiting message of ``slot``, if any); drop the oldest
        entries while over a bound. Never blocks."""
        if self.closed:
            return
        key: object = ("slot", slot) if slot is not None else next(self._seq)
        old = self._items.get(key)
        if old is not None:
            self._bytes -= len(old)
            self._items[key] = text
            self.stats.replaced += 1
        else:
            self._items[key] = text
        self._bytes += len(text)
        self.stats.queued += 1
        while len(self._items) > 1 and (
            len(self._items) > self.max_messages or self._bytes > self.max_bytes
        ):
            _, dropped = self._items.popitem(last=False)
            self._bytes -= len(dropped)
            self.stats.dropped += 1
        self._ready.set()

    async def get(self) -> str | None:
        """The oldest waiting message; None once closed."""
        while not self._items:
            if self.closed:
                return None
            self._ready.clear()
            await self._ready.wait()
        _, text = self._items.popitem(last=False)
        self._bytes -= len(text)
        self.stats.sent += 1
        return text

    def close(self) -> None:
        self.closed = True
        self._items.clear()
        self._bytes = 0
        self._ready.set()

    def __len__(self) -> int:
        return len(self._items)
