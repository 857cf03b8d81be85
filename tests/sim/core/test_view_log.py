"""The views kept for a recording (`tamp.sim.core.view_log`) and their Meshcat overlays
(`tamp.sim.core.recording.draw_views`): the geometry alone, then a pick in the LOTS cell."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydrake.math import RigidTransform, RollPitchYaw

from tamp.grasp.pinhole import camera_to_pixel
from tamp.sim.core.view_log import (
    LAST_VIEW_SPAN,
    frustum_segments,
    grasp_segments,
    view_points,
    visible_spans,
)

K = (200.0, 200.0, 159.5, 89.5)


@settings(max_examples=30, deadline=None)
@given(
    st.floats(-0.5, 0.5),
    st.floats(-0.5, 0.5),
    st.floats(0.2, 0.8),
    st.floats(-0.4, 0.4),
    st.floats(-3.1, 3.1),
)
def test_cloud_points_project_back_onto_their_pixels(x, y, z, tilt, yaw):
    """Every point of a view's cloud, seen from the camera that took it, lands on a pixel of
    the sampled grid at the depth the image holds there."""
    X_WC = RigidTransform(RollPitchYaw(np.pi + tilt, 0.0, yaw), [x, y, z])
    rng = np.random.default_rng(0)
    depth = rng.uniform(0.1, 1.0, (180, 320)).astype(np.float32)
    depth[::7, ::5] = np.nan  # no depth there
    pts = view_points(depth, K, X_WC, stride=6, max_depth=0.9)
    p_C = X_WC.inverse().multiply(pts.T.astype(float))
    u, v = camera_to_pixel(p_C, K)
    ui, vi = np.round(u).astype(int), np.round(v).astype(int)
    assert np.allclose(u, ui, atol=1e-3) and np.allclose(v, vi, atol=1e-3)
    assert np.all(ui % 6 == 0) and np.all(vi % 6 == 0)
    assert np.allclose(p_C[2], depth[vi, ui], atol=1e-5)
    expected = np.isfinite(depth[::6, ::6]) & (depth[::6, ::6] <= 0.9)
    assert len(pts) == int(expected.sum())


def test_frustum_reaches_the_image_corners():
    X_WC = RigidTransform(RollPitchYaw(np.pi, 0, 0.3), [0.5, 0.2, 0.5])
    start, end = frustum_segments(X_WC.GetAsMatrix4(), K, (320, 180), depth=0.3)
    assert start.shape == end.shape == (3, 8)
    assert np.allclose(start[:, :4], np.array([[0.5, 0.2, 0.5]]).T)
    far = X_WC.inverse().multiply(end[:, :4])
    assert np.allclose(far[2], 0.3)
    u, v = camera_to_pixel(far, K)
    assert np.allclose(sorted(set(np.round(u, 6))), [0, 320])
    assert np.allclose(sorted(set(np.round(v, 6))), [0, 180])
    # the far rectangle's sides join its corners in order
    assert np.allclose(start[:, 4:], end[:, :4])
    assert np.allclose(end[:, 4:], np.roll(end[:, :4], -1, axis=1))


def test_grasp_segment_is_the_closing_line():
    g = SimpleNamespace(x=0.5, y=0.2, z=0.03, yaw=np.pi / 2, width=0.06)
    a, b = grasp_segments([g])
    assert np.allclose(a[:, 0], [0.5, 0.17, 0.03]) and np.allclose(b[:, 0], [0.5, 0.23, 0.03])
    assert grasp_segments([])[0].shape == (3, 0)


def test_each_view_shows_until_the_next():
    assert visible_spans([1.0, 1.2, 2.0], end=10.0) == [
        (1.0, 1.2),
        (1.2, 2.0),
        (2.0, 2.0 + LAST_VIEW_SPAN),
    ]
    assert visible_spans([3.0], end=3.1) == [(3.0, 3.1)]
    assert visible_spans([], end=1.0) == []


@pytest.mark.slow
def test_a_recorded_pick_draws_every_view_with_its_grasps(tmp_path):
    """A pick in a cell drawn in Meshcat: the log holds every view perception served, each
    with a cloud on the table and the camera above it; the grasp's views carry their target
    and candidates; the recording has one overlay per view (`draw_cell_views`, what
    ``tamp simulate lots --record`` calls)."""
    from pydrake.geometry import Meshcat

    from tamp.sim.core.recording import save_recording, start_recording
    from tamp.sim.lots.driver import CellDriver
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.simulate import draw_cell_views
    from tamp.sim.lots.station import build_station
    from tests.sim.lots.helpers import write_scenario

    path = write_scenario(tmp_path, [{"class": "body", "workspace": "A", "xy": [0, 0], "yaw": 0}])
    meshcat = Meshcat(0)
    cell = build_station(load_cell_scenario(path), meshcat=meshcat)
    assert cell.view_log is not None
    start_recording(cell.visualizer)
    cell.planner.record = True
    d = CellDriver(cell)
    assert d.run("Pick(body)", timeout=90).status.name == "SUCCESS"
    records = cell.view_log.records(cell.view_log.GetMyContextFromRoot(d.context))
    served = cell.perception.state(cell.perception.GetMyContextFromRoot(d.context))
    assert len(records) == served.frames  # every view served, none twice
    assert [r.id for r in records] == sorted({r.id for r in records})
    for r in records:
        assert len(r.points) > 100
        assert np.median(r.points[:, 2]) < 0.1  # mostly the table and what lies on it
        assert r.X_WC[2, 3] > 0.2  # the camera above the table
    grasp_views = [r for r in records if r.target is not None]
    kept = {id(crop): cands for crop, _, cands in cell.planner.history}
    assert len(grasp_views) == len(cell.planner.history) >= 3
    assert all(id(r.target) in kept for r in grasp_views)
    n = draw_cell_views(cell, d.context)
    assert n == len(records)
    for k in range(n):
        assert meshcat.HasPath(f"/views/{k:03d}/cloud")
        assert meshcat.HasPath(f"/views/{k:03d}/frustum")
    assert any(meshcat.HasPath(f"/views/{k:03d}/best") for k in range(n))
    html = save_recording(cell.visualizer, meshcat, tmp_path / "pick.html")
    assert (tmp_path / "pick.html").stat().st_size > 0 and html.endswith("pick.html")
