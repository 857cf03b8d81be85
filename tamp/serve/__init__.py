"""A live mixed-reality link: ``tamp serve`` speaks the rosbridge v2 protocol.

SMP-MRO (Nakamura & Sekiyama, IEEE Access) demonstrates tasks in mixed reality: a HoloLens
2 app built on ROS# talks to the robot side through rosbridge. This package is that robot
side without ROS: `RosbridgeServer` (the protocol, `tamp.serve.server`), `TampApp` (the
demonstration → plan → execution flow, `tamp.serve.app`) and the browser demonstration page
(``web/``). Message definitions for ROS# code generation are in ``msg/``.
"""

from tamp.serve.app import Pipeline, RunCancelled, RunChannel, TampApp
from tamp.serve.server import Limits, RosbridgeServer, ServerThread

__all__ = [
    "Limits",
    "Pipeline",
    "RosbridgeServer",
    "RunCancelled",
    "RunChannel",
    "ServerThread",
    "TampApp",
]
