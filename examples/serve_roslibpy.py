"""Demonstrate SMP-MRO Case 2 to a running ``tamp serve``, plan and execute, with roslibpy.

    tamp serve                      # in one terminal (ws://127.0.0.1:9090/)
    python examples/serve_roslibpy.py [--host H] [--port P] [--token T]

This is what a ROS# app on a HoloLens does, message for message (docs/serve.md): call
``/tamp/demo/begin`` with the robot, the objects and the area radius, publish one
``tamp_msgs/DemoStep`` on ``/tamp/demo/step`` per released grab, call ``/tamp/plan`` and
``/tamp/execute``, and follow ``/tamp/state`` and ``/tamp/events``. Positions are in the MR
frame ``mr``: ROS convention, as ROS#'s ``Unity2Ros`` gives them ((x, y, z)_Unity →
(z, −x, y)). Needs roslibpy (``pip install roslibpy``).
"""

from __future__ import annotations

import argparse
import json
import sys
import threading

import roslibpy

# Case 2 of SMP-MRO (§V-C), as a person shows it in the headset (Unity coordinates, y up).
ROBOT = (0.4, 0.0, -1.2)
OBJECTS = {"O0": (0.4, 0.0, 1.3), "O1": (-0.6, 0.0, -0.2)}
STEPS = [
    ("O0", (0.9, 0.0, 1.3)),  # O0 to free space
    ("O1", (0.7, 0.0, 1.8)),  # O1 to free space
    ("O0", (-0.6, 0.0, -0.2)),  # O0 to where O1 was
    ("O1", (0.4, 0.0, 1.3)),  # O1 to where O0 was
]


def pose(p: tuple[float, float, float]) -> dict:
    """A geometry_msgs/Pose in the ``mr`` frame from a Unity point (ROS#'s Unity2Ros)."""
    x, y, z = p
    return {
        "position": {"x": z, "y": -x, "z": y},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=9090)
    ap.add_argument("--token", help="the token given to tamp serve --token")
    args = ap.parse_args()

    headers = {"Authorization": f"Bearer {args.token}"} if args.token else None
    ros = roslibpy.Ros(args.host, args.port, headers=headers, transport="asyncio")
    ros.run(timeout=5)

    def call(name: str, type_: str, request: dict | None = None) -> dict:
        service = roslibpy.Service(ros, name, type_)
        return service.call(roslibpy.ServiceRequest(request or {}), timeout=60)

    finished = threading.Event()

    def on_state(msg: dict) -> None:
        state = json.loads(msg["data"])
        print(f"state: {state['phase']}")
        if state["phase"] in ("done", "failed", "cancelled"):
            finished.set()

    def on_event(msg: dict) -> None:
        e = json.loads(msg["data"])
        if e["kind"] in ("start", "recovery", "appear", "step_rejected"):
            print(f"  {e['kind']}: {e.get('what') or e.get('condition') or e.get('why')}")

    roslibpy.Topic(ros, "/tamp/events", "std_msgs/String").subscribe(on_event)

    reply = call(
        "/tamp/demo/begin",
        "tamp_msgs/BeginDemo",
        {
            "header": {"frame_id": "mr"},
            "name": "case2",
            "robot": pose(ROBOT),
            "objects": [{"id": k, "pose": pose(p)} for k, p in OBJECTS.items()],
            "area_radius": 0.15,
            "start": [0.3, 0.9, 0.0],  # robot frame x, y, yaw
        },
    )
    print(reply["message"])
    steps = roslibpy.Topic(ros, "/tamp/demo/step", "tamp_msgs/DemoStep")
    steps.advertise()
    for obj, to in STEPS:
        steps.publish(
            roslibpy.Message({"header": {"frame_id": "mr"}, "object_id": obj, "pose": pose(to)})
        )

    plan = call("/tamp/plan", "tamp_msgs/Plan", {"cost_model": "distance", "constraints": []})
    print(plan["message"])
    if not plan["success"]:
        ros.close()
        ros.terminate()
        return 1
    roslibpy.Topic(ros, "/tamp/state", "std_msgs/String").subscribe(on_state)
    print(call("/tamp/execute", "std_srvs/Trigger")["message"])
    finished.wait(timeout=600)
    print(call("/tamp/demo/export", "std_srvs/Trigger")["message"])
    ros.close()
    ros.terminate()
    return 0


if __name__ == "__main__":
    sys.exit(main())
