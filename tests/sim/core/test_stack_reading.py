"""Reading a declared stack by its heights (`tamp.sim.core.stack_reading`): a camera straight
above a tower of boxes, the detections as a learned detector gives them."""

import numpy as np
import pytest

from tamp.sim.core.instances import ObjectDetection, located
from tamp.sim.core.stack_reading import StackModel, columns, read_stack, remembered_in_columns

K = (200.0, 200.0, 79.5, 44.5)
W, H = 160, 90
#: camera 0.5 m over the table's origin, looking straight down (camera y = -world y)
X_WC = np.array([[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0.5], [0, 0, 0, 1]], float)
TOWER = StackModel("B", ("bottom", "body", "peak"), (0.04, 0.05, 0.045))


def world_xy() -> tuple[np.ndarray, np.ndarray]:
    """The table point (x, y) under each pixel."""
    vs, us = np.mgrid[0:H, 0:W]
    x = (us - K[2]) * 0.5 / K[0]
    y = -(vs - K[3]) * 0.5 / K[1]
    return x, y


def scene(boxes: list[tuple[float, float, float, float, float, float]]) -> np.ndarray:
    """Depth of boxes (x0, x1, y0, y1, z0, z1) seen from above: each pixel sees the highest
    top over it (the rays are near vertical: the sides are not drawn)."""
    x, y = world_xy()
    top = np.zeros((H, W))
    for x0, x1, y0, y1, _, z1 in boxes:
        inside = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
        top = np.where(inside, np.maximum(top, z1), top)
    return 0.5 - top


def detection(cls: str, mask: np.ndarray, depth: np.ndarray) -> ObjectDetection:
    where = located(mask, depth, K, X_WC)
    assert where is not None
    return ObjectDetection(cls, 0.9, mask, **where)


def at_height(depth: np.ndarray, z: float) -> np.ndarray:
    return np.abs((0.5 - depth) - z) < 1e-6


def body_on_bottom(cx: float = 0.0) -> np.ndarray:
    return scene(
        [
            (cx - 0.03, cx + 0.03, -0.03, 0.03, 0.0, 0.04),
            (cx - 0.035, cx + 0.035, -0.02, 0.02, 0.04, 0.09),
        ]  # fmt: skip
    )


def test_a_bottoms_two_rim_strips_and_an_unknown_body_are_read_as_bottom_and_body():
    """The tower campaign's double count: the bottom seen either side of the body on it as two
    detections named ``bottom``, the body ``unknown``: one bottom and one body."""
    depth = body_on_bottom()
    rim = at_height(depth, 0.04)
    _, y = world_xy()
    found = [
        detection("bottom", rim & (y > 0), depth),
        detection("bottom", rim & (y < 0), depth),
        detection("unknown", at_height(depth, 0.09), depth),
    ]
    out = read_stack(found, TOWER, depth, K, X_WC)
    assert sorted(d.cls for d in out) == ["body", "bottom"]
    bottom = next(d for d in out if d.cls == "bottom")
    assert bottom.pixels == int(rim.sum())
    assert abs(bottom.centroid[0]) < 0.005 and abs(bottom.centroid[1]) < 0.005


def test_a_level_seen_by_one_strip_is_placed_under_the_top_ones_middle():
    """Only one of the bottom's strips in view (the other cut by the image's edge): the
    bottom is where its remembered track is, under the body's middle, not 2.5 cm aside."""
    depth = body_on_bottom()
    _, y = world_xy()
    strip = at_height(depth, 0.04) & (y > 0)
    found = [detection("unknown", strip, depth), detection("body", at_height(depth, 0.09), depth)]
    assert abs(found[0].centroid[1] - 0.025) < 0.003
    out = read_stack(found, TOWER, depth, K, X_WC)
    bottom = next(d for d in out if d.cls == "bottom")
    assert bottom.pixels == int(strip.sum())
    assert abs(bottom.centroid[1]) < 0.003 and abs(bottom.centroid[2] - 0.04) < 0.003


def test_a_peak_on_the_tower_is_the_third_level():
    depth = scene(
        [
            (-0.03, 0.03, -0.03, 0.03, 0.0, 0.04),
            (-0.035, 0.035, -0.02, 0.02, 0.04, 0.09),
            (-0.015, 0.015, -0.015, 0.015, 0.09, 0.135),
        ]  # fmt: skip
    )
    found = [
        detection("unknown", at_height(depth, 0.04) | at_height(depth, 0.09), depth),
        detection("unknown", at_height(depth, 0.135), depth),
    ]
    out = read_stack(found, TOWER, depth, K, X_WC)
    assert sorted(d.cls for d in out) == ["body", "bottom", "peak"]


def test_what_is_not_a_stack_is_left_as_the_detector_named_it():
    depth = body_on_bottom()
    whole = depth < 0.5 - 1e-6
    # one object showing one level: a tall unknown block is not told from a tower
    tall = scene([(-0.03, 0.03, -0.03, 0.03, 0.0, 0.09)])
    lone = [detection("unknown", tall < 0.5 - 1e-6, tall)]
    assert read_stack(lone, TOWER, tall, K, X_WC) == lone
    # a column holding another task class
    car = [detection("toy_car", at_height(depth, 0.09), depth),
           detection("unknown", at_height(depth, 0.04), depth)]  # fmt: skip
    assert [d.cls for d in read_stack(car, TOWER, depth, K, X_WC)] == ["toy_car", "unknown"]
    # a top at no stack height (a 6.5 cm pile)
    low = scene([(-0.03, 0.03, -0.03, 0.03, 0.0, 0.04), (-0.02, 0.02, -0.02, 0.02, 0.04, 0.065)])
    two = [detection("unknown", at_height(low, 0.04), low),
           detection("bottom", at_height(low, 0.065), low)]  # fmt: skip
    assert read_stack(two, TOWER, low, K, X_WC) == two
    # outside the stack's workspace
    out = read_stack(
        [detection("unknown", whole, depth)], TOWER, depth, K, X_WC, inside=lambda p: False
    )
    assert [d.cls for d in out] == ["unknown"]


def test_two_towers_side_by_side_are_two_columns():
    depth = np.minimum(body_on_bottom(-0.06), body_on_bottom(0.06))
    x, _ = world_xy()
    found = [
        detection("unknown", (depth < 0.5 - 1e-6) & (x < 0), depth),
        detection("body", at_height(depth, 0.09) & (x > 0), depth),
        detection("unknown", at_height(depth, 0.04) & (x > 0), depth),
    ]
    out = read_stack(found, TOWER, depth, K, X_WC)
    assert sorted(d.cls for d in out) == ["body", "body", "bottom", "bottom"]


def test_columns_join_points_within_the_radius_through_others():
    assert columns([(0, 0), (0.03, 0), (0.06, 0), (0.2, 0)]) == [[0, 1, 2], [3]]
    assert columns([]) == []
    # a lower part's side seen with the part on it (both rise above the first level): 4.9 cm
    # off the tower's middle is still the tower; a part of the first level's height there is not
    aside = [(0.0, 0.0), (0.049, 0.0)]
    assert columns(aside, tall=[True, True]) == [[0, 1]]
    assert columns(aside, tall=[True, False]) == [[0], [1]]
    assert columns([(0.0, 0.0), (0.095, 0.0)], tall=[True, True]) == [[0], [1]]


def test_a_stack_model_needs_one_height_per_class():
    assert TOWER.tops == pytest.approx((0.04, 0.09, 0.135))
    assert TOWER.levels_at(0.095) == 2 and TOWER.levels_at(0.065) == 0
    with pytest.raises(ValueError, match="one height per class"):
        StackModel("B", ("bottom", "body"), (0.04,))


def test_a_part_remembered_aside_is_the_level_read_in_its_column():
    """A bottom remembered where its strip put it (2.5 cm off) is the bottom read now under
    the body's middle; a bottom remembered beside the tower, or a body remembered there, is
    not."""
    from tamp.sim.core.messages import Seen

    remembered = [
        Seen(6, "bottom", (0.0, 0.025, 0.04)),
        Seen(7, "bottom", (0.0, 0.09, 0.04)),
        Seen(8, "peak", (0.0, 0.0, 0.11)),
    ]
    levels = [("bottom", (0.0, 0.0, 0.04)), ("body", (0.0, 0.0, 0.09))]
    assert remembered_in_columns(remembered, levels) == {6}
    assert remembered_in_columns(remembered, []) == frozenset()
