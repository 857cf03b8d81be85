"""Wall time of a whole ``tamp refine`` per task and the simulation's real-time factor.

For each packaged task (Figueroa Heredia et al. 2018, Tasks 1-4): the four phases plus the
tuning run, each
simulated in the workcell (SAP, 10 ms step, Channels/state machines/supervisor on the same
tick). Reports the task time of each phase (sim seconds, measured), whether each kept
phase met the goal on the plant, what each kept, the rate kept, the reduction beside the
paper's, the whole refinement's JSON (every attempt: what it tried, measured, kept), the total
sim time, wall and process CPU time, and the real-time factors sim/wall and sim/CPU. On a
shared machine the wall figure depends on what else runs (the load average is printed);
the CPU figure is the simulation's own cost.

    python benchmarks/refine.py [--tasks 1 2 3 4] [--category II] [--scale base|all]
                                [--out rows.jsonl]

Prints a table and one JSON line.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")

PAPER = {1: -0.703, 2: -0.736, 3: -0.542, 4: -0.642}  # reductions (Fig. 12, Fig. 14)


def run_task(n: int, category: str | None, scale: str) -> dict:
    from tamp.refine.architecture import default_architecture
    from tamp.refine.loader import load_program
    from tamp.refine.refinement import refine
    from tamp.sim.refine.simulate import simulate
    from tamp.verification.gate import gate_program
    from tamp.verification.refine import check_run

    program = load_program(f"task{n}")
    wall0, cpu0 = time.perf_counter(), time.process_time()
    out = refine(
        program,
        default_architecture(),
        simulate,
        gate=gate_program,
        check_run=check_run,
        category=category,
        scale=scale,
    )
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    sim = out.sim_time
    return {
        "task": n,
        "scale": scale,
        "phases": {p.name: round(p.task_time, 1) for p in out.phases},
        "goal_met": {p.name: p.run.outcome.achieved for p in out.phases},
        "kept": {p.name: p.kept for p in out.phases},
        "rate_hz": out.rate_hz,
        "reduction": round(-out.reduction, 4),
        "paper_reduction": PAPER[n],
        "sim_time": round(sim, 1),
        "wall_time": round(wall, 1),
        "cpu_time": round(cpu, 1),
        "realtime_factor": round(sim / wall, 2),
        "cpu_realtime_factor": round(sim / cpu, 2),
        "refinement": out.to_json(),  # every attempt, the timelines: also a --from-log log
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--category", choices=("I", "II", "III"))
    ap.add_argument("--scale", choices=("base", "all"), default="base", help="Step 3")
    ap.add_argument("--out", help="also write each task's row to this JSON-lines file")
    args = ap.parse_args()
    rows = []
    for n in args.tasks:
        rows.append(run_task(n, args.category, args.scale))
        if args.out:
            with open(args.out, "a") as f:
                f.write(json.dumps(rows[-1]) + "\n")
    print(
        f"{'task':>4} {'scale':>5} {'original':>9} {'parallel':>9} {'speed':>9} {'rate':>9} "
        f"{'Hz':>4} {'ours':>7} {'paper':>7} {'sim s':>7} {'wall s':>7} {'RTF':>5} {'CPU RTF':>7}"
    )
    for r in rows:
        ph = list(r["phases"].values())
        print(
            f"{r['task']:>4} {r['scale']:>5} "
            + " ".join(f"{t:9.1f}" for t in ph)
            + f" {r['rate_hz']:4g} {r['reduction']:+7.1%} {r['paper_reduction']:+7.1%}"
            f" {r['sim_time']:7.0f} {r['wall_time']:7.0f} {r['realtime_factor']:5.1f}"
            f" {r['cpu_realtime_factor']:7.1f}"
        )
    print(
        json.dumps(
            {
                "benchmark": "refine",
                "machine": platform.processor() or platform.machine(),
                "load_average": os.getloadavg()[0],
                "rows": rows,
            }
        )
    )


if __name__ == "__main__":
    main()
