"""The live session without a socket: MR frames (eq. 1–5), the loader fed a mapping, and
hostile requests answered with the field that is wrong."""

from __future__ import annotations

import math

import pytest
import yaml

from tamp.demo import demonstration_from_dict, load_demonstration
from tamp.errors import InputError
from tamp.rg import plan
from tamp.scenarios import path as packaged
from tamp.serve.mr import MessageError, robot_to_mr, rotation_of, to_file
from tamp.serve.session import DemoSession, SessionError, parse_constraints
from tests.serve.conftest import case_begin


def case(name: str) -> dict:
    return yaml.safe_load(packaged(name).read_text())


@pytest.mark.parametrize("name", ["case1.yaml", "case2.yaml", "case3.yaml"])
def test_the_loader_fed_a_mapping_equals_the_file(name):
    a = plan(demonstration_from_dict(case(name), "live:test")).to_json()
    b = plan(load_demonstration(name)).to_json()
    assert a == b


def test_the_mapping_entry_refuses_what_the_file_refuses():
    data = case("case2.yaml")
    with pytest.raises(InputError, match="live:x: version"):
        demonstration_from_dict({**data, "version": 2}, "live:x")
    with pytest.raises(InputError, match="live:x: version"):
        demonstration_from_dict({**data, "version": True}, "live:x")
    with pytest.raises(InputError, match="must be a mapping"):
        demonstration_from_dict([], "live:x")
    with pytest.raises(InputError, match=r"live:x: robot.domain: must be an absolute path"):
        demonstration_from_dict({**data, "robot": {"domain": "d.yaml"}}, "live:x")
    bad = {**data, "frame": {"robot_position": [0.4, math.nan, -1.2]}}
    with pytest.raises(InputError, match="frame.robot_position"):
        demonstration_from_dict(bad, "live:x")
    with pytest.raises(InputError, match="unknown key|steps"):
        demonstration_from_dict({**data, "stepz": []}, "live:x")


def test_case2_point_through_the_mr_frame():
    """O0 at Unity (0.4, 0, 1.3), uP_r (0.4, 0, −1.2): mr (1.3, −0.4, 0), robot (2.5, 0, 0)."""
    s = DemoSession()
    begin, steps = case_begin(case("case2.yaml"))
    assert begin["objects"][0]["pose"]["position"] == {"x": 1.3, "y": -0.4, "z": 0.0}
    s.begin(begin)
    scene = s.scene_json()
    assert scene["objects"][0]["mr"] == [1.3, -0.4, 0.0]
    assert scene["objects"][0]["robot"] == [2.5, 0.0, 0.0]
    for m in steps:
        s.step(m)
    assert s.demonstration_dict() == {**case("case2.yaml"), "robot": {"start": [0.3, 0.9, 0.0]}}
    assert robot_to_mr(s.mr_frame(), (2.5, 0.0, 0.0)) == [1.3, -0.4, 0.0]
    assert s.steps_json()[0] == {
        "goal": "G0",
        "object": "O0",
        "robot": [2.5, -0.5, 0.0],
        "mr": [1.3, -0.9, 0.0],
    }


def test_raw_unity_frame_and_rotated_robot():
    assert to_file((1.3, -0.4, 0.0), "mr") == [0.4, 0.0, 1.3]
    assert to_file((0.4, 0.0, 1.3), "unity_lh") == [0.4, 0.0, 1.3]
    assert rotation_of({"x": 0, "y": 0, "z": 0, "w": 1}, "mr", "q") is None
    assert rotation_of({"x": 0, "y": 0, "z": 0, "w": 0}, "mr", "q") is None  # ROS default
    c = math.sqrt(0.5)
    R = rotation_of({"x": 0, "y": 0, "z": c, "w": c}, "mr", "q")  # robot turned 90° about z
    s = DemoSession()
    begin, _ = case_begin(case("case2.yaml"))
    begin["robot"]["orientation"] = {"x": 0, "y": 0, "z": c, "w": c}
    s.begin(begin)
    assert s.demonstration_dict()["frame"]["rotation"] == R
    # O0 is 2.5 m ahead of the robot along mr x; turned 90°, that is the robot's −y.
    robot = s.scene_json()["objects"][0]["robot"]
    assert robot == pytest.approx([0.0, -2.5, 0.0], abs=1e-9)
    with pytest.raises(MessageError, match="not a unit quaternion"):
        rotation_of({"x": 0, "y": 0, "z": 1, "w": 1}, "mr", "q")
    with pytest.raises(MessageError, match="mr frame"):
        rotation_of({"x": 0, "y": 0, "z": c, "w": c}, "unity_lh", "q")


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda b: b.update(objects="O0"), "objects"),
        (lambda b: b.update(objects=[{"id": "O 0", "pose": {}}]), "objects[0].id"),
        (lambda b: b.update(objects=[{"id": "x" * 65, "pose": {}}]), "objects[0].id"),
        (lambda b: b["objects"][0]["pose"]["position"].update(x="1"), "objects[0].pose.position.x"),
        (lambda b: b["objects"][0]["pose"]["position"].update(x=math.inf), "position.x"),
        (lambda b: b.update(robot=[]), "robot"),
        (lambda b: b.update(start=[1, 2]), "start"),
        (lambda b: b.update(area_radius=-1), "area_radius"),
        (lambda b: b.update(header={"frame_id": "odom"}), "header.frame_id"),
        (lambda b: b.update(objects=[]), "objects"),
        (lambda b: b.update(appear="Oa@L1"), "appear"),
    ],
)
def test_hostile_begin_requests_name_the_field(change, field):
    begin, _ = case_begin(case("case2.yaml"))
    change(begin)
    s = DemoSession()
    with pytest.raises((MessageError, InputError)) as info:
        s.begin(begin)
    assert field in str(info.value)
    assert s.data is None  # nothing half-begun


def test_steps_undo_reset_and_refusals():
    s = DemoSession()
    with pytest.raises(SessionError, match="begin"):
        s.step({"object_id": "O0", "pose": {"position": {"x": 1}}})
    begin, steps = case_begin(case("case1.yaml"))
    s.begin(begin)
    with pytest.raises(SessionError, match="no steps"):
        s.demonstration()
    with pytest.raises(InputError, match="already there"):
        s.step({"object_id": "O0", "pose": begin["objects"][0]["pose"]})
    with pytest.raises(MessageError, match="pose.position"):
        s.step({"object_id": "O0", "pose": {"position": [1, 2, 3]}})
    s.step(steps[0])
    s.step(steps[1])
    assert "1 steps left" in s.undo()
    s.reset()
    with pytest.raises(SessionError, match="no step"):
        s.undo()


def test_constraints_spellings():
    assert parse_constraints(["G0<=G2", ["G1", "G3"]]) == [["G0", "G2"], ["G1", "G3"]]
    assert parse_constraints(None) == []
    for bad in ("G0<=G1", [3], ["G0"], ["G0<=G 1"]):
        with pytest.raises(MessageError):
            parse_constraints(bad)
