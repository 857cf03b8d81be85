"""The rosbridge v2 server against raw WebSocket peers: ROS#-style frames and hostile input."""

from __future__ import annotations

import json
import socket
import urllib.error
import urllib.request

import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from tamp.serve.outbox import Outbox
from tamp.serve.wire import Fragments, Op, WireError, canonical_type, dumps, loads, parse
from tests.serve.conftest import Served, wait_for


def recv_json(ws, timeout: float = 5.0) -> dict:
    return json.loads(ws.recv(timeout=timeout))


def recv_until(ws, predicate, timeout: float = 5.0) -> dict:
    while True:
        msg = recv_json(ws, timeout)
        if predicate(msg):
            return msg


def call(ws, service: str, args=None, mid="c1", **extra) -> dict:
    ws.send(
        json.dumps(
            {
                "op": "call_service",
                "id": mid,
                "service": service,
                **({"args": args} if args is not None else {}),
                **extra,
            }
        )
    )
    return recv_until(ws, lambda m: m.get("op") == "service_response")


# ---- the wire format, without a socket -------------------------------------------------------


def test_loads_refuses_nan_and_infinity_and_bad_utf8():
    for text in ('{"x": NaN}', '{"x": Infinity}', '{"x": -Infinity}', b'{"x": "\xff"}', "{"):
        with pytest.raises(WireError):
            loads(text)
    assert loads(b'{"op": "publish"}') == {"op": "publish"}


def test_dumps_never_sends_nan():
    with pytest.raises(ValueError):
        dumps({"x": float("nan")})
    assert dumps({"s": "é"}) == '{"s":"\\u00e9"}'  # ASCII, as ROS# decodes


def test_parse_checks_ops_ids_and_fields():
    assert parse({"op": "subscribe", "topic": "/t", "id": None}).id is None
    assert parse({"op": "subscribe", "topic": "/t", "id": 7}).id == 7
    op = parse({"op": "advertise", "topic": "/t", "type": "geometry_msgs/msg/PoseStamped"})
    assert op.fields["type"] == "geometry_msgs/PoseStamped"
    assert canonical_type("tamp_msgs/srv/Plan") == "tamp_msgs/Plan"
    for bad in (
        [],
        {"op": 3},
        {"op": "explode"},
        {"op": "publish", "topic": "/t"},
        {"op": "publish", "topic": "/t", "msg": []},
        {"op": "subscribe", "topic": "/t", "id": 1.5},
        {"op": "subscribe", "topic": "/t", "id": True},
        {"op": "subscribe", "topic": "/t", "throttle_rate": "fast"},
        {"op": "subscribe", "topic": ""},
        {"op": "set_level", "level": "loud"},
    ):
        with pytest.raises(WireError):
            parse(bad)


def test_fragments_reassemble_in_any_order_under_limits():
    f = Fragments(max_bytes=10, max_parts=3)

    def piece(n, d, total=3):
        return Op("fragment", "m", {"num": n, "total": total, "data": d})

    assert f.add(piece(2, "c")) is None
    assert f.add(piece(0, "a")) is None
    assert f.add(piece(1, "b")) == "abc"
    with pytest.raises(WireError):
        f.add(piece(0, "a", total=4))  # more pieces than allowed
    with pytest.raises(WireError):
        f.add(piece(3, "a"))  # num out of range
    f.add(piece(0, "x" * 6))
    with pytest.raises(WireError):
        f.add(piece(1, "y" * 6))  # larger than max_bytes
    g = Fragments(max_age=1.0)
    g.add(piece(0, "a"), now=0.0)
    assert len(g) == 1
    g.add(Op("fragment", "n", {"num": 0, "total": 2, "data": "z"}), now=5.0)
    assert len(g) == 1  # the stale message was forgotten


def test_outbox_is_bounded_and_slots_keep_only_the_latest():
    import asyncio

    box = Outbox(max_messages=3, max_bytes=1000)
    for i in range(5):
        box.put(f"event{i}")
    assert len(box) == 3 and box.stats.dropped == 2
    box.put("pose1", slot="/pose")
    box.put("pose2", slot="/pose")
    assert box.stats.replaced == 1
    got = asyncio.run(_drain(box))
    assert got[-1] == "pose2" and "pose1" not in got and "event0" not in got


async def _drain(box):
    out = []
    while len(box):
        out.append(await box.get())
    return out


# ---- over the socket ----------------------------------------------------------------------


def test_bad_json_then_a_valid_call_still_works(served):
    with connect(served.url) as ws:
        ws.send("{not json")
        ws.send('{"op": "no_such_op"}')
        ws.send('{"op": "publish"}')
        ws.send('{"x": NaN}')
        reply = call(ws, "/rosapi/nodes")
        assert reply["result"] is True and reply["id"] == "c1"
        assert reply["values"] == {"nodes": ["/tamp_serve"]}
    assert served.counter("bad_messages") == 4


def test_ids_are_echoed_as_sent_and_null_means_absent(served):
    with connect(served.url) as ws:
        assert call(ws, "/rosapi/services", mid=42)["id"] == 42
        assert call(ws, "/rosapi/services", mid="call_service:/rosapi/services:1")["id"] == (
            "call_service:/rosapi/services:1"
        )
        reply = call(ws, "/rosapi/services", mid=None)
        assert "id" not in reply and reply["result"] is True
        assert "/tamp/plan" in reply["values"]["services"]


def test_unknown_service_and_wrong_args_get_a_false_result(served):
    with connect(served.url) as ws:
        reply = call(ws, "/tamp/nope")
        assert reply == {
            "op": "service_response",
            "service": "/tamp/nope",
            "id": "c1",
            "values": "unknown service /tamp/nope",
            "result": False,
        }
        reply = call(ws, "/rosapi/topic_type", args=["/tamp/state"])  # args as a list
        assert reply["values"] == {"type": "std_msgs/String"}
        reply = call(ws, "/rosapi/topic_type", args=["/a", "/b"])
        assert reply["result"] is False and "arguments" in reply["values"]


def test_get_time_answers_ros1_and_ros2_spellings(served):
    with connect(served.url) as ws:
        t = call(ws, "/rosapi/get_time")["values"]["time"]
        assert t["secs"] == t["sec"] > 0 and t["nsecs"] == t["nanosec"]


def test_binary_message_in_1024_byte_continuation_frames(served):
    """ROS#'s WebSocketNetProtocol: binary frames, 1,024-byte pieces of one message."""
    payload = json.dumps(
        {"op": "call_service", "id": None, "service": "/rosapi/topics", "args": {"pad": "x" * 5000}}
    ).encode("ascii")
    pieces = [payload[i : i + 1024] for i in range(0, len(payload), 1024)]
    assert len(pieces) > 4
    with connect(served.url) as ws:
        ws.send(iter(pieces))
        reply = recv_until(ws, lambda m: m.get("op") == "service_response")
        assert reply["result"] is True and "/tamp/state" in reply["values"]["topics"]


def test_fragment_op_reversed_order(served):
    text = json.dumps({"op": "call_service", "id": "f1", "service": "/rosapi/nodes"})
    parts = [text[i : i + 10] for i in range(0, len(text), 10)]
    with connect(served.url) as ws:
        for n in reversed(range(len(parts))):
            ws.send(
                json.dumps(
                    {"op": "fragment", "id": "big", "num": n, "total": len(parts), "data": parts[n]}
                )
            )
        reply = recv_until(ws, lambda m: m.get("op") == "service_response")
        assert reply["id"] == "f1" and reply["result"] is True


def test_oversize_message_closes_1009(served):
    with connect(served.url, max_size=None) as ws:
        ws.send("x" * ((1 << 20) + 10))
        with pytest.raises(ConnectionClosed) as info:
            ws.recv(timeout=5)
        assert info.value.rcvd.code == 1009


def test_status_only_for_clients_that_asked(served):
    with connect(served.url) as ws:
        ws.send('{"op": "bogus", "id": "b1"}')
        assert call(ws, "/rosapi/nodes")["op"] == "service_response"  # no status before it
        ws.send('{"op": "set_level", "level": "error"}')
        ws.send('{"op": "bogus", "id": "b2"}')
        status = recv_json(ws)
        assert status["op"] == "status" and status["level"] == "error"
        assert "unknown op" in status["msg"]


def test_too_many_bad_messages_close_1008():
    s = Served()
    try:
        with connect(s.url) as ws:
            for _ in range(s.server.limits.errors_per_minute + 1):
                ws.send("{")
            with pytest.raises(ConnectionClosed) as info:
                while True:
                    ws.recv(timeout=5)
            assert info.value.rcvd.code == 1008
    finally:
        s.stop()


def test_latched_state_reaches_a_late_subscriber_with_ros2_type_name(served):
    with connect(served.url) as ws:
        ws.send(
            json.dumps(
                {
                    "op": "subscribe",
                    "id": "s1",
                    "topic": "/tamp/state",
                    "type": "std_msgs/msg/String",
                }
            )
        )
        msg = recv_json(ws)
        assert msg["topic"] == "/tamp/state"
        assert json.loads(msg["msg"]["data"])["phase"] == "idle"
        ws.send(
            json.dumps({"op": "subscribe", "topic": "/tamp/state", "type": "sensor_msgs/Image"})
        )
        ws.send(json.dumps({"op": "publish", "topic": "/tamp/state", "msg": {"data": "{}"}}))
    assert served.counter("bad_messages") == 2  # wrong type; a server topic published by a client


def test_pub_sub_between_clients_with_throttle_keeps_the_last_message(served):
    with connect(served.url) as pub, connect(served.url) as sub:
        sub.send(
            json.dumps(
                {
                    "op": "subscribe",
                    "id": "p",
                    "topic": "/mr/hand",
                    "type": "geometry_msgs/PoseStamped",
                    "throttle_rate": 200,
                    "queue_length": 1,
                }
            )
        )
        pub.send(
            json.dumps(
                {"op": "advertise", "topic": "/mr/hand", "type": "geometry_msgs/msg/PoseStamped"}
            )
        )
        wait_for(
            lambda: served.thread.call(lambda: "/mr/hand" in served.server.topics), what="advert"
        )
        for i in range(20):
            pub.send(
                json.dumps(
                    {"op": "publish", "topic": "/mr/hand", "msg": {"pose": {"position": {"x": i}}}}
                )
            )
        got = []
        while not got or got[-1] != 19:
            got.append(recv_json(sub)["msg"]["pose"]["position"]["x"])
        assert got[0] == 0 and got[-1] == 19 and len(got) < 20  # throttled, last kept


def test_a_client_that_never_reads_does_not_stall_another(served):
    """One subscriber never reads a 50 Hz-style stream of large poses; another subscriber of
    the same stream still gets every message up to the last, and the stalled client's queue
    stays bounded (its oldest messages are dropped and counted)."""
    big = "y" * 20_000
    with (
        connect(served.url) as pub,
        connect(served.url) as live,
        connect(served.url, close_timeout=0.2) as stuck,
    ):
        for ws, sid in ((live, "live"), (stuck, "stuck")):
            ws.send(
                json.dumps(
                    {"op": "subscribe", "id": sid, "topic": "/mr/hand", "type": "std_msgs/String"}
                )
            )
        pub.send(json.dumps({"op": "advertise", "topic": "/mr/hand", "type": "std_msgs/String"}))
        wait_for(
            lambda: served.thread.call(
                lambda: sum("/mr/hand" in c.subs for c in served.server.clients.values()) == 2
            ),
            what="subscriptions",
        )
        n = 600
        for i in range(n):
            pub.send(
                json.dumps({"op": "publish", "topic": "/mr/hand", "msg": {"data": f"{i}:{big}"}})
            )
        last = -1
        while last != n - 1:
            last = int(recv_json(live)["msg"]["data"].split(":")[0])
        server = served.server
        stuck_client = served.thread.call(
            lambda: max(server.clients.values(), key=lambda c: c.outbox.stats.dropped)
        )
        assert stuck_client.outbox.stats.dropped > 0
        assert len(stuck_client.outbox) <= server.limits.queue_messages
        assert served.counter("dropped") > 0


def test_killed_socket_is_cleaned_up_and_a_reconnect_gets_the_latched_state(served):
    with connect(served.url, close_timeout=0.2) as ws:
        ws.send(json.dumps({"op": "subscribe", "id": "s", "topic": "/tamp/state"}))
        recv_json(ws)
        ws.socket.shutdown(socket.SHUT_RDWR)  # the peer vanishes without a close frame
    wait_for(lambda: served.thread.call(lambda: len(served.server.clients) == 0), what="cleanup")
    with connect(served.url) as again:
        again.send(json.dumps({"op": "subscribe", "id": "s", "topic": "/tamp/state"}))
        assert json.loads(recv_json(again)["msg"]["data"])["phase"] == "idle"


def test_token_origin_and_client_limit():
    s = Served(token="secret-token", max_clients=2, origin=["https://mr.example"])
    try:
        with pytest.raises(InvalidStatus) as info:
            connect(s.url)
        assert info.value.response.status_code == 401
        url = s.url + "?token=secret-token"
        with pytest.raises(InvalidStatus) as info:
            connect(url, origin="https://evil.example")
        assert info.value.response.status_code == 403
        with connect(url, origin="https://mr.example"), connect(url):
            with pytest.raises(InvalidStatus) as info:
                connect(url)
            assert info.value.response.status_code == 503
        with connect(url, origin=f"http://127.0.0.1:{s.port}") as ws:  # the page's own origin
            assert call(ws, "/rosapi/nodes")["result"] is True
    finally:
        s.stop()


def test_page_is_served_and_nothing_outside_it(served):
    base = f"http://127.0.0.1:{served.port}"
    with urllib.request.urlopen(base + "/") as r:
        assert r.status == 200 and b"roslib" in r.read()
    for path in ("/../server.py", "/%2e%2e/server.py", "/nope.js"):
        with pytest.raises(urllib.error.HTTPError) as info:
            urllib.request.urlopen(base + path)
        assert info.value.code == 404


def test_nonfinite_values_are_never_sent(served):
    served.thread.call(lambda: served.server.publish("/tamp/events", {"data": float("nan")}))
    assert served.counter("refused_nonfinite_out") == 1


def test_a_client_cannot_make_the_server_hold_unbounded_state(served):
    limit = served.server.limits.topics_per_client
    with connect(served.url) as ws:
        for i in range(limit + 10):
            ws.send(
                json.dumps({"op": "advertise", "topic": f"/spam/{i}", "type": "std_msgs/String"})
            )
        assert call(ws, "/rosapi/nodes")["result"] is True  # still served
    assert served.counter("bad_messages") == 10
    wait_for(
        lambda: served.thread.call(
            lambda: not any(t.startswith("/spam/") for t in served.server.topics)
        ),
        what="forgotten on disconnect",
    )


def test_calls_in_progress_per_client_are_bounded():
    import threading

    from tamp.serve import Limits, RosbridgeServer, ServerThread

    gate = threading.Event()
    server = RosbridgeServer(limits=Limits(calls_per_client=3))
    server.service(
        "/slow", "std_srvs/Trigger", lambda c, a: gate.wait(10) and {"success": True}, blocking=True
    )
    thread = ServerThread(server)
    port = thread.start()
    try:
        with connect(f"ws://127.0.0.1:{port}/") as ws:
            for i in range(5):
                ws.send(json.dumps({"op": "call_service", "id": i, "service": "/slow"}))
            refused = [recv_json(ws) for _ in range(2)]
            assert all(r["result"] is False and "in progress" in r["values"] for r in refused)
            gate.set()
            done = [recv_json(ws) for _ in range(3)]
            assert sorted(r["id"] for r in done) == [0, 1, 2] and all(r["result"] for r in done)
    finally:
        gate.set()
        thread.stop()
