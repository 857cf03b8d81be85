"""The robot-adapter example (examples/robot_adapter.py, docs/guides/robot-adapter.md): a
`World` over a fake action server with latency, feedback, aborts and cancellation runs SMP-MRO
Case 3 the way `tamp plan case3.yaml --execute` does, recovery and a retried grasp included."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from tamp.world.actions import default_domain
from tamp.world.interface import Status, World

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "robot_adapter.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("robot_adapter", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules["robot_adapter"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_case3_on_the_fake_robot_reaches_every_goal(example):
    from tamp.demo import load_demonstration
    from tamp.scenarios import resolve

    report = example.run("case3.yaml", slips=("O0",))
    assert report.status is Status.SUCCESS, report.reason
    demo = load_demonstration(resolve("case3.yaml"))
    areas = demo.initial_world().areas
    final = report.final
    assert areas["L0"].contains(final.objects["O0"].pos)
    assert areas["L1"].contains(final.objects["O1"].pos)
    assert not areas["L1"].contains(final.objects["Oa"].pos)  # the obstacle was moved away
    assert final.held is None
    growth = "\n".join(report.growth)
    assert "retry Pick(O0)" in growth  # the slipped grasp (an aborted goal) is retried
    assert "recovery IsAreaFree(L1)" in growth  # the person's obstacle is cleared
    goals = "\n".join(report.goals)
    assert "pick O0: aborted (the grasp slipped)" in goals
    assert "a person puts Oa" in goals
    assert goals.count("place O1") >= 1 and goals.endswith("place O1: succeeded (placed)")
    assert ("Place(O1, L1)", "FAILURE") not in report.attempts


def test_the_adapter_keeps_the_world_protocol(example):
    from tamp.world import Area, Point

    domain = default_domain()
    server = example.FakeActionServer(
        example.RobotState((0.0, 0.0), objects={"A": (-1.0, 0.0)}), speed=1.0, latency=0.02
    )
    try:
        world = example.ActionServerWorld(server, {"L": Area("L", Point(2.0, 0.0, 0.0), 0.2)})
        assert isinstance(world, World)
        handle = world.start(domain.action("MoveTo", "L"))
        assert world.poll(handle) is Status.RUNNING  # pending (latency), then active
        with pytest.raises(RuntimeError):
            world.start(domain.action("Pick", "A"))  # one skill at a time
        deadline = time.monotonic() + 30
        while server.goal(handle).feedback_count < 3 and time.monotonic() < deadline:
            time.sleep(0.005)  # until the base has moved a few steps
        world.cancel(handle)  # returns once the server has stopped it
        assert server.goal(handle).status is example.GoalStatus.CANCELED
        assert world.poll(handle) is Status.FAILURE
        x = world.observe().robot.pos.x
        assert 0.0 < x < 1.5  # it stopped where it was
        assert server.goal(handle).feedback_count > 0
        pick = world.start(domain.action("Pick", "A"))
        while world.poll(pick) is Status.RUNNING:
            time.sleep(0.005)
        assert world.poll(pick) is Status.FAILURE  # A is out of reach from there
        with pytest.raises(ValueError):
            world.start(SimpleNamespace(name="Wave", args=()))  # no skill for it
    finally:
        server.shutdown()


def test_the_example_runs_as_a_script():
    proc = subprocess.run(
        [sys.executable, str(EXAMPLE), "case1.yaml", "--slip", "O2"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={"PYTHONPATH": str(ROOT), "PATH": ""},
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("execution: SUCCESS")
    assert "pick O2: aborted (the grasp slipped)" in proc.stdout
