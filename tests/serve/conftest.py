"""A `tamp serve` server on a free loopback port, in a thread with its own event loop."""

from __future__ import annotations

import argparse
import json
import time

import pytest

from tamp.commands.serve import make_app
from tamp.serve import ServerThread


def options(**overrides) -> argparse.Namespace:
    """`tamp serve`'s defaults (port 0: any free one), with ``overrides``."""
    base = dict(
        host="127.0.0.1",
        port=0,
        token=None,
        origin=[],
        sim=False,
        rate=0.0,
        demo=None,
        max_clients=8,
        max_message=1 << 20,
        plan_timeout=60.0,
    )
    base.update(overrides)
    return argparse.Namespace(**base)


class Served:
    """A running server: its thread, the server object, the app and the URL."""

    def __init__(self, **overrides):
        self.server, self.app = make_app(options(**overrides))
        self.thread = ServerThread(self.server)
        self.port = self.thread.start()
        self.url = f"ws://127.0.0.1:{self.port}/"

    def counter(self, name: str) -> int:
        return self.thread.call(lambda: self.server.counters[name])

    def stop(self) -> None:
        self.thread.stop()


@pytest.fixture
def served():
    s = Served()
    yield s
    s.stop()


def wait_for(predicate, timeout: float = 5.0, what: str = "condition"):
    """Poll ``predicate`` until it returns a truthy value (a bounded wait, not a timing)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}")


def unity_to_mr(p):
    """``Unity2Ros`` as ROS# applies it: (x, y, z) → (z, −x, y)."""
    x, y, z = p
    return {"x": z, "y": -x, "z": y}


def case_begin(data: dict) -> tuple[dict, list[dict]]:
    """A demonstration file's mapping as an MR app sends it: the /tamp/demo/begin request
    and the /tamp/demo/step messages, positions in the ``mr`` frame."""

    def pose(p):
        return {"position": unity_to_mr(p), "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}

    begin = {
        "header": {"frame_id": "mr"},
        "name": data.get("name", ""),
        "robot": pose(data["frame"]["robot_position"]),
        "area_radius": data["area_radius"],
        "object_height": data.get("object_height", 0.0),
        "start": list(data.get("robot", {}).get("start", [])),
        "objects": [{"id": o["id"], "pose": pose(o["position"])} for o in data["objects"]],
        "free_areas": [
            {"id": a["id"], "pose": pose(a["position"])} for a in data.get("free_areas", [])
        ],
        "appear": list(data.get("appear", [])),
    }
    steps = [
        {"header": {"frame_id": "mr"}, "object_id": s["object"], "pose": pose(s["to"])}
        for s in data["steps"]
    ]
    return begin, steps


def data_of(msg: dict) -> dict:
    return json.loads(msg["data"])


def close_ros(ros, served: Served) -> None:
    """Close a roslibpy client cleanly: its close frame, the server's answer, then stop its
    loop (``terminate`` alone stops the loop with the socket still open, and the server
    waits for the close handshake before cutting it)."""
    before = served.thread.call(lambda: len(served.server.clients))
    if ros.is_connected:
        ros.close()
        try:
            wait_for(
                lambda: served.thread.call(lambda: len(served.server.clients)) < before,
                timeout=2.0,
                what="close",
            )
        except AssertionError:
            pass  # the server cuts it when it stops
    ros.terminate()
