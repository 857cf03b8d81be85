"""The one pinhole model: projection and back-projection are inverse of each other."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.grasp.pinhole import camera_to_pixel, pixel_to_camera

K = (615.0, 612.0, 320.0, 240.0)  # fx, fy, cx, cy (D435-like at 640 x 480)


def test_principal_point_lies_on_the_optical_axis():
    assert pixel_to_camera(320.0, 240.0, 0.5, K) == pytest.approx([0, 0, 0.5])
    assert camera_to_pixel((0.0, 0.0, 2.0), K) == (320.0, 240.0)
    # 0.1 m right of the axis at 1 m: fx * 0.1 pixels right of cx
    assert camera_to_pixel((0.1, -0.05, 1.0), K) == pytest.approx((381.5, 209.4))


finite = st.floats(-1e3, 1e3, allow_nan=False)


@given(st.lists(st.tuples(finite, finite, st.floats(0.01, 10.0)), min_size=1, max_size=20))
def test_projection_inverts_back_projection_for_arrays(pixels):
    u, v, z = (np.array(c) for c in zip(*pixels, strict=True))
    p = pixel_to_camera(u, v, z, K)
    assert p.shape == (3, len(u))
    assert np.allclose(p[2], z)
    uu, vv = camera_to_pixel(p, K)
    assert np.allclose(uu, u, atol=1e-6) and np.allclose(vv, v, atol=1e-6)


@given(finite, finite)
def test_unit_depth_gives_the_viewing_ray(u, v):
    ray = pixel_to_camera(u, v, 1.0, K)
    for z in (0.3, 2.0):
        assert np.allclose(pixel_to_camera(u, v, z, K), z * ray)
