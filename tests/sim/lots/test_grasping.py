"""Where the pads meet the target (`tamp.sim.lots.grasping.seated`): pixel geometry only, no
network, no simulation. The cases are the Fig. 10 narrative's: a diagonal grasp on the
peak's square base and one at its edge (the peak turned in the pads and fell), a grasp along
a body's full length (a pad landed on its top and tipped it); and a saw's handle (Fig. 9:
taken by the handle, far from its centre of mass, and carried)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tamp.grasp.rect import GraspRect
from tamp.sim.lots.grasping import (
    GraspCandidate,
    antipodal,
    chord,
    near_grasp,
    seated,
    snap_to_mask,
    supported,
)


def _square(size: int = 40) -> np.ndarray:
    m = np.zeros((180, 180), bool)
    lo = 90 - size // 2
    m[lo : lo + size, lo : lo + size] = True  # rows 70..109, cols 70..109
    return m


def _box(length: float, width: float, deg: float) -> np.ndarray:
    """A length x width box centred at (90, 90), its long axis along GraspRect angle ``deg``."""
    a = math.radians(deg)
    e1 = np.array([math.cos(a), -math.sin(a)])  # the GraspRect direction of angle deg
    e2 = np.array([math.sin(a), math.cos(a)])
    yy, xx = np.mgrid[0:180, 0:180]
    u = (xx - 90) * e1[0] + (yy - 90) * e1[1]
    v = (xx - 90) * e2[0] + (yy - 90) * e2[1]
    return (np.abs(u) < length / 2) & (np.abs(v) < width / 2)


def _grasp(x: float, y: float, deg: float, width: float = 50.0) -> GraspRect:
    return GraspRect(x, y, math.radians(deg), width, width / 2)


@pytest.mark.parametrize("deg", [0, 10, 20, 80, 90, 100])
def test_closing_across_parallel_faces_is_antipodal(deg):
    assert antipodal(_grasp(90, 90, deg), _square())


@pytest.mark.parametrize("deg", [30, 35, 43, 60, 120])
@pytest.mark.parametrize("y", [90, 96])
def test_closing_diagonally_across_a_square_is_not(deg, y):
    """The Fig. 10 peak: closing at 43 deg on its square base, the pads 45 deg off the faces'
    normals (outside the friction cone's margin)."""
    assert not antipodal(_grasp(90, y, deg), _square())


def test_chord_ends_where_the_closing_line_leaves_the_mask():
    lo, hi = chord(_grasp(90, 80, 0), _square())  # cols 70..109 along x from x = 90
    assert (lo, hi) == (pytest.approx(-20, abs=0.5), pytest.approx(19, abs=0.5))
    assert chord(_grasp(30, 30, 0), _square()) is None  # centre off the target


def test_a_pad_past_the_end_of_a_face_is_not_supported():
    """The Fig. 10 peak: a grasp at the edge of its base along the jaws touched the face with
    a corner of each pad; it slipped after the lift."""
    m = _square()  # 40 px; a pad half-width of 8 px
    assert supported(_grasp(90, 90, 0), m, 8)
    assert supported(_grasp(90, 100, 0), m, 8)  # pads on rows 92..108: still on the faces
    assert not supported(_grasp(90, 105, 0), m, 8)  # a pad reaches past the corner
    # a handle: a 60 x 20 px bar joined to a 40 px wide blade (a saw from above); closing
    # across the handle's middle is supported, across the step to the blade is not
    saw = np.zeros((180, 180), bool)
    saw[80:100, 20:80] = True
    saw[70:110, 80:160] = True
    assert supported(_grasp(50, 90, 90), saw, 8)
    assert not supported(_grasp(76, 90, 90), saw, 8)


def test_seated_centres_on_the_whole_chord_and_needs_the_opening():
    # a 70 x 40 px body at 35 deg; the network's grasp closes along its length, 25 px off
    # the centre along the closing line, with a 30 px predicted opening
    m = _box(70, 40, 35)
    a = math.radians(35)
    along = _grasp(90 - 25 * math.cos(a), 90 + 25 * math.sin(a), 35, width=30.0)
    snapped = snap_to_mask(along, m)
    assert np.hypot(snapped.x - 90, snapped.y - 90) > 5  # snap's reach ends inside the body
    s = seated(along, m, opening=100.0, half_pad=8)
    assert s is not None and (s.x, s.y) == pytest.approx((90, 90), abs=1.0)
    assert s.angle == along.angle  # the network's angle is kept
    assert (
        seated(along, m, opening=65.0, half_pad=8) is None
    )  # 70 px long: the pads would land on it
    across = _grasp(90, 90, 35 + 90)
    assert seated(across, m, opening=65.0, half_pad=8) is not None  # across its 40 px width


def _scene(neighbour_u: int):
    """A 180 px crop seen from 0.4 m straight above the table: a 20 x 30 px target block 3 cm
    high in the centre, and a 2 cm high neighbour (10 x 30 px) whose left edge is at
    ``neighbour_u`` (the closing line runs along u)."""
    from pydrake.math import RigidTransform

    from tamp.sim.core.messages import Detection, TargetCrop
    from tamp.sim.lots.kinematics import down

    depth = np.full((180, 180), 0.4, np.float32)  # the table
    mask = np.zeros((180, 180), bool)
    mask[75:105, 80:100] = True
    depth[mask] = 0.37
    depth[75:105, neighbour_u : neighbour_u + 10] = 0.38
    det = Detection(1, "body", int(mask.sum()), 89.5, 89.5, 0.37)
    crop = TargetCrop(det, (0, 0), np.zeros((180, 180, 3), np.uint8), depth, mask)
    X_WC = RigidTransform(down(0.0), [0.5, 0.25, 0.4]).GetAsMatrix4()
    return crop, (231.0, 231.0, 89.5, 89.5), X_WC


@pytest.mark.parametrize(("neighbour_u", "clear"), [(112, False), (150, True)])
def test_a_grasp_is_clear_only_without_other_objects_in_the_jaws_sweep(neighbour_u, clear):
    """The jaws open 5 cm to either side (29 px at 0.4 m): a block 5 mm beyond the target's
    edge is caught, one 13 cm away is not; the table itself never counts."""
    from tamp.sim.lots.grasping import clear_of_others

    crop, K, X_WC = _scene(neighbour_u)
    rect = GraspRect(89.5, 89.5, 0.0, 30.0, 10.0)  # closing along u through the centre
    reach = 0.05 * K[0] / 0.37
    assert clear_of_others(rect, crop, K, X_WC, reach, 3.0) is clear
    across = GraspRect(
        89.5, 89.5, math.pi / 2, 30.0, 10.0
    )  # closing along v: the neighbour is beside
    assert clear_of_others(across, crop, K, X_WC, reach, 3.0)


@pytest.mark.parametrize(
    "dx, dyaw_deg, near",
    [
        (0.0, 0.0, True),
        (0.008, 15.0, True),
        (0.0, 180.0, True),
        (0.0, 170.0, True),
        (0.0, -175.0, True),
        (0.012, 0.0, False),
        (0.0, 25.0, False),
        (0.0, 90.0, False),
    ],
)
def test_a_grasp_near_one_that_missed_is_the_same_grasp(dx, dyaw_deg, near):
    """Closing angles count modulo 180 degrees: the two fingers are alike."""
    c = GraspCandidate(0.5 + dx, 0.2, 0.05, math.radians(30 + dyaw_deg), 0.05, 1.0, 0.2)
    assert near_grasp(c, (0.5, 0.2, math.radians(30))) is near
