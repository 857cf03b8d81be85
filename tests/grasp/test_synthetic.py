"""The Drake-rendered synthetic set: geometry of the grasps, projection, determinism, and
that the Jacquard loader reads what the generator writes."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.grasp.objects import MAX_OPENING, PRIMITIVES, TOOLS, grasp_world, make_object
from tamp.grasp.pinhole import pixel_to_camera
from tamp.grasp.synthetic import grasp_rectangle, look_at, project


@given(st.sampled_from(TOOLS + PRIMITIVES), st.integers(0, 10_000))
def test_object_grasps_fit_the_gripper_and_sit_on_top(kind, seed):
    obj = make_object(kind, np.random.default_rng(seed))
    assert obj.grasps, kind
    tops = [p.top for p in obj.parts]
    for g in obj.grasps:
        assert 0 < g.opening <= MAX_OPENING
        assert min(tops) - 1e-9 <= g.center[2] <= max(tops) + 1e-9
        assert math.hypot(g.center[0], g.center[1]) <= obj.radius + 1e-9


@given(
    st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(0.25, 0.5), st.floats(-3, 3),
    st.floats(-0.05, 0.05), st.floats(-0.05, 0.05),
)  # fmt: skip
def test_projection_of_a_top_down_camera(x, y, h, yaw, dx, dy):
    """A camera straight above (x, y) sees that point at the image centre, and a world
    offset shows up scaled by f / h, turned by the camera yaw."""
    K = np.array([[100.0, 0, 50], [0, 100.0, 50], [0, 0, 1]])
    X = np.eye(4)
    X[:3, :3] = look_at(np.array([x, y, h]), np.array([x, y, 0.0]), yaw)
    X[:3, 3] = [x, y, h]
    (u, v), (u2, v2) = project(K, X, np.array([[x, y, 0.0], [x + dx, y + dy, 0.0]]))
    assert math.isclose(u, 50, abs_tol=1e-9) and math.isclose(v, 50, abs_tol=1e-9)
    assert math.isclose(
        math.hypot(u2 - u, v2 - v), 100 * math.hypot(dx, dy) / h, rel_tol=1e-6, abs_tol=1e-9
    )
    # a grasp of opening 4 cm closing along world x, seen from h, spans 100 * 0.04 / h px
    rect = grasp_rectangle(K, X, np.array([x, y, 0.0]), 0.0, 0.04, 0.02)
    assert math.isclose(rect.width, 4.0 / h, rel_tol=1e-6)


def test_grasp_world_turns_with_the_object():
    obj = make_object("hammer", np.random.default_rng(0))
    g = obj.grasps[0]
    c0, y0 = grasp_world(g, 0.0, 0.0, 0.0)
    c1, y1 = grasp_world(g, 0.1, 0.2, math.pi / 2)
    assert np.allclose(c1[:2], [0.1 - c0[1], 0.2 + c0[0]])
    assert math.isclose(y1 - y0, math.pi / 2)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory) -> Path:
    from tamp.grasp.synthetic import SynthConfig, generate

    out = tmp_path_factory.mktemp("synth")
    summary = generate(out / "a", 3, SynthConfig(size=64, views=2, seed=7), progress=False)
    # the same set rendered by two processes (chunks of scenes): the same files
    twice = generate(out / "b", 3, SynthConfig(size=64, views=2, seed=7), progress=False, jobs=2)
    assert summary["images"] > 0 and summary["grasps"] >= summary["images"]
    assert twice == summary
    return out


@pytest.mark.slow
def test_deterministic_with_a_seed_in_one_or_two_processes(rendered: Path):
    files_a = sorted(p.relative_to(rendered / "a") for p in (rendered / "a").rglob("*.*"))
    files_b = sorted(p.relative_to(rendered / "b") for p in (rendered / "b").rglob("*.*"))
    assert files_a == files_b
    for rel in files_a:
        assert (rendered / "a" / rel).read_bytes() == (rendered / "b" / rel).read_bytes()


@pytest.mark.slow
def test_grasp_centres_lie_on_objects_above_the_table(rendered: Path):
    from tamp.grasp import formats

    for grasps in (rendered / "a").rglob("*_grasps.txt"):
        prefix = str(grasps)[: -len("_grasps.txt")]
        depth = formats.read_depth_tiff(prefix + "_perfect_depth.tiff")
        cam = json.loads(Path(prefix + "_camera.json").read_text())
        K, X = np.array(cam["K"]), np.array(cam["X_WC"])
        for r in formats.read_jacquard_grasps(grasps):
            z = depth[int(round(r.y)), int(round(r.x))]
            # back-project: the point is above the table top (z = 0) by the object height
            pc = np.array([(r.x - K[0, 2]) * z / K[0, 0], (r.y - K[1, 2]) * z / K[1, 1], z])
            pw = X[:3, :3] @ pc + X[:3, 3]
            assert 0.003 < pw[2] < 0.1


@pytest.mark.slow
def test_loader_reads_the_generated_set(rendered: Path):
    from tamp.grasp.datasets import GraspDataset

    ds = GraspDataset("jacquard", rendered / "a", size=32)
    assert len(ds) > 0
    assert len(set(ds.groups())) == len({p.parent for p in (rendered / "a").rglob("*_RGB.png")})
    s = ds.load(0)
    assert s.y[0].sum() > 0


def test_mats_change_the_colour_under_the_objects_and_nothing_else(tmp_path: Path):
    """``table: mats`` (the LOTS workcell's coloured workspace mats): the same scenes, grasps
    and depth (within the mat's 1 mm) as the plain set of the same seed; only colours differ,
    and where they differ the camera sees the table plane, not an object."""
    from tamp.grasp import formats
    from tamp.grasp.synthetic import SynthConfig, generate

    plain = generate(tmp_path / "p", 4, SynthConfig(size=48, views=1, seed=3), progress=False)
    mats = generate(
        tmp_path / "m", 4, SynthConfig(size=48, views=1, seed=3, table="mats"), progress=False
    )
    assert mats == plain
    recoloured = 0
    for grasps in sorted((tmp_path / "p").rglob("*_grasps.txt")):
        rel = grasps.relative_to(tmp_path / "p")
        assert grasps.read_text() == (tmp_path / "m" / rel).read_text()
        prefix_p = str(grasps)[: -len("_grasps.txt")]
        prefix_m = str(tmp_path / "m" / rel)[: -len("_grasps.txt")]
        dp = formats.read_depth_tiff(prefix_p + "_perfect_depth.tiff")
        dm = formats.read_depth_tiff(prefix_m + "_perfect_depth.tiff")
        assert np.nanmax(np.abs(dp - dm)) <= 0.0011
        changed = np.any(
            formats.read_rgb(prefix_p + "_RGB.png") != formats.read_rgb(prefix_m + "_RGB.png"), 2
        )
        if changed.any():
            recoloured += 1
            # the recoloured pixels back-projected: on the table plane (z = 0), not on objects
            cam = json.loads(Path(prefix_m + "_camera.json").read_text())
            K, X = np.asarray(cam["K"]), np.asarray(cam["X_WC"])
            vs, us = np.nonzero(changed)
            p_C = pixel_to_camera(us, vs, dm[vs, us], (K[0, 0], K[1, 1], K[0, 2], K[1, 2]))
            z_W = (X[:3, :3] @ p_C + X[:3, 3:4])[2]
            # (objects' outline pixels blend with what lies beside them: a few change too)
            assert np.mean(np.abs(z_W) < 0.003) > 0.9
    assert recoloured >= 2  # three scenes in four get a mat
    with pytest.raises(ValueError, match="table"):
        generate(tmp_path / "x", 1, SynthConfig(table="green"), progress=False)
