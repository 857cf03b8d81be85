"""Class-agnostic safety from depth without a simulator: the table, the gripper, the held object
and the learnt static scene are subtracted from the depth points; anything else within 5 cm
of the gripper or the held object is near; the rate and resolution budget."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from pydrake.math import RigidTransform, RollPitchYaw

from tamp.sim.lots.catalogue import ARM, READY
from tamp.sim.lots.depth_safety import (
    MARGIN,
    Scene,
    budget,
    distance_to_boxes,
    foreign_points,
    in_boxes,
    learn_background,
    learn_released,
    separation,
)
from tamp.sim.lots.safety import GripperModel, held_box

BAND = 0.05


@pytest.fixture(scope="module")
def gripper() -> GripperModel:
    return GripperModel()


def surface_points(boxes, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points on the faces of each box (world)."""
    out = []
    for X_WB, half in boxes:
        local = rng.uniform(-1, 1, (n, 3)) * half
        axis = rng.integers(0, 3, n)
        sign = rng.choice([-1.0, 1.0], n)
        local[np.arange(n), axis] = sign * half[axis]
        out.append(local @ X_WB.rotation().matrix().T + X_WB.translation())
    return np.vstack(out)


def at_ready(gripper: GripperModel, opening: float = 0.0):
    """The ready pose, the fingers closed (their pads meet under the TCP)."""
    gripper.set(np.r_[READY, opening / 2, opening / 2])
    return gripper.boxes_in_world()


def test_table_points_are_not_foreign_a_point_above_it_near_the_gripper_is(gripper):
    boxes = at_ready(gripper)
    tcp = gripper.tcp_pose().translation()
    table_z = tcp[2] - 0.05  # the pads' tips are 1.5 cm below the TCP: 3.5 cm above the table
    xs, ys = np.meshgrid(np.linspace(-0.1, 0.1, 21), np.linspace(-0.1, 0.1, 21))
    table = np.c_[xs.ravel() + tcp[0], ys.ravel(), np.full(xs.size, table_z + 0.003)]
    scene = Scene(table_z, boxes)
    assert len(foreign_points(table, scene)) == 0
    assert separation(table, scene) == math.inf
    lump = np.array([[tcp[0], 0.0, table_z + 0.01]])  # 1 cm over the table, under the pads
    d = separation(np.vstack([table, lump]), scene)
    assert d == pytest.approx(0.025, abs=1e-6) and d < BAND


def test_gripper_points_are_not_foreign_and_a_point_within_5cm_of_it_is(gripper):
    boxes = at_ready(gripper)
    rng = np.random.default_rng(1)
    own = surface_points(boxes, 200, rng)
    scene = Scene(-1.0, boxes)
    assert separation(own, scene) == math.inf
    tcp = gripper.tcp_pose().translation()
    for gap, near in ((0.03, True), (0.049, True), (0.06, False)):
        p = tcp + [0.0, 0.0, -(0.015 + gap)]  # below the pads' tips
        d = separation(np.vstack([own, p]), scene)
        assert d == pytest.approx(gap, abs=1e-6)
        assert (d < BAND) is near


def test_the_held_object_is_subtracted_and_watched(gripper):
    gripper.set(np.r_[READY, 0.02, 0.02])  # holding something 4 cm wide
    box = held_box(gripper.tcp_pose(), 0.04)
    scene = Scene(-1.0, gripper.boxes_in_world(), [box])
    rng = np.random.default_rng(2)
    inside = (rng.uniform(-1, 1, (300, 3)) * box[1]) @ box[0].rotation().matrix().T
    inside += box[0].translation()
    assert separation(inside, scene) == math.inf
    X_WH, half = box
    below = X_WH @ np.array([0.0, 0.0, half[2] + 0.03])  # 3 cm under the held object
    assert separation(below[None, :], scene) == pytest.approx(0.03, abs=1e-6)
    # without the held object the same point is farther: from the gripper alone
    assert separation(below[None, :], Scene(-1.0, scene.gripper)) > BAND


def test_the_learnt_static_scene_is_not_foreign_something_new_is(gripper):
    boxes = at_ready(gripper)
    tcp = gripper.tcp_pose().translation()
    scene = Scene(0.0, boxes)
    block = tcp + np.array([[0.0, 0.0, -0.04], [0.01, 0.0, -0.04]])  # an object being picked
    background = learn_background(np.zeros(0, np.int64), block, scene)
    known = Scene(0.0, boxes, background=background)
    assert separation(block, known) == math.inf
    hand = tcp + np.array([[0.0, 0.04, -0.03]])
    assert separation(np.vstack([block, hand]), known) < BAND
    assert separation(block, scene, too_close=3) == 0.0  # something under the near plane


def test_an_object_let_go_by_the_robot_joins_the_static_scene(gripper):
    gripper.set(np.r_[READY, 0.02, 0.02])
    box = held_box(gripper.tcp_pose(), 0.04)
    gripper.set(np.r_[READY, 0.04, 0.04])  # the fingers opened: nothing held any more
    scene = Scene(-1.0, gripper.boxes_in_world())
    X_WH, half = box
    placed = X_WH @ np.array([[0.0, 0.0, -0.02], [0.01, 0.0, -0.015]]).T  # in the old box
    hand = X_WH @ np.array([0.0, 0.0, half[2] + 0.02])  # 2 cm under it
    assert separation(placed.T, scene) < BAND  # foreign until learnt
    background = learn_released(np.zeros(0, np.int64), np.vstack([placed.T, hand]), box)
    known = Scene(-1.0, scene.gripper, background=background)
    assert separation(placed.T, known) == math.inf
    assert separation(np.vstack([placed.T, hand]), known) < math.inf  # the hand is not learnt


def test_in_boxes_with_margin():
    box = (RigidTransform([1.0, 0.0, 0.0]), np.array([0.1, 0.2, 0.3]))
    pts = np.array([[1.099, 0.0, 0.0], [1.104, 0.0, 0.0], [1.106, 0.0, 0.0]])
    assert in_boxes(pts, [box]).tolist() == [True, False, False]
    assert in_boxes(pts, [box], MARGIN).tolist() == [True, True, False]
    assert distance_to_boxes(pts, []) == math.inf


LIMITS = list(zip(ARM.lower, ARM.upper, strict=True))


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    q=st.tuples(*(st.floats(lo, hi) for lo, hi in LIMITS)),
    opening=st.floats(0.0, 0.08),
    rpy=st.tuples(*(st.floats(-math.pi, math.pi) for _ in range(3))),
    gap=st.floats(0.012, 0.045),
    seed=st.integers(0, 2**16),
)
def test_random_poses_own_points_vanish_a_foreign_point_in_the_band_stays(
    gripper, q, opening, rpy, gap, seed
):
    """At any joint angles and finger opening, points on the gripper's and a held object's
    surfaces are subtracted; a point ``gap`` (> the margin) out of the nearest box face, in
    any direction, is measured within the margin of ``gap``."""
    gripper.set(np.r_[q, opening / 2, opening / 2])
    held = [held_box(gripper.tcp_pose(), opening)]
    boxes = gripper.boxes_in_world()
    rng = np.random.default_rng(seed)
    own = surface_points([*boxes, *held], 50, rng)
    scene = Scene(-10.0, boxes, held)
    assert separation(own, scene) == math.inf
    # a point pushed out of a surface point along a random direction, then measured
    direction = RollPitchYaw(*rpy).ToRotationMatrix().matrix()[:, 0]
    p = own[rng.integers(len(own))] + gap * direction
    assume(not in_boxes(p[None, :], [*boxes, *held], MARGIN)[0])
    d = separation(p[None, :], scene)
    truth = distance_to_boxes(p[None, :], [*boxes, *held])
    assert d == pytest.approx(truth) and MARGIN < d <= gap + 1e-9 and d < BAND


def test_budget_fits_the_band_at_100hz_and_80x45():
    b, latency_left = budget()
    assert b.stop_time == pytest.approx(0.1056, abs=1e-3)  # joint 2 braking at 7.5 rad/s^2
    assert b.stop_distance == pytest.approx(0.0185, abs=2e-4)
    assert b.closing == pytest.approx(1.55 * 0.01)
    assert b.pixel == pytest.approx(0.0052, abs=1e-4)
    assert b.used < b.band and latency_left == pytest.approx(0.007, abs=5e-4)
    slow, left = budget(period=0.03)  # 33 Hz would not do
    assert slow.used > slow.band and left < 0
