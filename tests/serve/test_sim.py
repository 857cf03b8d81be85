"""`tamp serve --sim`: a live Case 3 runs in the Drake youBot cell with the tree's recovery,
picking and placing as `tamp plan --execute` does in the symbolic world, reported while it
runs; a cancel stops the simulation."""

from __future__ import annotations

import json
import threading

import pytest
import yaml

from tamp.commands.main import main as tamp_main
from tamp.scenarios import path as packaged
from tests.serve.conftest import Served, case_begin, close_ros, data_of, wait_for

roslibpy = pytest.importorskip("roslibpy")
pytest.importorskip("pydrake")


def _demonstrate(ros, s, name):
    data = yaml.safe_load(packaged(name).read_text())
    begin, steps = case_begin(data)
    assert _call(ros, "/tamp/demo/begin", begin)["success"]
    step = roslibpy.Topic(ros, "/tamp/demo/step", "tamp_msgs/DemoStep")
    for m in steps:
        step.publish(roslibpy.Message(m))
    wait_for(lambda: s.thread.call(lambda: len(s.app.session.mr_steps)) == len(steps), what="steps")
    assert _call(ros, "/tamp/plan")["success"]


def _call(ros, name, args=None):
    service = roslibpy.Service(ros, name, "x")
    return service.call(roslibpy.ServiceRequest(args or {}), timeout=60)


@pytest.mark.slow
def test_sim_runs_case3_like_the_symbolic_execution_and_reports_live(capsys):
    s = Served(sim=True)
    ros = roslibpy.Ros("127.0.0.1", s.port, transport="asyncio")
    ros.run(timeout=5)
    try:
        states, runs, events, joints = [], [], [], []
        roslibpy.Topic(ros, "/tamp/state", "std_msgs/String").subscribe(states.append)
        roslibpy.Topic(ros, "/tamp/execution", "std_msgs/String").subscribe(runs.append)
        roslibpy.Topic(ros, "/tamp/events", "std_msgs/String").subscribe(events.append)
        roslibpy.Topic(ros, "/joint_states", "sensor_msgs/JointState").subscribe(joints.append)
        _demonstrate(ros, s, "case3.yaml")
        assert "drake" in _call(ros, "/tamp/execute")["message"]
        # Reported while it runs: an action has started before the run has ended.
        wait_for(
            lambda: any(data_of(e)["kind"] == "start" for e in events),
            timeout=120,
            what="a live start event",
        )
        assert not runs
        wait_for(
            lambda: data_of(states[-1])["phase"] in ("done", "failed"),
            timeout=300,
            what="the Drake run",
        )
        assert data_of(states[-1])["phase"] == "done"
        run = data_of(wait_for(lambda: runs and runs[-1], what="run document"))
        capsys.readouterr()
        tamp_main(["plan", "case3.yaml", "--execute", "--json"])
        symbolic = json.loads(capsys.readouterr().out)
        hands = lambda names: [a for a in names if not a.startswith("MoveTo")]  # noqa: E731
        expected = [f"{a['action']}({', '.join(a['args'])})" for a in symbolic["executed"]]
        assert hands(run["executed"]) == hands(expected)
        assert "Pick(Oa)" in run["executed"]  # the recovery moved the obstacle
        kinds = [data_of(e)["kind"] for e in events]
        assert "appear" in kinds and kinds.count("start") == len(run["actions"])
        assert joints and joints[-1]["name"][:3] == ["base_x", "base_y", "base_yaw"]
    finally:
        close_ros(ros, s)
        s.stop()


@pytest.mark.slow
def test_cancel_stops_the_drake_run():
    s = Served(sim=True, rate=1.0)  # real time: the run is still going when cancelled
    ros = roslibpy.Ros("127.0.0.1", s.port, transport="asyncio")
    ros.run(timeout=5)
    try:
        events = []
        roslibpy.Topic(ros, "/tamp/events", "std_msgs/String").subscribe(events.append)
        _demonstrate(ros, s, "case1.yaml")
        assert _call(ros, "/tamp/execute")["success"]
        wait_for(
            lambda: any(data_of(e)["kind"] == "start" for e in events),
            timeout=120,
            what="the run under way",
        )
        assert _call(ros, "/tamp/cancel")["success"]
        wait_for(
            lambda: not any(t.name.startswith("tamp-serve-r") for t in threading.enumerate()),
            timeout=30,
            what="the simulation thread to stop",
        )
        assert s.thread.call(lambda: s.app.phase) == "cancelled"
        assert s.thread.call(lambda: s.server.topics["/tamp/execution"].last) is None
    finally:
        close_ros(ros, s)
        s.stop()
