"""Where the workcell's time goes (`tamp.sim.lots.station.cell_parts`), the grasp network's
thread scope, and benchmarks/lots_workcell.py: its seeded scenes, and one pick per network
(slow)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import torch

from tamp.grasp.networks import NETWORKS
from tamp.sim.core.timing import Stopwatch
from tamp.sim.lots.catalogue import CLASSES
from tamp.sim.lots.scenario import load_cell_scenario, rectangles_overlap
from tamp.sim.lots.station import cell_parts

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def bench():
    path = ROOT / "benchmarks" / "lots_workcell.py"
    spec = importlib.util.spec_from_file_location("lots_workcell_bench", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cell_parts_do_not_count_the_network_twice():
    cell = SimpleNamespace(
        skills=SimpleNamespace(control=Stopwatch(5.0, 3.0, 100)),
        planner=SimpleNamespace(network=Stopwatch(2.0, 1.0, 4)),
        perception=SimpleNamespace(render=Stopwatch(0.5, 0.2, 5), analysis=Stopwatch()),
    )
    parts = cell_parts(cell)
    assert parts["skills"].wall == 3.0 and parts["skills"].cpu == 2.0
    assert parts["network"] is cell.planner.network
    assert set(parts) == {"render", "perception", "network", "skills"}


def test_network_thread_scope_restores_torch_threads():
    from tamp.sim.core.threads import INFERENCE_THREADS, torch_threads

    before = torch.get_num_threads()
    with torch_threads(INFERENCE_THREADS):
        assert torch.get_num_threads() == INFERENCE_THREADS == 1
    assert torch.get_num_threads() == before


def test_scenes_are_seeded_valid_and_cycle_through_the_task_classes(bench):
    base = load_cell_scenario("tower")
    scenes = [bench.make_scene(base, s) for s in range(len(bench.TARGETS))]
    assert [t for _, t, _ in scenes] == list(bench.TARGETS)
    again = bench.make_scene(base, 3)
    assert again[0].objects == scenes[3][0].objects  # the same seed, the same scene
    assert scenes[0][0].objects != bench.make_scene(base, 8)[0].objects  # same class, new pose
    w = base.workspaces["A"]
    for scene, target, uid in scenes:
        assert scene.plant == base.plant and scene.grasp == base.grasp
        a, b = scene.objects
        assert a.id == uid and a.cls == target and b.cls != target
        corners = [CLASSES[o.cls].footprint.corners(*o.xy, o.yaw) for o in (a, b)]
        assert all(w.contains(*c) for cs in corners for c in cs)
        assert not rectangles_overlap(*corners, gap=0.01)


@pytest.mark.slow
def test_one_pick_per_network_on_the_plant(bench):
    base = load_cell_scenario("tower")
    scene, target, uid = bench.make_scene(base, 4)  # a tower body
    picks = {}
    for net in NETWORKS:
        p = picks[net] = bench.run_pick(scene, target, uid, net, timeout=40.0)
        assert p["network_calls"] >= 4 and p["frames"] >= 5
        assert p["success"] == (p["status"] == "SUCCESS" and p["target_z"] > bench.LIFTED)
        assert 0 < p["sim_time"] <= 41.0 and p["cpu_time"] > 0
        parts = p["parts"]
        assert parts["network"]["calls"] == p["network_calls"]
        assert parts["physics"]["cpu"] > 0
        assert sum(r["cpu_share"] for r in parts.values()) == pytest.approx(1.0, abs=0.01)
    assert picks["hrgnet"]["success"]  # the benchmark's scene 4: HRG-Net lifts the body


def test_views_probe_paints_only_the_table_plane_and_counts_grasps_on_the_mask():
    path = ROOT / "benchmarks" / "workcell_views.py"
    spec = importlib.util.spec_from_file_location("workcell_views_bench", path)
    views = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(views)
    rgb = np.zeros((20, 20, 3), np.uint8)
    rgb[...] = (140, 190, 140)  # a green mat
    depth = np.full((20, 20), 0.30, np.float32)
    depth[5:10, 5:15] = 0.28  # an object 2 cm tall
    rgb[5:10, 5:15] = (200, 40, 40)
    out = dict(views.variants(rgb, depth))
    assert np.array_equal(out["as rendered"], rgb)
    plain = out["table beige"]
    assert np.all(plain[5:10, 5:15] == (200, 40, 40))  # the object keeps its colour
    assert np.all(plain[0:5] == views.BEIGE) and np.all(plain[15:] == views.BEIGE)
    assert np.all(out["grey"][..., 0] == out["grey"][..., 2])
    mask = depth < 0.29
    from tamp.grasp.predict import PredictedGrasp

    grasps = [PredictedGrasp(7.0, 6.0, 0.0, 10.0, 1.0), PredictedGrasp(1.0, 1.0, 0.0, 10.0, 1.0),
              PredictedGrasp(50.0, 6.0, 0.0, 10.0, 1.0)]  # fmt: skip
    assert views.on_target(grasps, mask) == 1
