"""Cost of a whole ``tamp refine`` per task, before and after a change, in one run.

For each packaged task (Figueroa Heredia et al. 2018, Tasks 1-4): the whole refinement
(every phase simulated in the workcell, Fig. 5's rate search included) runs in a child
process of its own, once on this checkout and, with ``--before DIR``, once on another
checkout of the project (e.g. ``git worktree add --detach /tmp/before <commit>``), so the
two are measured by the same script on the same machine at the same time. Each row: the
task time of each phase (sim seconds), whether each kept phase met the goal on the plant,
the rates kept, the reduction beside the paper's, the runs' total sim time, the child's
process CPU time and wall time, and the real-time factors sim/wall and sim/CPU. On a
shared machine the wall figure depends on what else runs (the load average is printed);
the CPU figure is the refinement's own cost.

    python benchmarks/refine.py [--tasks 4 1 2 3] [--category II] [--scale base|all]
                                [--before DIR] [--out result.json] [--rows rows.jsonl]

Prints a table and writes (``--out``) one JSON document with every row, each with the
whole refinement's JSON (every attempt: what it tried, measured, kept; also a log for
``tamp refine --from-log``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")

PAPER = {1: -0.703, 2: -0.736, 3: -0.542, 4: -0.642}  # reductions (Fig. 12, Fig. 14)
HERE = Path(__file__).resolve().parent.parent

#: One refinement in a child process, on whatever ``tamp`` its PYTHONPATH finds (the API
#: it uses is the same before and after); prints one JSON line.
CHILD = """
import json, sys, time
task, category, scale = int(sys.argv[1]), sys.argv[2] or None, sys.argv[3]
wall0, cpu0 = time.perf_counter(), time.process_time()
from tamp.refine.refinement import refine
from tamp.sim.refine.scenario import load_scenario
from tamp.sim.refine.simulate import simulate
from tamp.verification.gate import gate_program
from tamp.verification.refine import check_run
s = load_scenario(f"task{task}")
def measure(p, a, **kw):
    return simulate(p, a, scene=s.scene, **kw)
out = refine(s.program, s.architecture, measure, gate=gate_program, check_run=check_run,
             category=category, scale=scale)
wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
print(json.dumps({"wall": wall, "cpu": cpu, "refinement": out.to_json(),
                  "goal_met": {p.name: p.run.outcome.achieved for p in out.phases},
                  "kept": {p.name: p.kept for p in out.phases}}))
"""


def run_task(n: int, category: str | None, scale: str, tree: Path) -> dict:
    """The whole refinement of Task ``n`` on the checkout ``tree``, in a child process."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    cmd = [sys.executable, "-c", CHILD, str(n), category or "", scale]
    done = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"task {n} on {tree} failed:\n{done.stderr[-2000:]}")
    child = json.loads(done.stdout.strip().splitlines()[-1])
    doc = child["refinement"]
    sim = doc["sim_time"]
    return {
        "task": n,
        "tree": str(tree),
        "scale": scale,
        "phases": {p["name"]: round(p["task_time"], 1) for p in doc["phases"]},
        "goal_met": child["goal_met"],
        "kept": child["kept"],
        "rate_hz": doc["rate_hz"],
        "reduction": round(-doc["reduction"], 4),
        "paper_reduction": PAPER[n],
        "runs": len(doc["attempts"]) + (1 if doc.get("rate_search", "online") == "online" else 0),
        "sim_time": round(sim, 1),
        "wall_time": round(child["wall"], 1),
        "cpu_time": round(child["cpu"], 1),
        "realtime_factor": round(sim / child["wall"], 2),
        "cpu_realtime_factor": round(sim / child["cpu"], 2),
        "refinement": doc,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, nargs="+", default=[4, 1, 2, 3])
    ap.add_argument("--category", choices=("I", "II", "III"))
    ap.add_argument("--scale", choices=("base", "all"), default="base", help="Step 3")
    ap.add_argument("--before", type=Path, help="another checkout to measure beside this one")
    ap.add_argument("--out", help="write the whole result (JSON) to this file")
    ap.add_argument("--rows", help="also append each row to this JSON-lines file")
    args = ap.parse_args()
    trees = [("before", args.before.resolve())] if args.before else []
    trees.append(("after" if args.before else "this", HERE))
    load0 = os.getloadavg()[0]
    rows = []
    for n in args.tasks:
        for label, tree in trees:
            row = {"label": label, **run_task(n, args.category, args.scale, tree)}
            rows.append(row)
            print(
                f"task {n} {label}: {row['cpu_time']} s CPU, {row['wall_time']} s wall", flush=True
            )
            if args.rows:
                with open(args.rows, "a") as f:
                    f.write(json.dumps(row) + "\n")
    print(
        f"{'task':>4} {'code':>6} {'original':>9} {'parallel':>9} {'speed':>9} {'rate':>9} "
        f"{'Hz':>4} {'ours':>7} {'paper':>7} {'runs':>4} {'sim s':>6} {'CPU s':>6} "
        f"{'wall s':>6} {'sim/CPU':>7}"
    )
    for r in rows:
        ph = list(r["phases"].values())
        print(
            f"{r['task']:>4} {r['label']:>6} "
            + " ".join(f"{t:9.1f}" for t in ph)
            + f" {r['rate_hz']:4g} {r['reduction']:+7.1%} {r['paper_reduction']:+7.1%}"
            f" {r['runs']:4d} {r['sim_time']:6.0f} {r['cpu_time']:6.1f} {r['wall_time']:6.1f}"
            f" {r['cpu_realtime_factor']:7.1f}"
        )
    if args.before:
        for n in args.tasks:
            b, a = (
                next(r for r in rows if r["task"] == n and r["label"] == x)
                for x in ("before", "after")
            )
            print(
                f"task {n}: CPU {b['cpu_time']:.1f} -> {a['cpu_time']:.1f} s "
                f"({b['cpu_time'] / a['cpu_time']:.1f}x), wall {b['wall_time']:.1f} -> "
                f"{a['wall_time']:.1f} s; phases {list(b['phases'].values())} -> "
                f"{list(a['phases'].values())}"
            )
    doc = {
        "benchmark": "refine",
        "command": "python " + " ".join(sys.argv),
        "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "load_average": [round(load0, 2), round(os.getloadavg()[0], 2)],
        "rows": rows,
    }
    if args.out:
        Path(args.out).write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
