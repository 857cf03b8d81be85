"""Real-time factor of the SMP-MRO Drake simulation, Cases 1-3 (Nakamura & Sekiyama, IEEE
Access, §V).

For each case (and each packaged seeded scenario named by ``--scenarios``, e.g.
``case3_camera``: friction grasps and camera perception, run with the draw of ``--seed``):
plan + verify once, then simulate the grown tree in the Drake diagram with
the packaged settings (SAP, 10 ms step) and, side by side, the measured reference
setting (5 ms step), and the same tree in the symbolic peer `tamp.bt.SymbolicWorld`
(effects applied instantly: what the physics and the skills cost on top).

Reports sim time, wall time, process CPU time, and the real-time factors sim/wall and
sim/CPU. On a shared machine the wall figure depends on what else runs (the load average
is printed); the CPU figure is what the simulation itself costs. Target: >= 5x.

    python benchmarks/sim_smp.py [--cases 1 2 3] [--scenarios case3_camera] [--seed 0]
                                 [--repeat 1] [--no-peer] [--out FILE.json]

Prints a table and one JSON line.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")


def run_drake(scenario, time_step: float, seed: int = 0) -> dict:
    from tamp.rg import plan
    from tamp.sim.smp.perturb import perturb
    from tamp.sim.smp.runner import SimRunner
    from tamp.sim.smp.simulate import make_tree
    from tamp.sim.smp.station import build_station

    sc = dataclasses.replace(
        scenario, plant=dataclasses.replace(scenario.plant, time_step=time_step)
    )
    tree = make_tree(sc, plan(sc.demo, sc.planner.cost))
    run_sc, _ = perturb(sc, seed)  # the seeded files' draw (nothing drawn for Cases 1-3)
    t0 = time.perf_counter()
    system = build_station(run_sc, tree)
    runner = SimRunner(system)
    build = time.perf_counter() - t0
    res = runner.run()
    return {
        "time_step": time_step,
        "status": res.status,
        "goals_on_plant": all(res.goals.values()),
        "actions": len(res.executed),
        "sim_time": round(res.sim_time, 2),
        "wall_time": round(res.wall_time, 3),
        "cpu_time": round(res.cpu_time, 3),
        "rtf_wall": round(res.realtime_factor, 2),
        "rtf_cpu": round(res.cpu_realtime_factor, 2),
        "build_time": round(build, 3),
    }


def run_symbolic(scenario) -> dict:
    from tamp.bt import SymbolicWorld
    from tamp.rg import plan
    from tamp.sim.smp.simulate import make_tree, verification_events

    tree = make_tree(scenario, plan(scenario.demo, scenario.planner.cost))
    world = SymbolicWorld(scenario.demo.initial_world(), events=verification_events(scenario))
    t0 = time.perf_counter()
    status = tree.run(world, step=world.step)
    wall = time.perf_counter() - t0
    return {
        "status": status.value,
        "actions": len(tree.executed),
        "ticks": tree.stats.ticks,
        "wall_time": round(wall, 4),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, nargs="*", default=[1, 2, 3])
    ap.add_argument(
        "--scenarios",
        nargs="*",
        default=[],
        help="packaged seeded scenarios too (e.g. case3_camera: friction grasps, camera)",
    )
    ap.add_argument("--seed", type=int, default=0, help="the seeded scenarios' draw")
    ap.add_argument("--out", help="also write the JSON document to this file")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-peer", action="store_true", help="skip the 5 ms and symbolic runs")
    args = ap.parse_args()

    from tamp.sim.smp.scenario import load_scenario, scenario_path
    from tamp.sim.smp.simulate import prepare

    rows = []
    names = [f"case{c}" for c in args.cases] + list(args.scenarios)
    for case in names:
        scenario = load_scenario(scenario_path(f"{case}.yaml"))
        t0 = time.perf_counter()
        prepare(scenario, verify=True)
        verify = time.perf_counter() - t0
        for rep in range(args.repeat):
            row = {"case": case, "repeat": rep, "plan_verify_time": round(verify, 3)}
            row["drake"] = run_drake(scenario, scenario.plant.time_step, args.seed)
            if not args.no_peer:
                row["drake_5ms"] = run_drake(scenario, 0.005, args.seed)
                row["symbolic"] = run_symbolic(scenario)
            row["load_avg"] = round(os.getloadavg()[0], 2)
            rows.append(row)

    print(
        f"{'case':>12} {'step':>6} {'status':>8} {'acts':>4} {'sim s':>7} {'wall s':>7} "
        f"{'cpu s':>6} {'RTF wall':>8} {'RTF cpu':>8} {'load':>5}"
    )
    for r in rows:
        for key in ("drake", "drake_5ms"):
            if key not in r:
                continue
            d = r[key]
            print(
                f"{r['case']:>12} {d['time_step'] * 1000:>4.0f}ms {d['status']:>8} "
                f"{d['actions']:>4} {d['sim_time']:>7.1f} {d['wall_time']:>7.2f} "
                f"{d['cpu_time']:>6.2f} {d['rtf_wall']:>7.1f}x {d['rtf_cpu']:>7.1f}x "
                f"{r['load_avg']:>5.1f}"
            )
        if "symbolic" in r:
            s = r["symbolic"]
            print(
                f"{r['case']:>12} {'symb':>6} {s['status']:>8} {s['actions']:>4} "
                f"{'-':>7} {s['wall_time']:>7.3f}  (SymbolicWorld peer, {s['ticks']} ticks)"
            )
    summary = {
        "benchmark": "sim_smp",
        "machine": f"{platform.machine()} {os.cpu_count()} cpus",
        "target_rtf": 5.0,
        "rows": rows,
    }
    print(json.dumps(summary))
    if args.out:
        Path(args.out).write_text(json.dumps(summary, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
