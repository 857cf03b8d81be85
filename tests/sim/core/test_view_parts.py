"""One object in pieces, one in a person's hand (`tamp.sim.core.view_parts`), on synthetic
depth images of a camera looking straight down at the table (no simulation)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from pydrake.math import RigidTransform, RotationMatrix

from tamp.sim.core.instances import ObjectDetection, located
from tamp.sim.core.view_parts import joined_fragments, touched_by_hand

K = (231.4, 231.4, 159.5, 89.5)
HEIGHT = 0.40  # the camera 40 cm above the table
X_WC = RigidTransform(RotationMatrix.MakeXRotation(np.pi), [0.5, 0.0, HEIGHT])  # looks down
SPANS = {"saw": 0.30, "scissors": 0.20, "screw": 0.08}


def _table() -> np.ndarray:
    return np.full((180, 320), HEIGHT, np.float32)


def _det(cls: str, mask: np.ndarray, depth: np.ndarray) -> ObjectDetection:
    where = located(mask, depth, K, X_WC)
    assert where is not None
    return ObjectDetection(cls, 0.9, mask, **where)


def _bar(depth: np.ndarray, rows: slice, cols: slice, top: float) -> np.ndarray:
    """A box whose top is ``top`` above the table over ``rows`` x ``cols``: its mask."""
    mask = np.zeros(depth.shape, bool)
    mask[rows, cols] = True
    depth[mask] = HEIGHT - top
    return mask


def test_a_saw_cut_in_two_by_what_the_gripper_holds_is_one_saw():
    """Fig. 9 with the learned detector: the held scissors hid a saw's middle, the two ends
    became two saws and the second stayed remembered in W^B for the rest of the run."""
    depth = _table()
    left = _bar(depth, slice(80, 95), slice(100, 140), 0.01)
    right = _bar(depth, slice(80, 95), slice(160, 200), 0.01)
    depth[60:120, 140:160] = 0.09  # the held object, 9 cm from the camera
    found = [_det("saw", left, depth), _det("saw", right, depth)]
    out = joined_fragments(found, depth, SPANS, K, X_WC)
    assert len(out) == 1 and out[0].cls == "saw"
    assert out[0].pixels == left.sum() + right.sum()
    middle = (found[0].centroid[0] + found[1].centroid[0]) / 2
    assert abs(out[0].centroid[0] - middle) < 0.005  # its middle, between the two pieces


def test_two_saws_with_bare_table_between_them_stay_two():
    depth = _table()
    left = _bar(depth, slice(80, 95), slice(100, 140), 0.01)
    right = _bar(depth, slice(80, 95), slice(160, 200), 0.01)
    found = [_det("saw", left, depth), _det("saw", right, depth)]
    assert len(joined_fragments(found, depth, SPANS, K, X_WC)) == 2


def test_pieces_longer_than_one_object_or_with_an_object_between_stay_apart():
    depth = _table()
    left = _bar(depth, slice(80, 90), slice(120, 140), 0.005)
    right = _bar(depth, slice(80, 90), slice(160, 180), 0.005)
    depth[60:120, 140:160] = 0.09
    screws = [_det("screw", left, depth), _det("screw", right, depth)]
    # together 10 cm: more than one 8 cm screw
    assert len(joined_fragments(screws, depth, SPANS, K, X_WC)) == 2
    # a third object lying between two pieces, no higher than they are, is no occluder
    depth = _table()
    left = _bar(depth, slice(80, 95), slice(100, 140), 0.01)
    right = _bar(depth, slice(80, 95), slice(160, 200), 0.01)
    middle = _bar(depth, slice(60, 120), slice(140, 160), 0.012)
    found = [_det("saw", left, depth), _det("saw", right, depth), _det("wrench", middle, depth)]
    assert len(joined_fragments(found, depth, SPANS, K, X_WC)) == 3


def test_scissors_under_a_hammers_handle_are_one_pair():
    """Fig. 9 with the learned detector: the hammer put down across the scissors' blade
    left the blade's tip beside the handle, and the scissors were counted twice."""
    depth = _table()
    tip = _bar(depth, slice(80, 90), slice(125, 135), 0.014)
    rest = _bar(depth, slice(80, 90), slice(145, 165), 0.014)
    handle = _bar(depth, slice(40, 140), slice(135, 145), 0.04)
    found = [
        _det("scissors", tip, depth),
        _det("scissors", rest, depth),
        _det("hammer", handle, depth),
    ]
    out = joined_fragments(found, depth, SPANS, K, X_WC)
    assert sorted(d.cls for d in out) == ["hammer", "scissors"]


@settings(max_examples=25, deadline=None)
@given(gap=st.integers(3, 30), top=st.floats(0.003, 0.03), occluder=st.floats(0.05, 0.3))
def test_pieces_are_joined_exactly_when_an_occluder_lies_between(gap, top, occluder):
    depth = _table()
    left = _bar(depth, slice(80, 95), slice(120 - gap, 140 - gap), top)
    right = _bar(depth, slice(80, 95), slice(160, 180), top)
    found = [_det("saw", left, depth), _det("saw", right, depth)]
    assert len(joined_fragments(found, depth, SPANS, K, X_WC)) == 2  # bare table between
    depth[60:120, 140 - gap : 160] = occluder
    assert len(joined_fragments(found, depth, SPANS, K, X_WC)) == 1


def test_an_object_the_hand_holds_is_touched_one_it_reaches_over_is_not():
    """Fig. 9 with the learned detector: the wrench the person carried over W^A was named a
    hammer and counted as a second one. What the hand touches is in the person's hand."""
    depth = _table()
    hand = _bar(depth, slice(70, 110), slice(150, 220), 0.06)  # fingers 6 cm up
    held = _bar(depth, slice(85, 95), slice(120, 150), 0.055)  # a wrench in them
    below = _bar(depth, slice(110, 120), slice(160, 200), 0.01)  # under the arm's edge
    far = _bar(depth, slice(20, 30), slice(20, 60), 0.01)
    found = [_det("hammer", held, depth), _det("saw", below, depth), _det("saw", far, depth)]
    assert touched_by_hand(found, [hand], depth) == [True, False, False]
    assert touched_by_hand(found, [], depth) == [False, False, False]
