"""The tower as a stack (`tamp.sim.lots.stack`, Zhou et al. Fig. 10): the order, where the
robot stacks from what it saw, what a person stacks onto, and the plant's judge; the
scenario's ``stack`` field (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tamp.errors import InputError
from tamp.sim.lots.catalogue import CLASSES
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.stack import (
    SEAT_TOLERANCE,
    below,
    covered,
    free_top,
    judge_stack,
    resting_on,
    support,
)
from tests.sim.lots.helpers import write_scenario

ORDER = ("bottom", "body", "peak")
FP = {c: CLASSES[c].footprint for c in (*ORDER, "toy_car")}
H = {c: FP[c].top for c in FP}  # heights: bottom 0.04, body 0.05, peak 0.045


def pose(x: float, y: float, z: float, yaw: float = 0.0, tilt: float = 0.0) -> np.ndarray:
    """A 4 x 4 pose: yaw about z, then ``tilt`` about the object's x axis."""
    c, s = math.cos(yaw), math.sin(yaw)
    ct, st = math.cos(tilt), math.sin(tilt)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, ct, -st], [0, st, ct]])
    X = np.eye(4)
    X[:3, :3] = Rz @ Rx
    X[:3, 3] = (x, y, z)
    return X


def in_b(x: float, y: float) -> bool:
    return abs(x - 0.5) <= 0.17 and abs(y + 0.25) <= 0.17


def tower(dz: float = 0.0, dx: float = 0.0) -> dict:
    """Bottom, body and peak stacked at W^B's centre (the body turned 30 deg); ``dz``,
    ``dx``: the peak raised or shifted."""
    return {
        "bottom_0": ("bottom", pose(0.5, -0.25, 0.0, 0.2)),
        "body_1": ("body", pose(0.502, -0.251, H["bottom"] - 0.001, 0.5)),
        "peak_0": ("peak", pose(0.5 + dx, -0.25, H["bottom"] + H["body"] + dz)),
        "body_0": ("body", pose(0.2, -0.58, 0.02)),  # in the waste basket
    }


def test_each_level_goes_on_the_class_before_it():
    assert below(ORDER, "body") == "bottom" and below(ORDER, "peak") == "body"
    assert below(ORDER, "bottom") is None  # the base goes on the floor
    assert below(ORDER, "toy_car") is None and below((), "body") is None


def test_support_is_the_highest_instance_of_the_class_seen():
    seen = [
        ("bottom", (0.5, -0.25, 0.04)),
        ("body", (0.45, -0.2, 0.05)),  # one on the floor
        ("body", (0.5, -0.25, 0.09)),  # one on the bottom: the stack's top
        ("peak", (0.6, -0.3, 0.04)),
    ]
    assert support("body", seen) == (0.5, -0.25, 0.09)
    assert support("bottom", seen) == (0.5, -0.25, 0.04)
    assert support("toy_car", seen) is None


def test_resting_on_needs_the_top_the_footprint_and_an_upright_axis():
    X_b = pose(0.5, -0.25, 0.0, 0.3)
    fp = FP["bottom"]
    assert resting_on(X_b, fp, pose(0.5, -0.25, 0.04))
    assert resting_on(X_b, fp, pose(0.51, -0.24, 0.04 - SEAT_TOLERANCE + 0.001, 1.0))
    assert not resting_on(X_b, fp, pose(0.5, -0.25, 0.04 + SEAT_TOLERANCE + 0.002))  # above
    assert not resting_on(X_b, fp, pose(0.5, -0.25, 0.0))  # beside it, on the floor
    assert not resting_on(X_b, fp, pose(0.6, -0.25, 0.04))  # off its footprint
    assert not resting_on(X_b, fp, pose(0.5, -0.25, 0.04, tilt=math.radians(30)))  # toppled


def test_the_complete_tower_is_three_high_and_the_waste_body_is_no_level():
    check = judge_stack(ORDER, tower(), FP, in_b)
    assert check.levels == ("bottom_0", "body_1", "peak_0")
    assert check.height == 3 and check.complete
    assert check.to_json()["complete"] and check.to_json()["height"] == 3
    assert check.describe() == "stack 3 of 3 high in W^B: peak_0 on body_1 on bottom_0"


def test_side_by_side_is_one_high():
    objects = {
        "bottom_0": ("bottom", pose(0.45, -0.25, 0.0)),
        "body_1": ("body", pose(0.55, -0.25, 0.0)),
        "peak_0": ("peak", pose(0.5, -0.15, 0.0)),
    }
    check = judge_stack(ORDER, objects, FP, in_b)
    assert check.levels == ("bottom_0",) and not check.complete
    assert "no body resting on it" in check.describe()


@pytest.mark.parametrize(("dz", "dx"), [(0.03, 0.0), (0.0, 0.05)])
def test_a_peak_held_above_or_fallen_beside_is_not_a_level(dz, dx):
    check = judge_stack(ORDER, tower(dz=dz, dx=dx), FP, in_b)
    assert check.height == 2


def test_the_base_must_lie_on_the_floor_of_the_workspace():
    objects = tower()
    objects["bottom_0"] = ("bottom", pose(0.5, 0.25, 0.0))  # in W^A
    assert judge_stack(ORDER, objects, FP, in_b).height == 0
    raised = {u: (c, X + _lift(0.02)) for u, (c, X) in tower().items()}
    assert judge_stack(ORDER, raised, FP, in_b).height == 0  # 2 cm up: not on the table
    assert judge_stack(ORDER, raised, FP, in_b, floor=0.02).height == 3  # a raised floor


def _lift(dz: float) -> np.ndarray:
    out = np.zeros((4, 4))
    out[2, 3] = dz
    return out


def test_covered_and_the_free_top_a_person_stacks_onto():
    objects = {u: o for u, o in tower().items() if u != "body_0"}  # W^B's objects
    assert covered("bottom_0", objects, FP) and covered("body_1", objects, FP)
    assert not covered("peak_0", objects, FP)
    assert free_top("body", objects, FP) is None  # the body has the peak on it
    del objects["peak_0"]
    x, y, z = free_top("body", objects, FP)
    assert z == pytest.approx(H["bottom"] - 0.001 + H["body"])
    assert (x, y) == pytest.approx((0.502, -0.251))
    assert free_top("toy_car", objects, FP) is None


def test_the_packaged_tower_declares_its_stack():
    assert load_cell_scenario("tower").stack == ORDER
    assert load_cell_scenario("tower_perturbed").stack == ORDER
    assert load_cell_scenario("model_building").stack == ()


@pytest.mark.parametrize(
    ("stack", "reason"),
    [
        (["bottom", "anvil"], "unknown class 'anvil'"),
        (["bottom", "body", "bottom"], "'bottom' is named twice"),
        (["bottom"], "two classes or more"),
        ("bottom", "expected"),
    ],
)
def test_a_bad_stack_names_the_file_and_the_field(tmp_path, stack, reason):
    path = write_scenario(tmp_path, [], stack=stack)
    with pytest.raises(InputError) as e:
        load_cell_scenario(path)
    assert str(e.value).startswith(f"{path}: stack: ") and reason in str(e.value)


def test_a_task_needs_the_stack_only_as_high_as_its_plan():
    """A task delivering only the base needs one level; the tower all three; a gap in the
    order stops the count (a peak without a body cannot stand)."""
    from tamp.sim.lots.stack import required_height

    order = ("bottom", "body", "peak")
    assert required_height(order, {"bottom": 1}) == 1
    assert required_height(order, {"bottom": 1, "body": 1, "peak": 1}) == 3
    assert required_height(order, {"bottom": 1, "peak": 1}) == 1
    assert required_height(order, {}) == 0


def test_a_stack_is_complete_as_high_as_required():
    """The judge counts the levels standing; the task's need decides `complete`."""
    objects = {k: v for k, v in tower().items() if not k.startswith("peak")}
    assert not judge_stack(ORDER, objects, FP, in_b).complete
    check = judge_stack(ORDER, objects, FP, in_b, required=2)
    assert check.complete and check.to_json()["required"] == 2
