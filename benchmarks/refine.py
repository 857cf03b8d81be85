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
                                [--profile SECONDS] [--rates ARCHITECTURE]

``--profile`` runs, instead of the refinements, the first seconds of each task's original
run on each checkout, timed and then under cProfile: sim seconds per CPU second, and the
share of the profile spent in Drake's own step against the project's Python LeafSystems
(the channels' queues, the state machines, the sensors, the supervisor, the contact
monitor).

``--rates FILE`` prints, instead, Fig. 5's rate per behavior of each task's program in every
category under the architecture file (`tamp.refine.architecture.behavior_searches`: the
queue model, no simulation): what that modelled architecture predicts.

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


#: The first seconds of a task's original run under cProfile, in a child process: where the
#: CPU goes (Drake's C++ step, counted as the simulator's own time, against the Python
#: LeafSystems' callbacks); prints one JSON line.
PROFILE = """
import cProfile, json, pstats, sys, time
task, seconds = int(sys.argv[1]), float(sys.argv[2])
from tamp.sim.refine.scenario import load_scenario
from tamp.sim.refine.simulate import simulate
s = load_scenario(f"task{task}")
simulate(s.program, s.architecture, scene=s.scene, max_sim_time=0.1)  # imports, first build
cpu0 = time.process_time()
simulate(s.program, s.architecture, scene=s.scene, max_sim_time=seconds)
cpu = time.process_time() - cpu0
prof = cProfile.Profile()
prof.enable()
simulate(s.program, s.architecture, scene=s.scene, max_sim_time=seconds)
prof.disable()
st = pstats.Stats(prof)
total = sum(v[2] for v in st.stats.values())
def own(name):
    return sum(v[2] for k, v in st.stats.items() if name in k[2])
rows = sorted(((v[3], f"{k[0].rpartition('/')[2]}:{k[2]}") for k, v in st.stats.items()
               if "tamp" in k[0]), reverse=True)
top = [[name, round(t / total, 3)] for t, name in rows if "simulate" not in name][:8]
print(json.dumps({"task": task, "sim_time": seconds, "cpu": cpu,
                  "advance_own_share": round(own("AdvanceTo") / total, 3),
                  "python_callbacks_cumulative_share": top}))
"""


def profile_task(n: int, seconds: float, tree: Path) -> dict:
    """Where the CPU of ``seconds`` of Task ``n``'s original run goes (``PROFILE``)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    cmd = [sys.executable, "-c", PROFILE, str(n), str(seconds)]
    done = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"profile of task {n} on {tree} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


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


def print_rates(tasks: list[int], file: Path) -> None:
    """Fig. 5 per behavior on the queue model of ``file``, per task and category."""
    from tamp.refine.architecture import behavior_searches, load_architecture
    from tamp.refine.loader import load_program

    arch = load_architecture(file)
    for n in tasks:
        program = load_program(f"task{n}")
        for cat in ("I", "II", "III"):
            found = behavior_searches(program.with_category(cat), arch)
            rates = ", ".join(f"{k} {s.found:g}" for k, s in found.items())
            print(f"task {n} Category {cat} ({arch.name}): {rates} Hz")


def table(rows: list[dict]) -> None:
    """One line per task and checkout."""
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, nargs="+", default=[4, 1, 2, 3])
    ap.add_argument("--category", choices=("I", "II", "III"))
    ap.add_argument("--scale", choices=("base", "all"), default="base", help="Step 3")
    ap.add_argument("--before", type=Path, help="another checkout to measure beside this one")
    ap.add_argument("--out", help="write the whole result (JSON) to this file")
    ap.add_argument("--rows", help="also append each row to this JSON-lines file")
    ap.add_argument(
        "--profile",
        type=float,
        metavar="SECONDS",
        help="instead: profile this many sim seconds of each task's original run (each tree)",
    )
    ap.add_argument("--rates", type=Path, help="instead: each behavior's rate under this file")
    args = ap.parse_args()
    if args.rates:
        return print_rates(args.tasks, args.rates)
    trees = [("before", args.before.resolve())] if args.before else []
    trees.append(("after" if args.before else "this", HERE))
    load0 = os.getloadavg()[0]
    rows = []
    for n in args.tasks if not args.profile else []:
        for label, tree in trees:
            row = {"label": label, **run_task(n, args.category, args.scale, tree)}
            rows.append(row)
            print(
                f"task {n} {label}: {row['cpu_time']} s CPU, {row['wall_time']} s wall", flush=True
            )
            if args.rows:
                with open(args.rows, "a") as f:
                    f.write(json.dumps(row) + "\n")
    if rows:
        table(rows)
    if args.before and rows:
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
    profiles = []
    if args.profile:
        for n in args.tasks:
            for label, tree in trees:
                prof = {"label": label, **profile_task(n, args.profile, tree)}
                profiles.append(prof)
                print(
                    f"task {n} {label}: {prof['sim_time']:g} sim s of the original run in "
                    f"{prof['cpu']:.1f} s CPU ({prof['sim_time'] / prof['cpu']:.1f} sim s/CPU s);"
                    f" Drake's step (own time) {prof['advance_own_share']:.0%} of the profile;"
                    f" Python callbacks (cumulative): {prof['python_callbacks_cumulative_share']}"
                )
    doc = {
        "benchmark": "refine",
        "command": "python " + " ".join(sys.argv),
        "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "load_average": [round(load0, 2), round(os.getloadavg()[0], 2)],
        "rows": rows,
        "profiles": profiles,
    }
    if args.out:
        Path(args.out).write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
