"""The LOTS paper's three grasp experiments (Zhou et al., IEEE T-ASE 2023, §V-A, Fig. 7) in
the Drake workcell, through the closed-loop descent (§IV-B, Fig. 6; `tamp.sim.lots.descent`).

Sets (one pick per scene, seeded; every method sees the same scenes):

- ``clutter``: multi-object interference: 5-8 objects in W^A, each placed touching another
  (footprints 3-8 mm apart), the target among them (``numpy.random.default_rng((1, s))``);
- ``random``: random initial positions and yaws: the target and one distractor anywhere in
  W^A (the scenes of ``benchmarks/lots_workcell.py``: ``default_rng(s)``);
- ``moving``: the ``random`` scene whose target is carried across the table during the
  descent: from 1.5 s to 4.5 s after the pick starts it moves at 2 cm/s in a direction
  drawn by ``default_rng((3, s))`` that keeps it inside W^A and clear of the distractor (the
  benchmark sets its pose and velocity on the plant every 20 ms: a conveyor, not a hand),
  and stops early when the fingers come within 12 cm of the table (`RELEASE_Z`).

Methods: ``hrgnet``, ``grconvnet``, ``ggcnn`` (the shipped weights, post-processing on: the
cell's default), and the controls ``mask_axis`` (no network: grasps across the target
mask's principal axis, `tamp.sim.lots.grasping.mask_axis_grasps`, post-processing on),
``mask_axis_raw`` (the same, post-processing off) and ``hrgnet_raw`` (HRG-Net with
post-processing off: its grasps on the mask as predicted). All use the same descent and
thresholds (the ``tower`` cell's ``grasp.descent``).

Per pick: ``Pick(cls)`` through `CellDriver`; success when the skill reports SUCCESS and the
plant shows the target more than 5 cm up; the time per pick is the skill's sim time from
start to end, retries included (failed picks count with their time). Tables: success rate
(Wilson 95 % interval), mean sim time per pick, and per method the paired per-scene
difference to HRG-Net (success in percentage points, time in seconds) with a bootstrap 95 %
interval over scenes (10 000 resamples, seed 0); an interval that holds zero is "no
significant difference", and below 10 paired scenes no claim is made either way.

    python benchmarks/grasp_experiments.py [--scenes 30] [--sets clutter random moving]
        [--methods hrgnet ...] [--out benchmarks/results/grasp_experiments.json] [--resume]
        [--pick-timeout 60] [--tables-only]

Every finished pick is written to ``--out`` at once (the per-scene records and the tables
from them), so ``--resume`` continues an interrupted or smaller run with the scenes and
methods still missing: ``--scenes 30 --resume`` completes a committed short run.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")

SETS = ("clutter", "random", "moving")
#: method -> (grasp.predictor, grasp.network, grasp.post_process)
METHODS = {
    "hrgnet": ("network", "hrgnet", True),
    "grconvnet": ("network", "grconvnet", True),
    "ggcnn": ("network", "ggcnn", True),
    "mask_axis": ("mask_axis", "hrgnet", True),
    "mask_axis_raw": ("mask_axis", "hrgnet", False),
    "hrgnet_raw": ("network", "hrgnet", False),
}
REFERENCE = "hrgnet"
#: the moving target: when it moves (s after the pick starts), how fast (m/s), how often
#: its pose is set (s)
MOVE_FROM, MOVE_TO, MOVE_SPEED, MOVE_TICK = 1.5, 4.5, 0.02, 0.02
#: ... and it stops early when the fingers come lower than this over the table (m)
RELEASE_Z = 0.12
#: clutter: how many objects, how far apart their footprints at least and at most (m)
CLUTTER_COUNT = (5, 8)
TOUCH_GAP = (0.003, 0.008)
BOOTSTRAP = 10_000
#: fewer paired scenes than this make no claim either way: a percentile bootstrap over a
#: handful of scenes gives intervals that are too narrow (a single scene: a point)
MIN_PAIRS = 10
OUT = Path(__file__).with_name("results") / "grasp_experiments.json"


def _workcell_bench():
    """``benchmarks/lots_workcell.py`` (its scenes, classes and lift verdict)."""
    path = Path(__file__).with_name("lots_workcell.py")
    spec = importlib.util.spec_from_file_location("lots_workcell_bench", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---- scenes -------------------------------------------------------------------------------
def clutter_scene(base, seed: int, classes: tuple[str, ...], targets: tuple[str, ...]):
    """5-8 objects in W^A, each touching one placed before it; the target is the first (near
    the workspace centre) and the only one of its class; a layout that does not fit is drawn
    again (``default_rng((1, seed, k))``, k = 0, 1, ...). (scenario, target class, id)."""
    for k in range(100):
        placed = _clutter(base, np.random.default_rng((1, seed, k)), seed, classes, targets)
        if placed is not None:
            scene = dataclasses.replace(base, name=f"clutter_{seed}", objects=tuple(placed))
            return scene, placed[0].cls, placed[0].id
    raise RuntimeError(f"clutter scene {seed}: no layout in 100 draws")


def _clutter(base, rng, seed: int, classes, targets):
    from tamp.sim.lots.catalogue import CLASSES
    from tamp.sim.lots.scenario import CellObject, rectangles_overlap

    w = base.workspaces["A"]
    n = int(rng.integers(CLUTTER_COUNT[0], CLUTTER_COUNT[1] + 1))
    target = targets[seed % len(targets)]
    rest = [c for c in classes if c != target]  # one instance of the target's class: the one
    kinds = [target, *(str(rng.choice(rest)) for _ in range(n - 1))]
    placed: list[CellObject] = []
    count: dict[str, int] = {}
    for cls in kinds:
        fp = CLASSES[cls].footprint
        for _ in range(500):
            yaw = float(rng.uniform(-math.pi, math.pi))
            if not placed:
                x = w.center[0] + rng.uniform(-0.03, 0.03)
                y = w.center[1] + rng.uniform(-0.03, 0.03)
            else:
                anchor = placed[int(rng.integers(len(placed)))]
                a, r = rng.uniform(-math.pi, math.pi), rng.uniform(0.03, 0.15)
                x, y = anchor.xy[0] + r * math.cos(a), anchor.xy[1] + r * math.sin(a)
            corners = fp.corners(x, y, yaw)
            if not all(w.contains(*c, margin=0.01) for c in corners):
                continue
            others = [CLASSES[p.cls].footprint.corners(*p.xy, p.yaw) for p in placed]
            if any(rectangles_overlap(corners, o, TOUCH_GAP[0]) for o in others):
                continue
            if others and not any(rectangles_overlap(corners, o, TOUCH_GAP[1]) for o in others):
                continue  # touching: within 8 mm of one placed before
            i = count.get(cls, 0)
            count[cls] = i + 1
            palette = CLASSES[cls].palette
            rgb = tuple(palette[i % len(palette)])
            placed.append(CellObject(f"{cls}_{i}", cls, "A", (x, y), yaw, rgb))
            break
        else:
            return None
    return placed


def motion(scene, uid: str, seed: int) -> tuple[float, float] | None:
    """The moving target's velocity (m/s): a direction drawn by ``default_rng((3, seed))``
    among 16 whose path keeps the target in W^A (1 cm margin) and 1 cm clear of the other
    objects; None when none does."""
    from tamp.sim.lots.catalogue import CLASSES
    from tamp.sim.lots.scenario import rectangles_overlap

    rng = np.random.default_rng((3, seed))
    o = scene.object(uid)
    fp = CLASSES[o.cls].footprint
    w = scene.workspaces["A"]
    others = [CLASSES[p.cls].footprint.corners(*p.xy, p.yaw) for p in scene.objects if p.id != uid]
    travel = MOVE_SPEED * (MOVE_TO - MOVE_FROM)
    start = float(rng.uniform(0, 2 * math.pi))
    for k in range(16):
        a = start + k * 2 * math.pi / 16
        d = (math.cos(a), math.sin(a))
        ok = True
        for f in np.linspace(0.0, 1.0, 6):
            c = fp.corners(o.xy[0] + f * travel * d[0], o.xy[1] + f * travel * d[1], o.yaw)
            if not all(w.contains(*p, margin=0.01) for p in c) or any(
                rectangles_overlap(c, q, 0.01) for q in others
            ):
                ok = False
                break
        if ok:
            return (MOVE_SPEED * d[0], MOVE_SPEED * d[1])
    return None


def make(set_name: str, base, seed: int, bench):
    """(scenario, target class, target id, velocity or None) of scene ``seed`` of a set."""
    if set_name == "clutter":
        classes = tuple(sorted(set(bench.TARGETS) | set(bench.DISTRACTORS)))
        return (*clutter_scene(base, seed, classes, bench.TARGETS), None)
    scene, target, uid = bench.make_scene(base, seed)
    return scene, target, uid, motion(scene, uid, seed) if set_name == "moving" else None


# ---- one pick -----------------------------------------------------------------------------
def run_pick(scene, target: str, uid: str, method: str, velocity, timeout: float) -> dict:
    """One ``Pick(target)`` with ``method`` (module docstring); what happened and its cost."""

    from tamp.sim.lots.driver import CellDriver
    from tamp.sim.lots.station import build_station

    predictor, network, post = METHODS[method]
    grasp = dataclasses.replace(
        scene.grasp, predictor=predictor, network=network, weights=None, post_process=post
    )
    cell = build_station(dataclasses.replace(scene, grasp=grasp))
    driver = CellDriver(cell, tick=MOVE_TICK if velocity else 0.05)
    plant, body = cell.plant, cell.cell.bodies[uid]
    w0, c0, t0 = time.perf_counter(), time.process_time(), driver.context.get_time()
    h = driver.start(f"Pick({target})")
    crash = None
    try:
        _poll(driver, h, t0, timeout, velocity, plant, body, cell)
    except RuntimeError as exc:  # the contact solver failed (a NaN): a failed pick, recorded
        crash = str(exc).split(". ")[0]
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    status = driver.status()
    sim = driver.context.get_time() - t0
    s = driver.skill_state()
    if crash is not None:
        return {
            "success": False,
            "status": "CRASH",
            "detail": f"{crash} (at {sim:.2f} s, step {s.steps[0].kind if s.steps else None})",
            "cause": "crash",
            "target_z": None,
            "sim_time": timeout,  # counted as a pick that timed out
            "attempts": s.grasp_attempts,
            "views": cell.planner.calls,
            "first_commit": None,
            "commits": 0,
            "cpu_time": round(cpu, 2),
            "wall_time": round(wall, 2),
        }
    z = float(plant.EvalBodyPoseInWorld(driver.plant_context(), body).translation()[2])
    commits = [t - t0 for t, m in s.log if m.startswith("commit after")]
    return {
        "success": status.status.value == "SUCCESS" and z > LIFTED,
        "status": status.status.value,
        "detail": status.detail,
        "cause": status.cause,
        "target_z": round(z, 4),
        "sim_time": round(sim, 3),
        "attempts": s.grasp_attempts,
        "views": cell.planner.calls,
        "first_commit": round(commits[0], 3) if commits else None,
        "commits": len(commits),
        "cpu_time": round(cpu, 2),
        "wall_time": round(wall, 2),
    }


def _poll(driver, h, t0, timeout, velocity, plant, body, cell) -> None:
    """Poll the pick to its end (or ``timeout``), carrying the moving target (module
    docstring) when ``velocity`` is given."""
    from pydrake.math import RigidTransform
    from pydrake.multibody.math import SpatialVelocity

    from tamp.world.interface import Status

    origin = None
    while driver.poll(h) is Status.RUNNING:
        el = driver.context.get_time() - t0
        if el > timeout:
            driver.cancel(h)
            break
        if velocity and MOVE_FROM <= el <= MOVE_TO and origin is not False:
            ctx = driver.plant_context()
            if cell.skills.kin.tcp_pose(driver.skill_state().q).translation()[2] < RELEASE_Z:
                # the fingers are coming down on it: the conveyor lets go (a pose set into
                # the closing fingers makes the contact solver fail, not the grasp)
                plant.SetFreeBodySpatialVelocity(ctx, body, SpatialVelocity.Zero())
                origin = False
                continue
            X = plant.EvalBodyPoseInWorld(ctx, body)
            if origin is None:
                origin = X.translation().copy()
            p = origin + (el - MOVE_FROM) * np.array([velocity[0], velocity[1], 0.0])
            p[2] = X.translation()[2]
            plant.SetFreeBodyPose(ctx, body, RigidTransform(X.rotation(), p))
            moving = el < MOVE_TO - MOVE_TICK  # at rest after the last tick
            v = np.array([velocity[0], velocity[1], 0.0]) if moving else np.zeros(3)
            plant.SetFreeBodySpatialVelocity(ctx, body, SpatialVelocity(np.zeros(3), v))


LIFTED = 0.05  # m above the table: the plant's verdict that the target was picked


# ---- statistics ---------------------------------------------------------------------------
def paired_bootstrap(diffs: list[float], seed: int = 0) -> tuple[float, float, float] | None:
    """(mean, low, high): the mean of paired per-scene differences and its bootstrap 95 %
    percentile interval over scenes; None without scenes."""
    if not diffs:
        return None
    d = np.asarray(diffs, float)
    rng = np.random.default_rng(seed)
    means = d[rng.integers(0, len(d), size=(BOOTSTRAP, len(d)))].mean(axis=1)
    lo, hi = np.percentile(means, [2.5, 97.5])
    return float(d.mean()), float(lo), float(hi)


def tables(picks: list[dict]) -> list[dict]:
    """One row per (set, method): scenes, success rate with its Wilson interval, mean time
    per pick, paired differences to `REFERENCE` over the scenes both ran."""
    from tamp.campaign.stats import wilson_interval

    rows = []
    by = {(p["set"], p["method"], p["scene"]): p for p in picks}
    for set_name in SETS:
        for method in METHODS:
            mine = sorted(
                (p for p in picks if (p["set"], p["method"]) == (set_name, method)),
                key=lambda p: p["scene"],
            )
            if not mine:
                continue
            ok = sum(p["success"] for p in mine)
            lo, hi = wilson_interval(ok, len(mine))
            row = {
                "set": set_name,
                "method": method,
                "scenes": len(mine),
                "successes": ok,
                "success_rate": round(ok / len(mine), 3),
                "success_ci": [round(lo, 3), round(hi, 3)],
                "mean_pick_time": round(float(np.mean([p["sim_time"] for p in mine])), 2),
                "mean_views": round(float(np.mean([p["views"] for p in mine])), 1),
                "committed_share": round(
                    float(np.mean([p["first_commit"] is not None for p in mine])), 3
                ),
                "mean_first_commit": _mean([p["first_commit"] for p in mine]),
                "crashes": sum(p["status"] == "CRASH" for p in mine),
            }
            pairs = [(p, by.get((set_name, REFERENCE, p["scene"]))) for p in mine]
            pairs = [(p, r) for p, r in pairs if r is not None]
            if method != REFERENCE and pairs:
                ds = paired_bootstrap([float(p["success"]) - float(r["success"]) for p, r in pairs])
                dt = paired_bootstrap([p["sim_time"] - r["sim_time"] for p, r in pairs])
                row["paired_scenes"] = len(pairs)
                row["success_diff"] = [round(v, 3) for v in ds]
                row["time_diff"] = [round(v, 2) for v in dt]
                enough = len(pairs) >= MIN_PAIRS
                row["time_diff_significant"] = enough and not (dt[1] <= 0.0 <= dt[2])
                row["success_diff_significant"] = enough and not (ds[1] <= 0.0 <= ds[2])
            rows.append(row)
    return rows


def _claim(row: dict, what: str) -> str:
    """What a difference's interval allows: nothing below `MIN_PAIRS` scenes, "n.s." when it
    holds zero, else nothing added (significant)."""
    if row["paired_scenes"] < MIN_PAIRS:
        return f" (n = {row['paired_scenes']} < {MIN_PAIRS}: no claim)"
    return "" if row[f"{what}_diff_significant"] else " n.s."


def _mean(values) -> float | None:
    """Mean of the values that are not None (rounded), None when there are none."""
    xs = [v for v in values if v is not None]
    return round(float(np.mean(xs)), 2) if xs else None


def markdown(rows: list[dict]) -> str:
    """The tables as Markdown, one per set."""
    out = []
    for set_name in SETS:
        mine = [r for r in rows if r["set"] == set_name]
        if not mine:
            continue
        out.append(f"\n**{set_name}**\n")
        out.append(
            "| method | scenes | success (95 % CI) | s per pick | views per pick | commit at s | "
            f"Δ success vs {REFERENCE} (95 % CI) | Δ s per pick vs {REFERENCE} (95 % CI) |"
        )
        out.append("|---|---:|---|---:|---:|---:|---|---|")
        for r in mine:
            lo, hi = r["success_ci"]
            s = f"{r['successes']}/{r['scenes']} ({lo * 100:.0f}–{hi * 100:.0f} %)"
            if r["crashes"]:
                s += f", {r['crashes']} crashed"
            commit = "—" if r["mean_first_commit"] is None else f"{r['mean_first_commit']:.2f}"
            ds = dt = "—"
            if "success_diff" in r:
                m, a, b = r["success_diff"]
                ds = f"{m * 100:+.0f} pp ({a * 100:+.0f}, {b * 100:+.0f})" + _claim(r, "success")
                m, a, b = r["time_diff"]
                dt = f"{m:+.2f} ({a:+.2f}, {b:+.2f})" + _claim(r, "time")
            out.append(
                f"| {r['method']} | {r['scenes']} | {s} | {r['mean_pick_time']:.2f} | "
                f"{r['mean_views']:.1f} | {commit} | {ds} | {dt} |"
            )
    return "\n".join(out)


# ---- main ---------------------------------------------------------------------------------
def write(path: Path, picks: list[dict], meta: dict) -> None:
    doc = meta | {
        "rows": tables(picks),
        "picks": sorted(
            picks,
            key=lambda p: (SETS.index(p["set"]), p["scene"], list(METHODS).index(p["method"])),
        ),
    }
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    tmp.replace(path)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=30, help="scenes 0..N-1 per set")
    ap.add_argument("--sets", nargs="+", choices=SETS, default=list(SETS))
    ap.add_argument("--methods", nargs="+", choices=list(METHODS), default=list(METHODS))
    ap.add_argument("--out", type=Path, default=OUT, help="the per-scene JSON (and tables)")
    ap.add_argument("--resume", action="store_true", help="keep --out's picks; run the rest")
    ap.add_argument("--pick-timeout", type=float, default=60.0, help="sim seconds per pick")
    ap.add_argument(
        "--tables-only", action="store_true", help="recompute and print --out's tables; run nothing"
    )
    ap.add_argument("--threads", type=int, default=1, help="torch threads")
    ap.add_argument("--note", default="", help="stored in --out (e.g. the commit the run used)")
    args = ap.parse_args()
    if args.scenes < 1:
        ap.error("--scenes: expected at least 1")
    picks: list[dict] = []
    if (args.resume or args.tables_only) and args.out.is_file():
        try:
            doc = json.loads(args.out.read_text())
            picks = doc["picks"]
        except (ValueError, KeyError) as exc:
            print(f"{args.out}: picks: not a grasp_experiments result ({exc})")
            return 2
    if args.tables_only:  # the tables again from the picks (rewritten into --out)
        if picks:
            write(args.out, picks, {k: v for k, v in doc.items() if k not in ("rows", "picks")})
        print(markdown(tables(picks)))
        return 0

    import torch

    from tamp.sim.lots.scenario import load_cell_scenario

    torch.set_num_threads(args.threads)
    bench = _workcell_bench()
    base = load_cell_scenario("tower")
    done = {(p["set"], p["method"], p["scene"]) for p in picks}
    meta = {
        "benchmark": "grasp_experiments",
        "command": "python benchmarks/grasp_experiments.py "
        + " ".join(
            f"--{k.replace('_', '-')} {' '.join(map(str, v)) if isinstance(v, list) else v}"
            for k, v in (("scenes", args.scenes), ("sets", args.sets), ("methods", args.methods))
        ),
        "note": args.note,
        "cell": "tower",
        "descent": dataclasses.asdict(base.grasp.descent),
        "machine": f"{platform.machine()} {os.cpu_count()} cpus (shared)",
        "time": "sim seconds per pick; cpu/wall per pick on the shared machine",
    }
    for s in range(args.scenes):  # scene by scene: every method on a scene before the next
        for set_name in args.sets:
            scene, target, uid, velocity = make(set_name, base, s, bench)
            for method in args.methods:
                if (set_name, method, s) in done:
                    continue
                p = run_pick(scene, target, uid, method, velocity, args.pick_timeout)
                p |= {
                    "set": set_name,
                    "scene": s,
                    "method": method,
                    "target": target,
                    "objects": len(scene.objects),
                    "velocity": None if velocity is None else [round(v, 4) for v in velocity],
                }
                picks.append(p)
                write(args.out, picks, meta | {"load_avg": round(os.getloadavg()[0], 2)})
                print(
                    f"{set_name:>7} {s:>2} {method:>13} {target:>11}: "
                    f"{'ok  ' if p['success'] else 'FAIL'} {p['sim_time']:5.1f} s sim, "
                    f"{p['views']:>2} views, commit {p['first_commit']}, {p['cpu_time']:5.1f} s cpu"
                    f"  {p['detail']}",
                    flush=True,
                )
    print(markdown(tables(picks)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
