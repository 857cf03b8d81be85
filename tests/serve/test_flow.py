"""Demonstrate, plan and execute over the wire with roslibpy (its asyncio transport), as an
MR app or a Python script would: the results equal ``tamp plan`` of the YAML files."""

from __future__ import annotations

import json
import threading

import pytest
import yaml

from tamp.commands.main import main as tamp_main
from tamp.commands.serve import execute_symbolic, plan_demo
from tamp.scenarios import path as packaged
from tamp.serve import Pipeline
from tests.serve.conftest import Served, case_begin, close_ros, data_of, wait_for

roslibpy = pytest.importorskip("roslibpy")


@pytest.fixture
def ros(served):
    client = roslibpy.Ros("127.0.0.1", served.port, transport="asyncio")
    client.run(timeout=5)
    yield client
    close_ros(client, served)


def call(ros, name: str, args: dict | None = None, type_: str = "std_srvs/Trigger") -> dict:
    return roslibpy.Service(ros, name, type_).call(roslibpy.ServiceRequest(args or {}), timeout=30)


def listen(ros, name: str, type_: str = "std_msgs/String") -> list:
    got: list = []
    roslibpy.Topic(ros, name, type_).subscribe(got.append)
    return got


def demonstrate(ros, case: str) -> dict:
    """Begin and publish the steps of a packaged demonstration; returns its mapping."""
    data = yaml.safe_load(packaged(case).read_text())
    begin, steps = case_begin(data)
    reply = call(ros, "/tamp/demo/begin", begin, "tamp_msgs/BeginDemo")
    assert reply["success"], reply["message"]
    shown = listen(ros, "/tamp/demo/steps")
    step = roslibpy.Topic(ros, "/tamp/demo/step", "tamp_msgs/DemoStep")
    step.advertise()
    for m in steps:
        step.publish(roslibpy.Message(m))
    wait_for(lambda: shown and len(data_of(shown[-1])["steps"]) == len(steps), what="steps")
    return data


def cli_json(capsys, *argv: str) -> str:
    capsys.readouterr()
    tamp_main(list(argv))
    return capsys.readouterr().out


@pytest.mark.parametrize("case", ["case1.yaml", "case2.yaml", "case3.yaml"])
def test_live_demonstration_plans_like_the_yaml_file(ros, capsys, tmp_path, case):
    demonstrate(ros, case)
    reply = call(ros, "/tamp/plan", {"cost_model": "distance", "constraints": []}, "tamp_msgs/Plan")
    assert reply["success"], reply["message"]
    expected = cli_json(capsys, "plan", case, "--json")
    assert reply["plan_json"] + "\n" == expected
    assert reply["order"] == json.loads(expected)["order"]
    exported = call(ros, "/tamp/demo/export")["message"]
    out = tmp_path / case
    out.write_text(exported)
    assert cli_json(capsys, "plan", str(out), "--json") == expected  # the export round-trips


@pytest.mark.parametrize("case", ["case1.yaml", "case3.yaml"])
def test_execute_reports_the_actions_of_tamp_plan_execute(ros, capsys, case):
    demonstrate(ros, case)
    states = listen(ros, "/tamp/state")
    events = listen(ros, "/tamp/events")
    executions = listen(ros, "/tamp/execution")
    assert call(ros, "/tamp/plan", {}, "tamp_msgs/Plan")["success"]
    assert call(ros, "/tamp/execute")["success"]
    wait_for(lambda: states and data_of(states[-1])["phase"] in ("done", "failed"), what="done")
    assert data_of(states[-1])["phase"] == "done"
    expected = json.loads(cli_json(capsys, "plan", case, "--execute", "--json"))
    got = data_of(wait_for(lambda: executions and executions[-1], what="execution"))
    assert got["executed"] == expected["executed"]
    assert got["recoveries"] == expected["recoveries"]
    wait_for(lambda: any(data_of(e)["kind"] == "success" for e in events), what="events")
    started = [data_of(e)["what"] for e in events if data_of(e)["kind"] == "start"]
    names = [f"{a['action']}({', '.join(a['args'])})" for a in expected["attempts"]]
    assert started == names
    kinds = {data_of(e)["kind"] for e in events}
    if case == "case3.yaml":  # O_a appears on l_1 and the tree grows a recovery
        assert expected["recoveries"] >= 1 and {"recovery", "appear"} <= kinds
    pose = listen(ros, "/tamp/robot/pose", "geometry_msgs/PoseStamped")
    wait_for(lambda: pose, what="latched robot pose")
    assert pose[0]["header"]["frame_id"] == "mr"


def test_a_late_subscriber_gets_the_latched_plan_at_once(ros, served):
    demonstrate(ros, "case2.yaml")
    assert call(ros, "/tamp/plan", {}, "tamp_msgs/Plan")["success"]
    late = roslibpy.Ros("127.0.0.1", served.port, transport="asyncio")
    late.run(timeout=5)
    try:
        plans = listen(late, "/tamp/plan_result")
        doc = data_of(wait_for(lambda: plans and plans[0], what="latched plan"))
        assert doc["success"] and doc["plan"]["order"] == ["G1", "G0", "G3", "G2"]
        assert set(doc["goals_mr"]) == {"G0", "G1", "G2", "G3"}
    finally:
        close_ros(late, served)


def test_clear_answers_to_wrong_requests(ros):
    with pytest.raises(Exception, match="unknown service /tamp/nope"):
        call(ros, "/tamp/nope")
    reply = call(ros, "/tamp/plan", {}, "tamp_msgs/Plan")
    assert not reply["success"] and "begin" in reply["message"]
    assert not call(ros, "/tamp/execute")["success"]
    assert not call(ros, "/tamp/cancel")["success"]
    data = yaml.safe_load(packaged("case2.yaml").read_text())
    begin, _ = case_begin(data)
    begin["objects"].append(dict(begin["objects"][0]))  # a duplicate id
    reply = call(ros, "/tamp/demo/begin", begin, "tamp_msgs/BeginDemo")
    assert not reply["success"] and reply["message"].startswith("live:s")
    assert "objects[2].id" in reply["message"]
    begin, _ = case_begin(data)
    begin["header"]["frame_id"] = "map"
    reply = call(ros, "/tamp/demo/begin", begin, "tamp_msgs/BeginDemo")
    assert not reply["success"] and "header.frame_id" in reply["message"]
    assert set(ros.get_topics()) >= {"/tamp/state", "/tamp/plan_result", "/tamp/demo/step"}


def test_a_bad_step_is_refused_with_the_loaders_reason(ros):
    demonstrate(ros, "case1.yaml")
    events = listen(ros, "/tamp/events")
    step = roslibpy.Topic(ros, "/tamp/demo/step", "tamp_msgs/DemoStep")
    step.publish(roslibpy.Message({"object_id": "O9", "pose": {"position": {"x": 1.0}}}))
    e = data_of(wait_for(lambda: events and events[-1], what="rejection"))
    assert e["kind"] == "step_rejected" and "unknown object 'O9'" in e["why"]
    assert "steps[3].object" in e["why"]


def test_steps_during_execution_are_refused_and_cancel_stops_the_run():
    """A run held open by the test's executor: a step and a plan during it are refused,
    cancel ends it as cancelled, and its late result is not published."""
    release = threading.Event()

    def held(demo, result, mapping, channel):
        release.wait(10)
        return execute_symbolic(demo, result, mapping, channel)

    s = Served()
    s.app.pipeline = Pipeline(plan=plan_demo, execute=held, name="held")
    ros = roslibpy.Ros("127.0.0.1", s.port, transport="asyncio")
    ros.run(timeout=5)
    try:
        demonstrate(ros, "case1.yaml")
        states, events = listen(ros, "/tamp/state"), listen(ros, "/tamp/events")
        assert call(ros, "/tamp/plan", {}, "tamp_msgs/Plan")["success"]
        assert call(ros, "/tamp/execute")["success"]
        wait_for(lambda: states and data_of(states[-1])["phase"] == "executing", what="executing")
        step = roslibpy.Topic(ros, "/tamp/demo/step", "tamp_msgs/DemoStep")
        step.publish(roslibpy.Message({"object_id": "O0", "pose": {"position": {"x": 1.0}}}))
        e = data_of(wait_for(lambda: events and events[-1], what="rejection"))
        assert e["kind"] == "step_rejected" and "executing" in e["why"]
        assert "executing" in call(ros, "/tamp/plan", {}, "tamp_msgs/Plan")["message"]
        assert not call(ros, "/tamp/execute")["success"]
        assert call(ros, "/tamp/cancel")["success"]
        wait_for(lambda: data_of(states[-1])["phase"] == "cancelled", what="cancelled")
        release.set()
        assert call(ros, "/tamp/demo/undo")["success"]  # the session is editable again
        wait_for(lambda: data_of(states[-1])["phase"] == "demonstrating", what="demonstrating")
        assert s.thread.call(lambda: s.server.topics["/tamp/execution"].last) is None
    finally:
        release.set()
        close_ros(ros, s)
        s.stop()


def test_open_a_packaged_scene_and_refuse_paths(ros):
    reply = call(ros, "/tamp/demo/open", {"name": "case3.yaml"}, "tamp_msgs/OpenDemo")
    assert reply["success"] and "2 objects" in reply["message"]
    scenes = listen(ros, "/tamp/scene")
    scene = data_of(wait_for(lambda: scenes and scenes[0], what="scene"))
    assert [o["id"] for o in scene["objects"]] == ["O0", "O1"]
    assert scene["objects"][0]["robot"] == [1.0, -0.5, 0.0]  # eq. (1)-(5), as case3.yaml says
    for bad in ("../../etc/passwd", "/etc/hosts", "nope.yaml"):
        assert not call(ros, "/tamp/demo/open", {"name": bad}, "tamp_msgs/OpenDemo")["success"]
