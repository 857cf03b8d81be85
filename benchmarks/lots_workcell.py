"""The LOTS workcell (Zhou et al., IEEE T-ASE 2023, §IV-B, Fig. 6): grasp success and time
per pick for HRG-Net,
GR-ConvNet-style and GG-CNN-style networks on the same seeded scenes, and the workcell's
real-time factor with the camera running and where its wall time goes.

Scenes. Scene ``s`` is one pick: the packaged ``tower`` cell (its plant, camera, control
and grasp settings) with its objects replaced by a target and one distractor in W^A,
drawn by ``numpy.random.default_rng(s)``: the target's class cycles through the classes of
the three packaged tasks (model building, tower, Example 1), positions and yaws are uniform
where the footprints fit in W^A at least 1 cm apart. The scenario format has no seed or
perturbation of its own yet, so the benchmark derives the scenes itself. Every network sees
the same scenes. A single pick per scene keeps the benchmark affordable; the full tasks are
``tamp simulate lots``.

Per scene and network: ``Pick(cls)`` through `CellDriver` (closed-loop multi-view grasp,
up to ``grasp.attempts`` attempts). A pick succeeds when the skill reports SUCCESS *and*
the plant shows the target lifted (more than 5 cm above the table); the time per pick is
the skill's sim time from start to end, including the retries.

Timing: sim time, wall time, process CPU time (all threads), and the non-overlapping parts
of `tamp.sim.lots.station.cell_parts` (render, perception, network, skills); the rest is the
plant's step (contact, SAP) and the framework. ``--task tower`` also runs the full LOTS task
(`simulate_lots`, camera, friction grasps and safety monitor on, verification gate off) once
per ``--time-steps`` value for the workcell's real-time factor; ``--interference SCRIPT``
adds that person (e.g. ``tower_interference``, Fig. 10). On a machine shared with other jobs
the wall figures depend on the load (printed); the CPU figures (``rtf_cpu``: sim seconds per
CPU second) are what the workcell itself costs.

``--baseline DIR``: also run the task with the ``tamp`` package in DIR (e.g. a ``git worktree``
of an earlier commit), in a fresh process before this one's, and print both: before/after in
one run. The task row keeps the run's verdict, the robot's actions and the safety stops, so
that a speed change that changes what happens shows.

    python benchmarks/lots_workcell.py [--scenes 30] [--networks NET ...]
        [--task tower] [--interference SCRIPT] [--time-steps 0.004 0.01] [--pick-timeout 60]
        [--threads 2] [--weights NET=PATH ...] [--baseline DIR] [--out FILE]
    python benchmarks/lots_workcell.py --scenes 0 --task tower \
        --interference tower_interference --baseline /tmp/before --out FILE

Prints a table and one JSON line (``--out FILE`` also writes it there).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import platform
import subprocess
import sys
import time

import numpy as np

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")

#: target classes, in the order scenes cycle through them (the three packaged tasks)
TARGETS = ("hammer", "scissors", "saw", "bottom", "body", "peak", "screwdriver", "screw")
#: what the distractor may be
DISTRACTORS = ("hammer", "scissors", "bottom", "body", "peak", "screwdriver", "wrench")
LIFTED = 0.05  # m above the table: the plant's verdict that the target was picked


def make_scene(base, seed: int):
    """The single-pick scene of ``seed``: (scenario, target class, target object id)."""
    from tamp.sim.lots.catalogue import CLASSES
    from tamp.sim.lots.scenario import CellObject, rectangles_overlap

    rng = np.random.default_rng(seed)
    target = TARGETS[seed % len(TARGETS)]
    other = str(rng.choice([c for c in DISTRACTORS if c != target]))
    w = base.workspaces["A"]
    placed: list[CellObject] = []
    for k, cls in enumerate((target, other)):
        fp = CLASSES[cls].footprint
        for _ in range(1000):
            x = w.center[0] + rng.uniform(-w.size[0] / 2, w.size[0] / 2)
            y = w.center[1] + rng.uniform(-w.size[1] / 2, w.size[1] / 2)
            yaw = rng.uniform(-math.pi, math.pi)
            corners = fp.corners(x, y, yaw)
            if not all(w.contains(*c, margin=0.01) for c in corners):
                continue
            if any(
                rectangles_overlap(corners, CLASSES[p.cls].footprint.corners(*p.xy, p.yaw), 0.01)
                for p in placed
            ):
                continue
            palette = CLASSES[cls].palette
            placed.append(
                CellObject(f"{cls}_{k}", cls, "A", (x, y), yaw, palette[k % len(palette)])
            )
            break
        else:
            raise RuntimeError(f"scene {seed}: no room for the {cls}")
    scene = dataclasses.replace(base, name=f"pick_{seed}", objects=tuple(placed))
    return scene, target, placed[0].id


def run_pick(
    scene, target: str, uid: str, network: str, timeout: float, weights: str | None = None
) -> dict:
    """One ``Pick(target)`` in ``scene`` with ``network`` (its shipped weights, or the file
    ``weights``); what happened and what it cost."""
    from tamp.sim.core.timing import breakdown
    from tamp.sim.lots.driver import CellDriver
    from tamp.sim.lots.grasping import dilate, on_mask, snap_to_mask
    from tamp.sim.lots.simulate import with_network
    from tamp.sim.lots.station import build_station, cell_parts

    scene = with_network(scene, network)
    if weights is not None:
        scene = dataclasses.replace(scene, grasp=dataclasses.replace(scene.grasp, weights=weights))
    cell = build_station(scene)
    cell.planner.record = True  # every view's crop and predictions (for the on-target count)
    driver = CellDriver(cell)
    w0, c0, t0 = time.perf_counter(), time.process_time(), driver.context.get_time()
    status = driver.run(f"Pick({target})", timeout=timeout)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    sim = driver.context.get_time() - t0
    z = cell.plant.EvalBodyPoseInWorld(driver.plant_context(), cell.cell.bodies[uid]).translation()[
        2
    ]
    skills = driver.skill_state()
    ok = status.status.value == "SUCCESS" and float(z) > LIFTED
    # views whose best grasp has its centre on the target as the network put it, and after
    # `snap_to_mask` moved it along its closing line (what the skill uses)
    on, snapped = 0, 0
    for crop, grasps, _ in cell.planner.history:
        mask = dilate(np.asarray(crop.mask), 1)
        if grasps:
            on += on_mask(grasps[0].rect(), mask) is not None
            snapped += snap_to_mask(grasps[0].rect(), mask) is not None
    return {
        "success": ok,
        "status": status.status.value,
        "detail": status.detail,
        "target_z": round(float(z), 4),
        "attempts": skills.grasp_attempts,
        "sim_time": round(sim, 3),
        "wall_time": round(wall, 3),
        "cpu_time": round(cpu, 3),
        "frames": driver.stats().frames,
        "network_calls": cell.planner.calls,
        "views_best_on_target": on,
        "views_best_snapped": snapped,
        "parts": breakdown(wall, cpu, cell_parts(cell)),
    }


def run_task(task_name: str, time_step: float, interference: str | None = None) -> dict:
    """The full LOTS task in the workcell (camera running) at plant step ``time_step``, with
    the person of the script ``interference`` (None: no person)."""
    from tamp.lots.controller import LotsController
    from tamp.lots.task import load_events, load_task
    from tamp.sim.core.timing import Stopwatch, breakdown
    from tamp.sim.lots import simulate
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.simulate import LotsScenario
    from tamp.sim.lots.station import cell_parts

    # time the LOTS controller's ticks (measurement only: a wrapper around the class method)
    ticks = Stopwatch()
    tick = LotsController.tick

    def timed_tick(self, world):
        with ticks:
            return tick(self, world)

    built = {}
    build = simulate.build_lots_diagram

    def keep(*a, **k):
        built["d"] = build(*a, **k)
        return built["d"]

    base = load_cell_scenario(task_name)
    plant = dataclasses.replace(base.plant, time_step=time_step)
    scenario = dataclasses.replace(base, plant=plant)
    task = load_task(task_name)
    events = tuple(load_events(interference, task)) if interference else ()
    LotsController.tick, simulate.build_lots_diagram = timed_tick, keep
    try:
        c0 = time.process_time()
        res = simulate.simulate_lots(LotsScenario(task, scenario, events), verify=False)
        cpu = time.process_time() - c0
    finally:
        LotsController.tick, simulate.build_lots_diagram = tick, build
    parts = cell_parts(built["d"].cell) | {"lots_controller": ticks}
    return {
        "task": task_name,
        "interference": interference,
        "time_step": time_step,
        "status": res.status,
        "satisfied": res.satisfied,
        "grasps": res.grasps,
        "frames": res.frames_rendered,
        "robot_actions": [a.text() for a in res.robot_actions],
        "safety_stops": [f"{s.time:.2f} {s.cause}" for s in res.safety_stops],
        "sim_time": round(res.sim_time, 2),
        "wall_time": round(res.wall_time, 2),
        "cpu_time": round(cpu, 2),
        "rtf_wall": round(res.realtime_factor, 3),
        "rtf_cpu": round(res.sim_time / cpu, 3) if cpu > 0 else None,
        "load_avg": round(os.getloadavg()[0], 2),
        "parts": breakdown(res.wall_time, cpu, parts),
    }


def source(root: str) -> dict:
    """Where a ``tamp`` package came from: its folder and, in a git checkout, the commit and
    whether its files differ from it."""
    out = {"path": os.path.abspath(root)}
    try:
        git = ["git", "-C", root]
        head = subprocess.run(
            [*git, "rev-parse", "--short", "HEAD"], capture_output=True, text=True
        )
        dirty = subprocess.run(
            [*git, "status", "--porcelain", "tamp"], capture_output=True, text=True
        )
    except OSError:
        return out
    if head.returncode == 0:
        out |= {"commit": head.stdout.strip(), "modified": bool(dirty.stdout.strip())}
    return out


def baseline_tasks(src: str, task: str, interference: str | None, steps: list[float]) -> list:
    """`run_task` rows of the ``tamp`` package in ``src``, in a fresh process."""
    argv = [sys.executable, os.path.abspath(__file__), "--scenes", "0", "--task", task]
    argv += ["--time-steps", *map(str, steps), "--quiet"]
    if interference:
        argv += ["--interference", interference]
    env = {**os.environ, "PYTHONPATH": os.path.abspath(src)}
    out = subprocess.run(argv, env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])["tasks"]


def summarise(network: str, picks: list[dict]) -> dict:
    ok = [p for p in picks if p["success"]]
    wall = sum(p["wall_time"] for p in picks)
    cpu = sum(p["cpu_time"] for p in picks)
    sim = sum(p["sim_time"] for p in picks)
    parts: dict[str, dict] = {}
    for p in picks:
        for k, v in p["parts"].items():
            acc = parts.setdefault(k, {"wall": 0.0, "cpu": 0.0, "calls": 0})
            for f in ("wall", "cpu", "calls"):
                acc[f] += v[f]
    for v in parts.values():
        v["wall_share"] = round(v["wall"] / wall, 3) if wall else 0.0
        v["cpu_share"] = round(v["cpu"] / cpu, 3) if cpu else 0.0
        v["wall"], v["cpu"] = round(v["wall"], 2), round(v["cpu"], 2)
    calls = sum(p["network_calls"] for p in picks)
    return {
        "network": network,
        "scenes": len(picks),
        "successes": len(ok),
        "success_rate": round(len(ok) / len(picks), 3) if picks else 0.0,
        "attempts": sum(p["attempts"] for p in picks),
        "mean_pick_time": round(sum(p["sim_time"] for p in picks) / len(picks), 2),
        "mean_successful_pick_time": (
            round(sum(p["sim_time"] for p in ok) / len(ok), 2) if ok else None
        ),
        "network_ms_per_call": (
            round(parts["network"]["cpu"] / calls * 1000, 1) if calls else None
        ),
        "views": calls,
        "views_best_on_target": sum(p["views_best_on_target"] for p in picks),
        "views_best_snapped": sum(p["views_best_snapped"] for p in picks),
        "sim_time": round(sim, 2),
        "wall_time": round(wall, 2),
        "cpu_time": round(cpu, 2),
        "rtf_wall": round(sim / wall, 3) if wall else None,
        "rtf_cpu": round(sim / cpu, 3) if cpu else None,
        "parts": parts,
    }


def main() -> int:
    from tamp.grasp.networks import NETWORKS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=30, help="seeded scenes 0..N-1 (0: only --task)")
    ap.add_argument("--first", type=int, default=0, help="first scene seed")
    ap.add_argument("--networks", nargs="+", choices=list(NETWORKS), default=list(NETWORKS))
    ap.add_argument("--pick-timeout", type=float, default=60.0, help="sim seconds per pick")
    ap.add_argument("--task", default=None, help="also run this LOTS task (e.g. tower)")
    ap.add_argument("--time-steps", type=float, nargs="+", default=None)
    ap.add_argument("--interference", default=None, help="the task run's person (a script)")
    ap.add_argument("--baseline", metavar="DIR", help="also run --task with the tamp in DIR")
    ap.add_argument("--out", metavar="FILE", help="also write the JSON document to FILE")
    ap.add_argument("--quiet", action="store_true", help="print the JSON line only")
    ap.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's)")
    ap.add_argument(
        "--weights",
        nargs="+",
        default=[],
        metavar="NET=PATH",
        help="a weights file instead of NET's shipped one (e.g. a network trained on other data)",
    )
    args = ap.parse_args()
    if args.baseline and not args.task:
        ap.error("--baseline needs --task")
    weights = {}
    for item in args.weights:
        net, sep, path = item.partition("=")
        if not sep or net not in args.networks or not os.path.isfile(path):
            ap.error(f"--weights {item!r}: expected NET=PATH with NET one of --networks, a file")
        weights[net] = path

    import torch

    from tamp.sim.lots.scenario import load_cell_scenario

    if args.threads:
        torch.set_num_threads(args.threads)
    base = load_cell_scenario("tower")
    seeds = range(args.first, args.first + args.scenes)
    scenes = {s: make_scene(base, s) for s in seeds}
    rows, per_scene = [], []
    for net in args.networks if seeds else ():  # --scenes 0: the task alone
        picks = []
        for s in seeds:
            scene, target, uid = scenes[s]
            p = run_pick(scene, target, uid, net, args.pick_timeout, weights.get(net))
            p |= {"scene": s, "network": net, "target": target}
            picks.append(p)
            print(
                f"  {net:>9} scene {s:>2} {target:>11}: {'ok ' if p['success'] else 'FAIL'} "
                f"{p['sim_time']:5.1f} s sim, {p['attempts']} att, {p['wall_time']:5.1f} s wall"
                f"  {p['detail']}",
                flush=True,
            )
        per_scene += [{k: v for k, v in p.items() if k != "parts"} for p in picks]
        rows.append(summarise(net, picks) | {"weights": weights.get(net, "shipped")})
    tasks, before = [], []
    steps = args.time_steps or [base.plant.time_step]
    if args.task and args.baseline:
        before = baseline_tasks(args.baseline, args.task, args.interference, steps)
        if not args.quiet:  # kept in the output should this package's run fail
            print(json.dumps({"baseline": {"src": args.baseline, "tasks": before}}), flush=True)
    if args.task:
        for step in steps:
            tasks.append(run_task(args.task, step, args.interference))
    if args.quiet:
        print(json.dumps({"benchmark": "lots_workcell", "tasks": tasks}))
        return 0

    print(
        f"\n{'network':>9} {'scenes':>6} {'success':>8} {'attempts':>8} {'s/pick':>7} "
        f"{'ms/net':>7} {'RTF wall':>8} {'RTF cpu':>8}"
    )
    for r in rows:
        print(
            f"{r['network']:>9} {r['scenes']:>6} {r['success_rate'] * 100:>7.0f}% "
            f"{r['attempts']:>8} {r['mean_pick_time']:>7.2f} {r['network_ms_per_call'] or 0:>7.0f} "
            f"{r['rtf_wall']:>8.2f} {r['rtf_cpu']:>8.2f}"
        )
    for r in rows:
        print(
            f"  {r['network']}: best grasp of a view on the target in {r['views_best_on_target']}"
            f" of {r['views']} views, after snap_to_mask in {r['views_best_snapped']}"
        )
    if rows and rows[0]["network"] == "hrgnet":
        for r in rows[1:]:
            saved = 1 - rows[0]["mean_pick_time"] / r["mean_pick_time"]
            held = [x["mean_successful_pick_time"] for x in (rows[0], r)]
            of_held = ""
            if all(held):
                of_held = f", held picks only: {(1 - held[0] / held[1]) * 100:.0f} %"
            print(
                f"  time per pick saved by HRG-Net against {r['network']}: {saved * 100:.0f} %"
                + of_held
            )
    for r in rows + tasks:
        label = r.get("network") or f"{r['task']} @ {r['time_step'] * 1000:g} ms"
        shares = ", ".join(
            f"{k} {v['cpu_share'] * 100:.0f}%" for k, v in r["parts"].items() if v["cpu"] > 0
        )
        print(f"  CPU time of {label}: {shares}")
    for label, rows_ in (("before", before), ("after", tasks) if before else ("", tasks)):
        for t in rows_:
            print(
                f"  {label + ' ' if label else ''}task {t['task']}"
                f"{' + ' + t['interference'] if t.get('interference') else ''} "
                f"@ {t['time_step'] * 1000:g} ms: {t['status']} "
                f"satisfied={t['satisfied']} sim {t['sim_time']} s, wall {t['wall_time']} s, "
                f"cpu {t['cpu_time']} s: RTF wall {t['rtf_wall']}, RTF cpu {t['rtf_cpu']}"
            )
    for b, a in zip(before, tasks, strict=False):
        same = (b["status"], b["satisfied"], b.get("robot_actions")) == (
            a["status"],
            a["satisfied"],
            a["robot_actions"],
        )
        print(
            f"  @ {a['time_step'] * 1000:g} ms: RTF cpu {b['rtf_cpu']} -> {a['rtf_cpu']} "
            f"({a['rtf_cpu'] / b['rtf_cpu']:.2f}x), same verdict and robot actions: {same}"
        )
    summary = {
        "benchmark": "lots_workcell",
        "machine": f"{platform.machine()} {os.cpu_count()} cpus",
        "load_avg": round(os.getloadavg()[0], 2),
        "torch_threads": torch.get_num_threads(),
        "scenes": list(seeds),
        "rows": rows,
        "tasks": tasks,
        "picks": per_scene,
    }
    import tamp

    summary["tamp"] = source(os.path.dirname(os.path.dirname(tamp.__file__)))
    if before:
        summary["baseline"] = {"src": source(args.baseline), "tasks": before}
    print(json.dumps(summary))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(summary, fh, indent=1)
            fh.write("\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
