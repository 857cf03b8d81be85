"""An object a person puts down at a time: unseen before, seen after, and the tree recovers
(with no free area in the demonstration, the tree finds free areas itself)."""

from __future__ import annotations

import math

import pytest

from .helpers import verified_runner, write_one_bottle

pytestmark = pytest.mark.slow  # Drake simulation runs


def test_obstacle_appearing_at_a_time_is_cleared_from_the_goal(tmp_path):
    path = write_one_bottle(
        tmp_path, "objects:\n  - {id: Oa, model: obstacle}\nappear: ['Oa@L0@t=3']\n"
    )
    scenario, system, runner = verified_runner(path)
    seen: list[tuple[float, bool]] = []
    est_ctx = system.estimator.GetMyContextFromRoot(runner.root)

    def record(t: float) -> None:
        world = system.estimator.world_state_port.Eval(est_ctx)
        seen.append((t, "Oa" in world.objects))

    result = runner.run(on_chunk=record)
    assert result.status == "SUCCESS", result.reason
    assert abs(result.appeared["Oa"] - 3.0) < 1e-9
    assert not any(s for t, s in seen if t < 3.0 - 1e-9)
    assert all(s for t, s in seen if t >= 3.0)
    l0 = system.areas["L0"]
    o0, oa = result.final_poses["O0"], result.final_poses["Oa"]
    assert math.hypot(o0.x - l0.pos.x, o0.y - l0.pos.y) <= l0.radius
    assert abs(o0.z - 0.1) < 0.01
    assert math.hypot(oa.x - l0.pos.x, oa.y - l0.pos.y) > l0.radius + 0.05
    assert abs(oa.z - 0.075) < 0.01  # resting on the floor, upright
    placed = [a.action for a in result.actions if a.status == "SUCCESS"]
    assert any(a.startswith("Place(Oa, free_auto") for a in placed)
    assert placed[-1] == "Place(O0, L0)"


def test_object_without_when_appears_once_the_robot_is_within_reach(tmp_path):
    """``--appear Y@L0`` (no WHEN): a person puts Y on l_0 when the robot gets there (§V-D2)."""
    path = write_one_bottle(tmp_path, "objects:\n  - {id: Y, model: obstacle}\nappear: ['Y@L0']\n")
    scenario, system, runner = verified_runner(path)
    reach = scenario.demo.domain().reach
    l0 = system.areas["L0"].pos
    distance: list[tuple[float, float]] = []

    def record(t: float) -> None:
        x, y, _ = runner.robot_pose()
        distance.append((t, math.hypot(l0.x - x, l0.y - y)))

    result = runner.run(on_chunk=record)
    assert result.status == "SUCCESS", result.reason
    t_appear = result.appeared["Y"]
    first_close = next(t for t, d in distance if d <= reach)
    assert t_appear == first_close > 0  # not before: the robot starts 1.2 m away
    placed = [a.action for a in result.actions if a.status == "SUCCESS"]
    assert any(a.startswith("Place(Y, ") for a in placed) and placed[-1] == "Place(O0, L0)"


def test_an_object_appearing_onto_an_occupied_area_is_set_aside(capsys):
    """Issue 17: O_a put down on l_2 where O2 already stands used to go *inside* O2; O2 ended
    toppled outside l_2 and the run still said SUCCESS (exit 1). Now the person puts O_a down
    on the nearest free spot, the run says so, and status, ``ok`` and the exit code agree."""
    import json

    from tamp.commands.main import main

    code = main(
        ["simulate", "smp-mro", "--case", "1", "--appear", "Oa@L2@after:Place(O2, L2)", "--json"]
    )
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and data["status"] == "SUCCESS" and data["ok"] is True
    assert data["goals"] == {"O0@L0": True, "O1@L1": True, "O2@L2": True}
    (warning,) = data["warnings"]
    assert "Oa@L2@after:Place(O2, L2): the place is occupied by O2" in warning
    assert "outside every area" in warning
    oa, o2 = data["final_poses"]["Oa"], data["final_poses"]["O2"]
    assert abs(o2["z"] - 0.1) < 0.01 and abs(oa["z"] - 0.1) < 0.01  # both upright
    for area in ((3.8, 0.8), (2.8, 0.6), (1.8, 0.6)):  # L0, L1, L2 (robot frame)
        assert math.hypot(oa["x"] - area[0], oa["y"] - area[1]) > 0.15 + 0.035
    t_place = next(a["end"] for a in data["actions"] if a["action"] == "Place(O2, L2)")
    assert abs(data["appeared"]["Oa"] - t_place) < 0.05


def test_a_stacked_goal_object_is_a_failure_whatever_the_tree_says(tmp_path):
    """Success is judged on the plant in 3-D: O0 resting on top of Y inside l_0 is not at
    l_0. The tree's view is planar, so it reports SUCCESS; the run's status is FAILURE,
    and ``ok``/the exit code follow the status."""
    from pydrake.math import RigidTransform

    path = write_one_bottle(
        tmp_path, "objects:\n  - {id: Y, model: obstacle}\nappear: ['Y@1.5,-0.5@t=1000']\n"
    )
    scenario, system, runner = verified_runner(path)
    ex_ctx = system.executor.GetMyContextFromRoot(runner.root)
    l0 = system.areas["L0"].pos

    def stack_at_the_end(t: float) -> None:
        if system.executor.state(ex_ctx).result is None:
            return
        plant, ctx = system.plant, runner.plant_context
        plant.SetFreeBodyPose(ctx, system.bodies["Y"], RigidTransform([l0.x, l0.y, 0.075]))
        plant.SetFreeBodyPose(ctx, system.bodies["O0"], RigidTransform([l0.x, l0.y, 0.25]))

    result = runner.run(on_chunk=stack_at_the_end)
    assert system.executor.state(ex_ctx).result.value == "SUCCESS"  # the tree's view
    assert result.status == "FAILURE" and not result.ok and result.exit_code == 1
    assert result.goals == {"O0@L0": False}
    assert "on the plant O0 is not resting on the floor (z = 0.250 m" in result.reason
    assert "on top of Y" in result.reason
    assert result.to_json()["ok"] is False and result.to_json()["status"] == "FAILURE"


def test_one_diagram_runs_twice_in_two_contexts_alike(tmp_path):
    """Areas the tree finds at run time (ring search: free_auto<k>) live in the Context, not
    on the System objects: a second run of the same diagram starts clean and does the same."""
    path = write_one_bottle(
        tmp_path, "objects:\n  - {id: Oa, model: obstacle}\nappear: ['Oa@L0@t=3']\n"
    )
    scenario, system, first = verified_runner(path)
    untouched = system.diagram.CreateDefaultContext()
    a = first.run()
    ctx_a = first.root
    found = system.executor.state(system.executor.GetMyContextFromRoot(ctx_a)).extra_areas
    assert any(name.startswith("free_auto") for name in found)
    ctl_a = system.skills.areas(system.skills.GetMyContextFromRoot(ctx_a))
    assert set(found) <= set(ctl_a)
    # nothing of run 1 is left on the systems: a fresh context knows the built areas only
    fresh = system.diagram.CreateDefaultContext()
    for ctx in (fresh, untouched):
        assert system.skills.areas(system.skills.GetMyContextFromRoot(ctx)) == dict(system.areas)
        assert system.executor.state(system.executor.GetMyContextFromRoot(ctx)).extra_areas == {}

    from tamp.sim.smp.runner import SimRunner

    b = SimRunner(system).run()
    timing = ("wall_time", "realtime_factor", "cpu_time", "cpu_realtime_factor")
    ja, jb = a.to_json(), b.to_json()
    for key in timing:
        ja.pop(key), jb.pop(key)
    assert a.status == "SUCCESS" and ja == jb


def test_an_obstacle_knocked_over_is_a_failure_though_every_goal_holds(tmp_path):
    """Every object is judged, not only the goal objects: Y, put down by the person at the
    start and never picked, is found lying 10 cm from where it was put once the tree has
    succeeded. O0 rests in l_0 (the goal holds); the run fails with cause ``disturbed``,
    naming Y and what happened to it, in the text report and the JSON."""
    from pydrake.math import RigidTransform, RollPitchYaw

    path = write_one_bottle(
        tmp_path, "objects:\n  - {id: Y, model: obstacle}\nappear: ['Y@1.5,-0.5@0']\n"
    )
    scenario, system, runner = verified_runner(path)
    ex_ctx = system.executor.GetMyContextFromRoot(runner.root)
    radius = scenario.object("Y").kind.radius

    def knock_over_at_the_end(t: float) -> None:
        if system.executor.state(ex_ctx).result is None:
            return
        X = RigidTransform(RollPitchYaw(math.pi / 2, 0.0, 0.0), [1.6, -0.5, radius])
        system.plant.SetFreeBodyPose(runner.plant_context, system.bodies["Y"], X)

    result = runner.run(on_chunk=knock_over_at_the_end)
    assert system.executor.state(ex_ctx).result.value == "SUCCESS"  # the tree's view
    assert result.goals == {"O0@L0": True} and result.appeared == {"Y": 0.0}
    assert result.status == "FAILURE" and result.cause == "disturbed" and not result.ok
    why = "Y knocked over (tilt 90°), moved 10.0 cm though the robot never picked it"
    assert result.reason == f"the tree succeeded but on the plant {why}"
    (d,) = result.to_json()["disturbed"]
    assert d["object"] == "Y" and d["reason"] == why and d["tilt_deg"] == pytest.approx(90.0)
    assert d["moved"] == pytest.approx(0.1, abs=1e-3) and d["on"] == []
    assert f"  disturbed: {why}" in result.details_lines()
