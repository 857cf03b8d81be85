"""`tamp serve --sim`: a live Case 3 runs in the Drake youBot cell with the tree's recovery,
picking and placing as `tamp plan --execute` does in the symbolic world."""

from __future__ import annotations

import json

import pytest
import yaml

from tamp.commands.main import main as tamp_main
from tamp.scenarios import path as packaged
from tests.serve.conftest import Served, case_begin, close_ros, data_of, wait_for

roslibpy = pytest.importorskip("roslibpy")
pytest.importorskip("pydrake")


@pytest.mark.slow
def test_sim_runs_case3_like_the_symbolic_execution(capsys):
    s = Served(sim=True)
    ros = roslibpy.Ros("127.0.0.1", s.port, transport="asyncio")
    ros.run(timeout=5)
    try:
        data = yaml.safe_load(packaged("case3.yaml").read_text())
        begin, steps = case_begin(data)
        states, runs = [], []
        roslibpy.Topic(ros, "/tamp/state", "std_msgs/String").subscribe(states.append)
        roslibpy.Topic(ros, "/tamp/execution", "std_msgs/String").subscribe(runs.append)
        call = lambda name, args=None: roslibpy.Service(ros, name, "x").call(  # noqa: E731
            roslibpy.ServiceRequest(args or {}), timeout=60
        )
        assert call("/tamp/demo/begin", begin)["success"]
        step = roslibpy.Topic(ros, "/tamp/demo/step", "tamp_msgs/DemoStep")
        for m in steps:
            step.publish(roslibpy.Message(m))
        wait_for(lambda: s.thread.call(lambda: len(s.app.session.mr_steps)) == 2, what="steps")
        assert call("/tamp/plan")["success"]
        assert "drake" in call("/tamp/execute")["message"]
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
    finally:
        close_ros(ros, s)
        s.stop()
