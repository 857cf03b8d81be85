"""A rosbridge v2 server without ROS: topics, services and ``/rosapi`` over one WebSocket.

The ROS# MR apps of SMP-MRO (Nakamura & Sekiyama, IEEE Access, §V: HoloLens 2 → ROS# →
rosbridge), roslibpy and roslibjs all speak rosbridge v2 JSON. `RosbridgeServer` implements
what they use (advertise/unadvertise, publish, subscribe/unsubscribe with ``throttle_rate``
and ``queue_length``, latched topics re-sent to new subscribers, ``call_service`` answered
by exactly one ``service_response`` with the same id, ``fragment`` in, ``set_level``, and
the ``/rosapi`` introspection calls), robust by default:

- every frame goes through `tamp.serve.wire` (strict JSON, op table); a bad message is
  dropped and counted, the connection stays open (as rosbridge does), and a ``status`` op
  is sent only to a client that asked for one with ``set_level``; more than
  `Limits.errors_per_minute` bad messages close the connection (1008);
- the WebSocket library enforces `Limits.max_message` (close 1009), pings (half-open
  clients), and reassembles continuation frames;
- fan-out only puts text into each client's `Outbox`; one writer task per client sends, so
  a client that never reads delays nobody else;
- each service call is its own task with a timeout, handlers that compute (planning,
  simulation) run in worker threads (`RosbridgeServer.service(..., blocking=True)`);
- the WebSocket handshake checks an optional token (``?token=``: browsers cannot set
  headers on a WebSocket; the page's static files need none), the Origin header against an
  allowlist (no Origin, as sent by ROS#, roslibpy and other non-browser clients, is
  accepted; a browser page is accepted from this server's own address and the listed
  origins) and the client count (503); plain HTTP requests get the demonstration page's
  static files.
"""

from __future__ import annotations

import asyncio
import collections
import logging
import mimetypes
import threading
import time
from collections.abc import Awaitable, Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

from tamp.serve.outbox import Outbox
from tamp.serve.wire import Fragments, Op, WireError, dumps, finite, loads, parse

log = logging.getLogger("tamp.serve")

#: Message types whose streams are latest-wins for every subscriber (a pose at 50 Hz:
#: only the newest matters to a client that fell behind).
STREAM_TYPES = frozenset(
    {
        "geometry_msgs/PoseStamped",
        "geometry_msgs/Pose",
        "tf2_msgs/TFMessage",
        "sensor_msgs/JointState",
        "nav_msgs/Odometry",
    }
)


@dataclass(frozen=True)
class Limits:
    """The server's bounds (the CLI exposes each as an option)."""

    max_clients: int = 8
    max_message: int = 1 << 20  # bytes per WebSocket message (close 1009 beyond)
    queue_messages: int = 256  # per client send queue
    queue_bytes: int = 4 << 20
    errors_per_minute: int = 100  # bad messages before a client is closed (1008)
    service_timeout: float = 30.0  # s, unless the call asks for less
    fragment_age: float = 30.0  # s from a message's first fragment to its last
    max_topics: int = 1024  # topics in all (clients create them by advertising)
    topics_per_client: int = 256  # subscribed or advertised by one client
    calls_per_client: int = 16  # service calls of one client in progress at once
    ping_interval: float | None = 20.0


class ServiceError(Exception):
    """A call that failed as a protocol matter: answered ``result: false`` with this text."""


Handler = Callable[["Client", dict[str, Any]], Any]


@dataclass
class Service:
    name: str
    type: str
    handler: Handler
    blocking: bool = False  # run in a worker thread
    timeout: float | None = None
    request_fields: tuple[str, ...] = ()


@dataclass
class Topic:
    name: str
    type: str
    latched: bool = False
    slot: bool = False  # latest-wins in every client's queue
    inbound: Callable[[Client, dict[str, Any]], None] | None = None  # client → server
    server_owned: bool = False  # only the server publishes it
    last: str | None = None  # the latched message's text
    publishers: set[int] = field(default_factory=set)


@dataclass
class Subscription:
    throttle_ms: float = 0.0
    queue_length: int = 0


@dataclass
class _Throttle:
    last: float = -1e18
    pending: collections.deque = field(default_factory=lambda: collections.deque(maxlen=1))
    timer: asyncio.TimerHandle | None = None


class Client:
    """One connection: its queue, subscriptions, advertisements and error budget."""

    def __init__(self, cid: int, ws: Any, limits: Limits):
        self.id = cid
        self.ws = ws
        self.outbox = Outbox(max_messages=limits.queue_messages, max_bytes=limits.queue_bytes)
        self.subs: dict[str, dict[Any, Subscription]] = {}
        self.throttle: dict[str, _Throttle] = {}
        self.adverts: set[str] = set()
        self.fragments = Fragments(max_bytes=limits.max_message, max_age=limits.fragment_age)
        self.level = "none"
        self.errors: collections.deque[float] = collections.deque()
        self.error_count = 0
        self.warned_drop = False
        self.calls = 0  # service calls in progress

    def wants_status(self, level: str) -> bool:
        order = ("info", "warning", "error")
        return self.level != "none" and order.index(level) >= order.index(self.level)


class RosbridgeServer:
    """Topics, services and the connection handling (module docstring)."""

    def __init__(
        self,
        *,
        limits: Limits | None = None,
        token: str | None = None,
        origins: Iterable[str] = (),
        web_root: Path | None = None,
        node_name: str = "/tamp_serve",
    ):
        self.limits = limits or Limits()
        self.token = token
        self.origins = {o.rstrip("/") for o in origins}
        self.web_root = web_root
        self.node_name = node_name
        self.topics: dict[str, Topic] = {}
        self.services: dict[str, Service] = {}
        self.clients: dict[int, Client] = {}
        self.counters: collections.Counter[str] = collections.Counter()
        self._ids = iter(range(1, 1 << 62))
        self.loop: asyncio.AbstractEventLoop | None = None
        self._server: Any = None
        self.port: int | None = None
        self._add_rosapi()

    # ---- declarations -------------------------------------------------------------------

    def topic(
        self,
        name: str,
        type_: str,
        *,
        latched: bool = False,
        slot: bool = False,
        inbound: Callable[[Client, dict[str, Any]], None] | None = None,
    ) -> Topic:
        """Declare a topic the server publishes (``inbound`` None) or consumes."""
        t = Topic(name, type_, latched=latched, slot=slot, inbound=inbound)
        t.server_owned = inbound is None
        self.topics[name] = t
        return t

    def service(
        self,
        name: str,
        type_: str,
        handler: Handler,
        *,
        blocking: bool = False,
        timeout: float | None = None,
        request_fields: tuple[str, ...] = (),
    ) -> None:
        """Declare a service; ``blocking`` handlers run in a worker thread."""
        self.services[name] = Service(name, type_, handler, blocking, timeout, request_fields)

    # ---- publishing (server side) ---------------------------------------------------------

    def publish(self, name: str, msg: dict[str, Any]) -> None:
        """Send ``msg`` on ``name`` to its subscribers (event-loop thread only)."""
        topic = self.topics[name]
        try:
            text = dumps({"op": "publish", "topic": name, "msg": msg})
        except ValueError:  # NaN or infinity: never sent
            self.counters["refused_nonfinite_out"] += 1
            log.warning("not sending a non-finite value on %s", name)
            return
        self._fan_out(topic, text)

    def publish_threadsafe(self, name: str, msg: dict[str, Any]) -> None:
        """`publish` from a worker thread (directly, before the server has started: then it
        only sets a latched topic's message)."""
        if self.loop is None:
            self.publish(name, msg)
        elif not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self.publish, name, msg)

    def _fan_out(self, topic: Topic, text: str) -> None:
        if topic.latched:
            topic.last = text
        self.counters["published"] += 1
        for client in list(self.clients.values()):
            subs = client.subs.get(topic.name)
            if subs:
                self._offer(client, topic, subs, text)

    def _offer(self, client: Client, topic: Topic, subs: dict, text: str) -> None:
        throttle = min(s.throttle_ms for s in subs.values()) / 1000.0
        slot = topic.name if topic.slot else None
        if throttle <= 0:
            self._put(client, text, slot)
            return
        st = client.throttle.setdefault(topic.name, _Throttle())
        qlen = max(1, min(s.queue_length for s in subs.values()))
        if st.pending.maxlen != qlen:
            st.pending = collections.deque(st.pending, maxlen=qlen)
        now = time.monotonic()
        if now - st.last >= throttle and st.timer is None:
            st.last = now
            self._put(client, text, slot)
            return
        st.pending.append(text)  # the newest waits for the window's end: never lost
        if st.timer is None and self.loop is not None:
            st.timer = self.loop.call_at(
                self.loop.time() + max(0.0, st.last + throttle - now),
                self._flush_throttle,
                client,
                topic,
            )

    def _flush_throttle(self, client: Client, topic: Topic) -> None:
        st = client.throttle.get(topic.name)
        if st is None:
            return
        st.timer = None
        st.last = time.monotonic()
        slot = topic.name if topic.slot else None
        while st.pending:
            self._put(client, st.pending.popleft(), slot)

    def _put(self, client: Client, text: str, slot: str | None) -> None:
        before = client.outbox.stats.dropped
        replaced = client.outbox.stats.replaced
        client.outbox.put(text, slot)
        if client.outbox.stats.replaced > replaced:
            self.counters["coalesced"] += 1  # a newer message of a latest-wins slot
        if client.outbox.stats.dropped > before:
            self.counters["dropped"] += client.outbox.stats.dropped - before
            if not client.warned_drop:
                client.warned_drop = True
                log.warning("client %d reads too slowly: dropping its oldest messages", client.id)

    # ---- receiving ----------------------------------------------------------------------

    def _error(self, client: Client, text: str, mid: Any = None) -> None:
        self.counters["bad_messages"] += 1
        client.error_count += 1
        now = time.monotonic()
        client.errors.append(now)
        while client.errors and now - client.errors[0] > 60.0:
            client.errors.popleft()
        log.debug("client %d: %s", client.id, text)
        if client.wants_status("error"):
            status = {"op": "status", "level": "error", "msg": text}
            if mid is not None:
                status["id"] = mid
            self._put(client, dumps(status), None)
        if len(client.errors) > self.limits.errors_per_minute and self.loop is not None:
            self.counters["closed_for_errors"] += 1
            self.loop.create_task(
                client.ws.close(1008, f"more than {self.limits.errors_per_minute} bad messages")
            )

    def receive(self, client: Client, data: str | bytes) -> None:
        """Handle one WebSocket message (text or binary JSON)."""
        self.counters["received"] += 1
        try:
            op = parse(loads(data))
        except WireError as exc:
            self._error(client, str(exc))
            return
        try:
            self._dispatch(client, op)
        except WireError as exc:
            self._error(client, str(exc), op.id)
        except Exception as exc:  # a bug handling one message never drops the client
            self.counters["internal_errors"] += 1
            log.exception("client %d: %s failed", client.id, op.op)
            self._error(client, f"{op.op}: internal error: {type(exc).__name__}", op.id)

    def _dispatch(self, client: Client, op: Op) -> None:
        f = op.fields
        if op.op == "fragment":
            whole = client.fragments.add(op)
            if whole is not None:
                self.receive(client, whole)
        elif op.op == "publish":
            self._client_publish(client, f["topic"], f["msg"], bool(f.get("latch", False)))
        elif op.op == "subscribe":
            self._subscribe(client, op)
        elif op.op == "unsubscribe":
            subs = client.subs.get(f["topic"], {})
            if op.id is None:
                subs.clear()
            else:
                subs.pop(op.id, None)
            if not subs:
                client.subs.pop(f["topic"], None)
                self._drop_throttle(client, f["topic"])
        elif op.op == "advertise":
            self._advertise(client, f["topic"], f["type"], bool(f.get("latch", False)))
        elif op.op == "unadvertise":
            self._unadvertise(client, f["topic"])
        elif op.op == "call_service":
            assert self.loop is not None
            self.loop.create_task(self._call(client, op))
        elif op.op == "set_level":
            client.level = f["level"]
        elif op.op in ("advertise_service", "unadvertise_service"):
            raise WireError(f"{op.op}: clients cannot provide services on this server")
        elif op.op == "service_response":
            raise WireError("service_response: no call of this server is waiting for it")

    def _subscribe(self, client: Client, op: Op) -> None:
        f = op.fields
        name = f["topic"]
        topic = self.topics.get(name)
        want = f.get("type")
        if topic is not None and want and want != topic.type:
            raise WireError(f"subscribe: {name} has type {topic.type}, not {want}")
        self._room(client, name, "subscribe")
        if topic is None:
            if not want:
                raise WireError(f"subscribe: unknown topic {name} and no type given")
            topic = self.topics[name] = Topic(name, want, slot=want in STREAM_TYPES)
        throttle = float(f.get("throttle_rate", 0) or 0)
        qlen = int(f.get("queue_length", 0) or 0)
        if throttle < 0 or throttle > 3_600_000 or qlen < 0 or qlen > 10_000:
            raise WireError("subscribe: throttle_rate or queue_length out of range")
        key = op.id if op.id is not None else ("anon", name)
        subs = client.subs.setdefault(name, {})
        if key not in subs and len(subs) >= 64:
            raise WireError(f"subscribe: more than 64 subscriptions to {name}")
        subs[key] = Subscription(throttle, qlen)
        if f.get("compression") not in (None, "none"):
            log.info(
                "client %d asked for %s compression: sending JSON", client.id, f["compression"]
            )
        if topic.last is not None:  # latched: the newest message at once
            st = client.throttle.setdefault(name, _Throttle())
            st.last = time.monotonic()
            self._put(client, topic.last, name if topic.slot else None)

    def _room(self, client: Client, name: str, op: str) -> None:
        """Bounds on what one client can make the server hold (topics, subscriptions)."""
        if name in client.subs or name in client.adverts:
            return
        if len(set(client.subs) | client.adverts) >= self.limits.topics_per_client:
            raise WireError(f"{op}: more than {self.limits.topics_per_client} topics")
        if name not in self.topics and len(self.topics) >= self.limits.max_topics:
            raise WireError(f"{op}: the server holds {self.limits.max_topics} topics already")

    def _advertise(self, client: Client, name: str, type_: str, latch: bool) -> None:
        self._room(client, name, "advertise")
        topic = self.topics.get(name)
        if topic is None:
            topic = self.topics[name] = Topic(
                name, type_, latched=latch, slot=type_ in STREAM_TYPES
            )
        elif topic.type != type_:
            raise WireError(f"advertise: {name} has type {topic.type}, not {type_}")
        elif topic.server_owned:
            raise WireError(f"advertise: {name} is published by the server")
        topic.publishers.add(client.id)
        topic.latched = topic.latched or latch
        client.adverts.add(name)

    def _unadvertise(self, client: Client, name: str) -> None:
        client.adverts.discard(name)
        topic = self.topics.get(name)
        if topic is not None:
            topic.publishers.discard(client.id)
            self._forget_if_unused(topic)

    def _forget_if_unused(self, topic: Topic) -> None:
        if topic.server_owned or topic.inbound is not None or topic.publishers:
            return
        if not any(topic.name in c.subs for c in self.clients.values()):
            self.topics.pop(topic.name, None)

    def _client_publish(self, client: Client, name: str, msg: dict, latch: bool) -> None:
        topic = self.topics.get(name)
        if topic is None or (topic.inbound is None and name not in client.adverts):
            if topic is not None and topic.server_owned:
                raise WireError(f"publish: {name} is published by the server")
            raise WireError(f"publish: advertise {name} first")
        self.counters["client_published"] += 1
        if topic.inbound is not None:
            topic.inbound(client, msg)
            return
        text = dumps({"op": "publish", "topic": name, "msg": msg})
        if latch:
            topic.last = text
        self._fan_out(topic, text)

    async def _call(self, client: Client, op: Op) -> None:
        name = op.fields["service"]
        reply: dict[str, Any] = {"op": "service_response", "service": name}
        if op.id is not None:
            reply["id"] = op.id
        self.counters["calls"] += 1
        client.calls += 1
        try:
            if client.calls > self.limits.calls_per_client:
                raise ServiceError(
                    f"{name}: more than {self.limits.calls_per_client} calls in progress"
                )
            service = self.services.get(name)
            if service is None:
                raise ServiceError(f"unknown service {name}")
            args = op.fields.get("args", {})
            if isinstance(args, list):
                if len(args) > len(service.request_fields):
                    raise ServiceError(
                        f"{name}: {len(args)} arguments, expected at most "
                        f"{len(service.request_fields)}"
                    )
                args = dict(zip(service.request_fields, args, strict=False))
            timeout = service.timeout or self.limits.service_timeout
            asked = op.fields.get("timeout")
            if asked is not None and asked > 0:
                timeout = min(timeout, float(asked))
            if service.blocking:
                work: Awaitable[Any] = asyncio.to_thread(service.handler, client, args)
            else:
                result = service.handler(client, args)
                work = result if asyncio.iscoroutine(result) else _done(result)
            values = await asyncio.wait_for(work, timeout)
            finite(values, "values")
            reply.update(values=values, result=True)
        except TimeoutError:
            self.counters["service_errors"] += 1
            reply.update(values=f"{name}: no answer within {timeout:g} s", result=False)
        except (ServiceError, WireError) as exc:
            self.counters["service_errors"] += 1
            reply.update(values=str(exc), result=False)
        except Exception as exc:  # a handler's bug is one failed call, never a dead client
            self.counters["service_errors"] += 1
            log.exception("service %s failed", name)
            reply.update(
                values=f"{name}: internal error: {type(exc).__name__}: {exc}", result=False
            )
        finally:
            client.calls -= 1
        if op.id is None:
            reply.pop("id", None)
        try:
            text = dumps(reply)
        except ValueError:
            text = dumps(
                {**reply, "values": f"{name}: a non-finite value in the answer", "result": False}
            )
        self._put(client, text, None)

    # ---- rosapi ---------------------------------------------------------------------------

    def _add_rosapi(self) -> None:
        def topics(_c, _a):
            names = sorted(self.topics)
            return {"topics": names, "types": [self.topics[n].type for n in names]}

        def topic_type(_c, a):
            t = self.topics.get(str(a.get("topic", "")))
            return {"type": t.type if t else ""}

        def topics_for_type(_c, a):
            want = str(a.get("type", ""))
            return {"topics": sorted(n for n, t in self.topics.items() if t.type == want)}

        def services(_c, _a):
            return {"services": sorted(self.services)}

        def service_type(_c, a):
            s = self.services.get(str(a.get("service", "")))
            return {"type": s.type if s else ""}

        def get_time(_c, _a):
            now = time.time()
            secs, nsecs = int(now), int((now % 1) * 1e9)
            return {"time": {"secs": secs, "nsecs": nsecs, "sec": secs, "nanosec": nsecs}}

        def nodes(_c, _a):
            return {"nodes": [self.node_name]}

        for name, fn, type_, req in (
            ("topics", topics, "rosapi/Topics", ()),
            ("topic_type", topic_type, "rosapi/TopicType", ("topic",)),
            ("topics_for_type", topics_for_type, "rosapi/TopicsForType", ("type",)),
            ("services", services, "rosapi/Services", ()),
            ("service_type", service_type, "rosapi/ServiceType", ("service",)),
            ("get_time", get_time, "rosapi/GetTime", ()),
            ("nodes", nodes, "rosapi/Nodes", ()),
        ):
            self.service(f"/rosapi/{name}", type_, fn, request_fields=req)

    # ---- connections --------------------------------------------------------------------

    async def _handle(self, ws: Any) -> None:
        from websockets.exceptions import ConnectionClosed

        client = Client(next(self._ids), ws, self.limits)
        self.clients[client.id] = client
        self.counters["connections"] += 1
        writer = asyncio.create_task(self._writer(client))
        try:
            async for data in ws:
                self.receive(client, data)
        except ConnectionClosed:
            pass
        finally:
            self._disconnect(client)
            writer.cancel()

    async def _writer(self, client: Client) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            while (text := await client.outbox.get()) is not None:
                await client.ws.send(text)
                self.counters["sent"] += 1
        except (ConnectionClosed, asyncio.CancelledError):
            pass

    def _disconnect(self, client: Client) -> None:
        self.clients.pop(client.id, None)
        client.outbox.close()
        for st in client.throttle.values():
            if st.timer is not None:
                st.timer.cancel()
        for name in list(client.adverts):
            self._unadvertise(client, name)
        for name in list(client.subs):
            topic = self.topics.get(name)
            client.subs.pop(name)
            if topic is not None:
                self._forget_if_unused(topic)

    def _drop_throttle(self, client: Client, name: str) -> None:
        st = client.throttle.pop(name, None)
        if st is not None and st.timer is not None:
            st.timer.cancel()

    def _process_request(self, connection: Any, request: Any) -> Any:
        """Token, Origin, client count; plain HTTP GETs get the page's static files."""
        url = urlsplit(request.path)
        headers = request.headers
        upgrade = headers.get("Upgrade", "").lower() == "websocket"
        if not upgrade:  # the page's own files: public, no data, no token needed
            return self._static(connection, url.path)
        if self.token is not None:
            given = parse_qs(url.query).get("token", [None])[0]
            auth = headers.get("Authorization", "")
            if given != self.token and auth != f"Bearer {self.token}":
                self.counters["refused_token"] += 1
                return connection.respond(401, "a valid ?token= is required\n")
        origin = headers.get("Origin")
        if origin is not None and not self._origin_ok(origin, headers.get("Host", "")):
            self.counters["refused_origin"] += 1
            return connection.respond(403, f"origin {origin[:80]} is not allowed\n")
        if len(self.clients) >= self.limits.max_clients:
            self.counters["refused_full"] += 1
            return connection.respond(503, f"at most {self.limits.max_clients} clients\n")
        return None

    def _origin_ok(self, origin: str, host: str) -> bool:
        origin = origin.rstrip("/")
        if origin in self.origins or "*" in self.origins:
            return True
        parts = urlsplit(origin)
        return parts.scheme in ("http", "https") and parts.netloc == host

    def _static(self, connection: Any, path: str) -> Any:
        from websockets.datastructures import Headers
        from websockets.http11 import Response

        if self.web_root is None:
            return connection.respond(404, "no page is served here\n")
        rel = "index.html" if path in ("", "/") else path.lstrip("/")
        root = self.web_root.resolve()
        target = (root / rel).resolve()
        if root not in target.parents or not target.is_file():
            return connection.respond(404, "not found\n")
        body = target.read_bytes()
        ctype = mimetypes.guess_type(target.name)[0] or "application/octet-stream"
        if ctype.startswith("text/") or ctype.endswith("javascript"):
            ctype += "; charset=utf-8"
        return Response(
            200,
            "OK",
            Headers(
                [
                    ("Content-Type", ctype),
                    ("Content-Length", str(len(body))),
                    ("Cache-Control", "no-store"),
                    ("X-Content-Type-Options", "nosniff"),
                ]
            ),
            body,
        )

    async def start(self, host: str = "127.0.0.1", port: int = 9090) -> int:
        """Listen; returns the bound port (``port`` 0 picks a free one)."""
        from websockets.asyncio.server import serve

        self.loop = asyncio.get_running_loop()
        self._server = await serve(
            self._handle,
            host,
            port,
            process_request=self._process_request,
            max_size=self.limits.max_message,
            max_queue=64,
            write_limit=64 * 1024,
            ping_interval=self.limits.ping_interval,
            ping_timeout=self.limits.ping_interval,
            compression=None,
            close_timeout=1.0,  # a peer that vanished without closing holds nothing
            server_header="tamp-serve",
        )
        self.port = self._server.sockets[0].getsockname()[1]
        return self.port

    async def stop(self) -> None:
        """Close every connection (1001; a peer that does not answer within a second is
        cut) and stop listening."""
        if self._server is None:
            return
        self._server.close(close_connections=False)
        await asyncio.gather(*(self._close(c) for c in list(self.clients.values())))
        try:
            await asyncio.wait_for(self._server.wait_closed(), 5.0)
        except TimeoutError:
            log.warning("some connections did not close")
        self._server = None

    @staticmethod
    async def _close(client: Client) -> None:
        try:
            await asyncio.wait_for(client.ws.close(1001, "server stopping"), 1.0)
        except Exception:  # noqa: BLE001 - a vanished peer: cut the connection
            client.ws.transport.abort()


async def _done(value: Any) -> Any:
    return value


class ServerThread:
    """A server on its own event loop in a daemon thread (tests, benchmarks, notebooks)."""

    def __init__(self, server: RosbridgeServer, host: str = "127.0.0.1", port: int = 0):
        self.server = server
        self.host = host
        self.port = port
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(
            target=self._loop.run_forever, daemon=True, name="tamp-serve"
        )

    def start(self) -> int:
        self._thread.start()
        fut = asyncio.run_coroutine_threadsafe(self.server.start(self.host, self.port), self._loop)
        self.port = fut.result(timeout=10)
        return self.port

    def call(self, fn: Callable[[], Any]) -> Any:
        """Run ``fn`` on the server's loop and return its result."""

        async def run():
            return fn()

        return asyncio.run_coroutine_threadsafe(run(), self._loop).result(timeout=10)

    def stop(self) -> None:
        asyncio.run_coroutine_threadsafe(self.server.stop(), self._loop).result(timeout=30)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=10)
