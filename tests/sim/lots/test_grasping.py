"""Where the pads meet the target (`tamp.sim.lots.grasping.seated`): pixel geometry only, no
network, no simulation. The cases are the Fig. 10 narrative's: a diagonal grasp on the
peak's square base and one at its edge (the peak turned in the pads and fell), a grasp along
a body's full length (a pad landed on its top and tipped it)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tamp.grasp.rect import GraspRect
from tamp.sim.lots.grasping import antipodal, centred, chord, seated, snap_to_mask


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


def test_a_grasp_at_the_edge_along_the_jaws_is_not_centred():
    """The Fig. 10 peak: held 2.3 cm off the centre of its 5 cm base, it turned in the pads."""
    m = _square()
    assert centred(_grasp(90, 90, 0), m)
    assert centred(_grasp(90, 96, 0), m)  # 6 px of a 40 px extent: within 20 %
    assert not centred(_grasp(90, 105, 0), m)  # 15 px off: near the edge
    assert centred(_grasp(105, 90, 0), m)  # off along the closing line: `seated` re-centres


def test_seated_centres_on_the_whole_chord_and_needs_the_opening():
    # a 70 x 40 px body at 35 deg; the network's grasp closes along its length, 25 px off
    # the centre along the closing line, with a 30 px predicted opening
    m = _box(70, 40, 35)
    a = math.radians(35)
    along = _grasp(90 - 25 * math.cos(a), 90 + 25 * math.sin(a), 35, width=30.0)
    snapped = snap_to_mask(along, m)
    assert np.hypot(snapped.x - 90, snapped.y - 90) > 5  # snap's reach ends inside the body
    s = seated(along, m, opening=100.0)
    assert s is not None and (s.x, s.y) == pytest.approx((90, 90), abs=1.0)
    assert s.angle == along.angle  # the network's angle is kept
    assert seated(along, m, opening=65.0) is None  # 70 px long: the pads would land on it
    across = _grasp(90, 90, 35 + 90)
    assert seated(across, m, opening=65.0) is not None  # across its 40 px width
