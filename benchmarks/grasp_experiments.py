"""The LOTS paper's three grasp experiments (Zhou et al., IEEE T-ASE 2023, §V-A, Fig. 7) in
the Drake workcell, through the closed-loop descent (§IV-B, Fig. 6; `tamp.sim.lots.descent`).

Sets (one pick per scene, seeded; every method sees the same scenes):

- ``clutter``: multi-object interference: 5-8 objects in W^A, each placed touching another
  (footprints 3-8 mm apart), the target among them (``numpy.random.default_rng((1, s))``);
- ``random``: random initial positions and yaws: the target and one distractor anywhere in
  W^A (the scenes of ``benchmarks/lots_workcell.py``: ``default_rng(s)``);
- ``moving``: the ``random`` scene whose target slides across the table through the descent
  and the final approach: from 1.5 s after the pick starts it moves at 2 cm/s until the
  fingers first close on it (or its path ends), in the direction, of 16 starting at one
  drawn by ``default_rng((3, s))``, whose straight path stays inside W^A and clear of the
  distractor longest (up to 16 cm; the benchmark sets its pose and velocity on the plant
  every 20 ms: a conveyor, not a hand). Each pick records how far it went and whether it
  was still moving when the fingers closed (``moving_at_close``).

Methods: ``hrgnet``, ``grconvnet``, ``ggcnn`` (the shipped weights, post-processing on: the
cell's default), and the controls ``mask_axis`` (no network: grasps across the target
mask's principal axis, `tamp.sim.lots.grasping.mask_axis_grasps`, post-processing on),
``mask_axis_raw`` (the same, post-processing off) and ``hrgnet_raw`` (HRG-Net with
post-processing off: its grasps on the mask as predicted). All use the same descent and
thresholds (the ``tower`` cell's ``grasp.descent``), the final approach of ``--approach``
(``closed``, the cell's default, or ``open``) and the views read by ``--detector``
(``oracle``: the label image, the cell's default; ``learned``: the learned detector).

Per pick: ``Pick(cls)`` through `CellDriver`; success when the skill reports SUCCESS and the
plant shows the target more than 5 cm up; the time per pick is the skill's sim time from
start to end, retries included (failed picks count with their time). Tables: success rate
(Wilson 95 % interval), mean sim time per pick, and per method the paired per-scene
difference to HRG-Net (success in percentage points, time in seconds) with a bootstrap 95 %
interval over scenes (10 000 resamples, seed 0); an interval that holds zero is "no
significant difference", and below 10 paired scenes no claim is made either way.

    python benchmarks/grasp_experiments.py [--scenes 30] [--sets clutter random moving]
        [--methods hrgnet ...] [--out benchmarks/results/grasp_experiments.json] [--resume]
        [--pick-timeout 60] [--tables-only] [--detector oracle|learned] [--approach closed|open]

Every finished pick is written to ``--out`` at once (the per-scene records and the tables
from them), so ``--resume`` continues an interrupted or smaller run with the scenes and
methods still missing: ``--scenes 30 --resume`` completes a committed short run (with the
detector and approach it was run with: a file without them was run with the oracle and the
open approach, before the closed one existed).
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
from typing import NamedTuple

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
#: the moving target: when it starts (s after the pick starts), how fast (m/s), how often
#: its pose is set (s); it moves until the fingers first close (a pose set into closing
#: fingers makes the contact solver fail, not the grasp) or its path ends
MOVE_FROM, MOVE_SPEED, MOVE_TICK = 1.5, 0.02, 0.02
#: ... along a straight path of at most `MOVE_MAX` (m: 8 s, past the first close of every
#: pick the closed approach made in the smoke run) and at least `MOVE_MIN` (the 6 cm the
#: moving set had before), checked every `PATH_STEP`
MOVE_MAX, MOVE_MIN, PATH_STEP = 0.16, 0.06, 0.01
#: ``--detector`` and ``--approach`` of a result file that does not name them
LEGACY = {"detector": "oracle", "approach": "open"}
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


class Motion(NamedTuple):
    """The moving target's conveyor: its velocity (m/s, world x and y) and the length of its
    straight path (m)."""

    velocity: tuple[float, float]
    travel: float


def motion(scene, uid: str, seed: int) -> Motion | None:
    """The moving target's path: of 16 directions, starting at one drawn by
    ``default_rng((3, seed))``, the one whose straight path keeps the target in W^A (1 cm
    margin) and 1 cm clear of the other objects longest, up to `MOVE_MAX` (the first such
    on a tie); None when none gets `MOVE_MIN`."""
    from tamp.sim.lots.catalogue import CLASSES
    from tamp.sim.lots.scenario import rectangles_overlap

    rng = np.random.default_rng((3, seed))
    o = scene.object(uid)
    fp = CLASSES[o.cls].footprint
    w = scene.workspaces["A"]
    others = [CLASSES[p.cls].footprint.corners(*p.xy, p.yaw) for p in scene.objects if p.id != uid]
    start = float(rng.uniform(0, 2 * math.pi))
    best: Motion | None = None
    for k in range(16):
        a = start + k * 2 * math.pi / 16
        d = (math.cos(a), math.sin(a))
        travel = 0.0
        for f in np.arange(PATH_STEP, MOVE_MAX + 1e-9, PATH_STEP):
            c = fp.corners(o.xy[0] + f * d[0], o.xy[1] + f * d[1], o.yaw)
            if not all(w.contains(*p, margin=0.01) for p in c) or any(
                rectangles_overlap(c, q, 0.01) for q in others
            ):
                break
            travel = float(f)
        if travel >= MOVE_MIN - 1e-9 and (best is None or travel > best.travel + 1e-9):
            best = Motion((MOVE_SPEED * d[0], MOVE_SPEED * d[1]), round(travel, 3))
    return best


def make(set_name: str, base, seed: int, bench):
    """(scenario, target class, target id, `Motion` or None) of scene ``seed`` of a set."""
    if set_name == "clutter":
        classes = tuple(sorted(set(bench.TARGETS) | set(bench.DISTRACTORS)))
        return (*clutter_scene(base, seed, classes, bench.TARGETS), None)
    scene, target, uid = bench.make_scene(base, seed)
    return scene, target, uid, motion(scene, uid, seed) if set_name == "moving" else None


# ---- one pick -----------------------------------------------------------------------------
def run_pick(scene, target: str, uid: str, method: str, move, timeout: float) -> dict:
    """One ``Pick(target)`` with ``method`` (module docstring), the target carried by
    ``move`` (a `Motion`, or None); what happened and its cost."""

    from tamp.sim.lots.driver import CellDriver
    from tamp.sim.lots.station import build_station

    predictor, network, post = METHODS[method]
    grasp = dataclasses.replace(
        scene.grasp, predictor=predictor, network=network, weights=None, post_process=post
    )
    cell = build_station(dataclasses.replace(scene, grasp=grasp))
    driver = CellDriver(cell, tick=MOVE_TICK if move else 0.05)
    plant, body = cell.plant, cell.cell.bodies[uid]
    w0, c0, t0 = time.perf_counter(), time.process_time(), driver.context.get_time()
    h = driver.start(f"Pick({target})")
    crash = None
    conveyor = Conveyor(move, plant, body) if move else None
    try:
        _poll(driver, h, t0, timeout, conveyor)
    except RuntimeError as exc:  # the contact solver failed (a NaN): a failed pick, recorded
        crash = str(exc).split(". ")[0]
    moved = {} if conveyor is None else conveyor.record()
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
        } | moved
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
    } | moved


class Conveyor:
    """Carries the moving target along its `Motion` from `MOVE_FROM` after the pick starts
    until the skill first commands the fingers closed or the path ends (module docstring);
    then it stands still for good."""

    def __init__(self, move: Motion, plant, body):
        self.move, self.plant, self.body = move, plant, body
        self.origin: np.ndarray | None = None
        self.done = False
        self.at_close = False  # still moving when the fingers closed
        self.moved = 0.0

    def step(self, driver, el: float) -> None:
        """Once per poll, ``el`` sim seconds after the pick started."""
        from pydrake.math import RigidTransform
        from pydrake.multibody.math import SpatialVelocity

        from tamp.sim.lots.skills import CLOSED

        if self.done or el < MOVE_FROM:
            return
        ctx = driver.plant_context()
        X = self.plant.EvalBodyPoseInWorld(ctx, self.body)
        origin = self.origin = X.translation().copy() if self.origin is None else self.origin
        closing = driver.skill_state().finger == CLOSED
        d = min((el - MOVE_FROM) * MOVE_SPEED, self.move.travel)
        if closing or d >= self.move.travel:
            self.at_close = closing and d < self.move.travel
            self.done = True
            self.plant.SetFreeBodySpatialVelocity(ctx, self.body, SpatialVelocity.Zero())
            return
        u = np.array([*self.move.velocity, 0.0]) / MOVE_SPEED
        p = origin + d * u
        p[2] = X.translation()[2]
        self.plant.SetFreeBodyPose(ctx, self.body, RigidTransform(X.rotation(), p))
        v = SpatialVelocity(np.zeros(3), MOVE_SPEED * u)
        self.plant.SetFreeBodySpatialVelocity(ctx, self.body, v)
        self.moved = float(d)

    def record(self) -> dict:
        """What the pick's record says of the motion."""
        return {
            "travel": self.move.travel,
            "moved": round(self.moved, 4),
            "moving_at_close": self.at_close,
        }


def _poll(driver, h, t0, timeout, conveyor: Conveyor | None) -> None:
    """Poll the pick to its end (or ``timeout``), carrying the moving target (module
    docstring) when a ``conveyor`` is given."""
    from tamp.world.interface import Status

    while driver.poll(h) is Status.RUNNING:
        el = driver.context.get_time() - t0
        if el > timeout:
            driver.cancel(h)
            break
        if conveyor is not None:
            conveyor.step(driver, el)


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
    from tamp.sim.core.models import DETECTORS
    from tamp.sim.lots.scenario import APPROACHES, CameraSettings, DescentSettings

    what = "what reads the wrist camera's views (camera.detector; default %(default)s)"
    ap.add_argument("--detector", choices=DETECTORS, default=CameraSettings().detector, help=what)
    what = "the final approach from the preset height (grasp.descent.approach; default %(default)s)"
    ap.add_argument("--approach", choices=APPROACHES, default=DescentSettings().approach, help=what)
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
        for key, default in LEGACY.items():
            had = doc.get(key, default)
            if args.resume and picks and had != getattr(args, key):
                ran = getattr(args, key)
                print(f"{args.out}: {key}: its picks ran with {had}, not --{key} {ran}")
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
    descent = dataclasses.replace(base.grasp.descent, approach=args.approach)
    base = dataclasses.replace(
        base,
        camera=dataclasses.replace(base.camera, detector=args.detector),
        grasp=dataclasses.replace(base.grasp, descent=descent),
    )
    done = {(p["set"], p["method"], p["scene"]) for p in picks}
    meta = {
        "benchmark": "grasp_experiments",
        "command": "python benchmarks/grasp_experiments.py "
        + " ".join(
            f"--{k.replace('_', '-')} {' '.join(map(str, v)) if isinstance(v, list) else v}"
            for k, v in (
                ("scenes", args.scenes),
                ("sets", args.sets),
                ("methods", args.methods),
                ("detector", args.detector),
                ("approach", args.approach),
            )
        ),
        "note": args.note,
        "cell": "tower",
        "detector": args.detector,
        "approach": args.approach,
        "descent": dataclasses.asdict(base.grasp.descent),
        "machine": f"{platform.machine()} {os.cpu_count()} cpus (shared)",
        "time": "sim seconds per pick; cpu/wall per pick on the shared machine",
    }
    for s in range(args.scenes):  # scene by scene: every method on a scene before the next
        for set_name in args.sets:
            scene, target, uid, move = make(set_name, base, s, bench)
            for method in args.methods:
                if (set_name, method, s) in done:
                    continue
                p = run_pick(scene, target, uid, method, move, args.pick_timeout)
                p |= {
                    "set": set_name,
                    "scene": s,
                    "method": method,
                    "target": target,
                    "objects": len(scene.objects),
                    "velocity": None if move is None else [round(v, 4) for v in move.velocity],
                    "detector": args.detector,
                    "approach": args.approach,
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
