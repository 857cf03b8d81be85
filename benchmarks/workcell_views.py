"""Do the grasp networks find the target on the LOTS workcell's views, and is the coloured
workspace mat what misleads them? (A diagnostic beside `benchmarks/lots_workcell.py`.)

Records the crops the grasp planner sees during ``Pick`` in seeded single-pick scenes (the
scenes of `benchmarks/lots_workcell.py`, HRG-Net in the loop, the first four views of each
pick), then asks every network for its ``--top`` best grasps on each crop three ways: as
rendered; with the table and mat pixels (depth within 4 mm of the table plane) painted the
synthetic set's beige; and with the colour image in grey. A grasp counts when its centre lies
on the target's mask. The synthetic training set (`tamp grasp synth`) has a beige-grey table;
the workcell's objects lie on pale green and blue mats.

    python benchmarks/workcell_views.py [--scenes 2 1 9] [--networks NET ...]
        [--weights NET=PATH ...] [--top 5]

Prints a table and one JSON line.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")

BEIGE = (200, 190, 170)  # a synthetic-table colour (`tamp.grasp.synthetic.generate`'s range)


def _bench():
    path = Path(__file__).with_name("lots_workcell.py")
    spec = importlib.util.spec_from_file_location("lots_workcell_bench", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def record_views(scene_seeds, views: int = 4) -> dict[int, list[tuple]]:
    """(rgb, depth, mask) of the first ``views`` crops of each scene's pick (HRG-Net)."""
    from tamp.sim.lots.driver import CellDriver
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.station import build_station

    bench, base = _bench(), load_cell_scenario("tower")
    out = {}
    for s in scene_seeds:
        scene, target, _ = bench.make_scene(base, s)
        cell = build_station(scene)
        cell.planner.record = True
        CellDriver(cell).run(f"Pick({target})", timeout=30.0)
        crops = [c for c, _, _ in cell.planner.history][:views]
        out[s] = [(np.asarray(c.rgb), np.asarray(c.depth), np.asarray(c.mask)) for c in crops]
    return out


def variants(rgb: np.ndarray, depth: np.ndarray):
    """The crop as rendered, with the table plane painted beige, and in grey."""
    yield "as rendered", rgb
    valid = depth > 0
    table = np.max(depth[valid]) if valid.any() else 0.0
    plain = rgb.copy()
    plain[valid & (depth > table - 0.004)] = BEIGE
    yield "table beige", plain
    yield "grey", np.repeat(rgb.mean(axis=2, keepdims=True), 3, axis=2).astype(np.uint8)


def on_target(grasps, mask: np.ndarray) -> int:
    """How many of ``grasps`` have their centre on ``mask`` (the workcell's own test)."""
    from tamp.sim.lots.grasping import on_mask

    return sum(on_mask(g.rect(), mask) is not None for g in grasps)


def main() -> int:
    from tamp.grasp.networks import NETWORKS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, nargs="+", default=[2, 1, 9])
    ap.add_argument("--networks", nargs="+", choices=list(NETWORKS), default=list(NETWORKS))
    ap.add_argument("--weights", nargs="+", default=[], metavar="NET=PATH")
    ap.add_argument("--top", type=int, default=5)
    args = ap.parse_args()
    import torch

    from tamp.sim.lots.grasping import GraspPlanner
    from tamp.sim.lots.scenario import GraspSettings

    torch.set_num_threads(1)
    files: dict[str, str | None] = {n: None for n in args.networks}  # None: the shipped file
    for item in args.weights:
        net, sep, path = item.partition("=")
        if not sep or net not in files or not os.path.isfile(path):
            ap.error(f"--weights {item!r}: expected NET=PATH with NET one of --networks, a file")
        files[net] = path
    views = record_views(args.scenes)
    rows = []
    for net, path in files.items():
        # the workcell's own loader (shipped weights by network, or the file given)
        planner = GraspPlanner(GraspSettings(network=net, weights=path), (1.0, 1.0, 0.0, 0.0))
        predictor, path = planner.predictor, str(planner.weights)
        counts: dict[str, int] = {}
        total = 0
        for crops in views.values():
            for rgb, depth, mask in crops:
                total += args.top
                for name, image in variants(rgb, depth):
                    grasps = predictor.predict(rgb=image, depth=depth, n=args.top)
                    counts[name] = counts.get(name, 0) + on_target(grasps, mask)
        rows.append({"network": net, "weights": path, "grasps": total} | counts)
    names = [k for k in rows[0] if k not in ("network", "weights", "grasps")]
    print(f"{'network':>10} " + " ".join(f"{n:>13}" for n in names) + "   (grasps on the target)")
    for r in rows:
        print(f"{r['network']:>10} " + " ".join(f"{r[n]:>7}/{r['grasps']:<5}" for n in names))
    print(json.dumps({"benchmark": "workcell_views", "scenes": args.scenes, "rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
