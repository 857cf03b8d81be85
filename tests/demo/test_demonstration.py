"""Demonstration layer: frames (eq. 1-5), goals, intent and physical constraints, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tamp.demo import MRFrame, load_demonstration
from tamp.errors import InputError
from tamp.scenarios import path


def test_unity_to_ros_default_handedness() -> None:
    frame = MRFrame(robot_position=(0.0, 0.0, 0.0))
    p = frame.to_robot((1.0, 2.0, 3.0))  # user x right, y up, z forward
    assert (p.x, p.y, p.z) == (3.0, -1.0, 2.0)  # robot x = user z, y = -user x, z = user y


def test_eq1_subtracts_robot_position_then_rotates() -> None:
    yaw = math.pi / 2  # rotation about the user's up axis (y)
    R = (
        (math.cos(yaw), 0.0, math.sin(yaw)),
        (0.0, 1.0, 0.0),
        (-math.sin(yaw), 0.0, math.cos(yaw)),
    )
    frame = MRFrame(robot_position=(1.0, 0.0, 1.0), rotation=R)
    T = frame.homogeneous()
    assert np.allclose(T[:3, :3], R) and np.allclose(T[:3, 3], -np.asarray(R) @ [1.0, 0.0, 1.0])
    p = frame.to_robot((1.0, 0.0, 2.0))  # 1 m in front of the robot along user z
    # R maps user z=(0,0,1) to (1,0,0): user x; robot y = -user x
    assert p.x == pytest.approx(0.0, abs=1e-12) and p.y == pytest.approx(-1.0)


def test_identity_rotation_matches_paper_eq1() -> None:
    frame = MRFrame(robot_position=(0.4, 0.0, -1.2))
    T = frame.homogeneous()
    assert np.allclose(T[:3, 3], [-0.4, 0.0, 1.2])  # T = [I, -uP_r; 0, 1]


def test_case1_goals_and_no_constraints() -> None:
    d = load_demonstration(path("case1.yaml"))
    assert [g.object for g in d.goals] == ["O0", "O1", "O2"]
    assert d.constraints == frozenset()
    assert d.objects["O2"].x == pytest.approx(1.0) and d.objects["O2"].y == pytest.approx(0.0)


def test_case2_constraints_are_exactly_the_papers() -> None:
    d = load_demonstration(path("case2.yaml"))
    assert d.constraints == {("G0", "G2"), ("G1", "G3"), ("G0", "G3"), ("G1", "G2")}
    kinds = {c: r.split(":")[0] for c, r in d.constraint_reasons.items()}
    assert kinds == {
        ("G0", "G2"): "intent",
        ("G1", "G3"): "intent",
        ("G0", "G3"): "physical",
        ("G1", "G2"): "physical",
    }


def test_initial_world_has_goal_and_free_areas() -> None:
    d = load_demonstration(path("case3.yaml"))
    w = d.initial_world()
    assert set(w.areas) == {"L0", "L1", "free1", "free2"}
    assert w.held is None and set(w.objects) == {"O0", "O1"}


BASE = """version: 1
frame: {robot_position: [0, 0, 0]}
area_radius: 0.15
objects:
  - {id: A, position: [0, 0, 1]}
  - {id: B, position: [0, 0, 2]}
"""


@pytest.mark.parametrize(
    "body, field, words",
    [
        ("steps:\n  - {object: C, to: [0, 0, 3]}\n", "steps[0].object", "unknown object"),
        ("steps:\n  - {object: A, to: [0, 0, 2]}\n", "steps[0]", "never leaves"),
        (
            "steps:\n  - {object: A, to: [0, 0, 3]}\n  - {object: B, to: [0, 0, 4]}\n"
            "constraints: [[G0, G1], [G1, G0]]\n",
            "constraints",
            "cyclic",
        ),
        (
            "steps:\n  - {object: A, to: [0, 0, 3]}\nconstraints: [[G0, G7]]\n",
            "constraints[0]",
            "G7",
        ),
        ("steps:\n  - {object: A, to: [0, 0]}\n", "steps[0].to", "3 numbers"),
        ("steps:\n  - {object: A, to: [0, 0, 3], speed: 2}\n", "steps[0].speed", "unknown key"),
        ("steps: []\n", "steps", "at least one step"),
    ],
)
def test_bad_demonstrations_name_the_field(tmp_path, body: str, field: str, words: str) -> None:
    p = tmp_path / "demo.yaml"
    p.write_text(BASE + body)
    with pytest.raises(InputError) as err:
        load_demonstration(p)
    msg = str(err.value)
    assert str(p) in msg and field in msg and words in msg


def test_cycle_message_names_the_steps(tmp_path) -> None:
    p = tmp_path / "demo.yaml"
    p.write_text(
        BASE + "steps:\n  - {object: A, to: [0, 0, 3]}\n  - {object: B, to: [0, 0, 4]}\n"
        "constraints: [[G0, G1], [G1, G0]]\n"
    )
    with pytest.raises(InputError) as err:
        load_demonstration(p)
    assert "steps[0]" in str(err.value) and "steps[1]" in str(err.value)


def test_overlapping_initial_objects_refused(tmp_path) -> None:
    p = tmp_path / "demo.yaml"
    p.write_text(
        BASE.replace("[0, 0, 2]", "[0, 0, 1.1]") + "steps:\n  - {object: A, to: [0, 0, 3]}\n"
    )
    with pytest.raises(InputError, match="overlap"):
        load_demonstration(p)


def test_non_rotation_matrix_refused(tmp_path) -> None:
    p = tmp_path / "demo.yaml"
    p.write_text(
        BASE.replace(
            "frame: {robot_position: [0, 0, 0]}",
            "frame: {robot_position: [0, 0, 0], rotation: [[2, 0, 0], [0, 1, 0], [0, 0, 1]]}",
        )
        + "steps:\n  - {object: A, to: [0, 0, 3]}\n"
    )
    with pytest.raises(InputError, match="frame.rotation"):
        load_demonstration(p)
