"""Optimal goal order: our RG search vs Fast Downward (unified-planning, optimal A* + LM-cut).

Instances: `tamp.demo.cyclic_swap(n)` — n objects each move to the next one's start place
via their own buffer area (2n goals); action cost = travel distance. Both planners get the
same metric: distances rounded *up* to whole millimetres (integers, as Fast Downward needs;
rounding up keeps the triangle inequality). Fast Downward gets the same task as PDDL:
objects may only go to their buffer, then (once buffered) to their target; a place holds
one object; the robot drives between places (cost = distance), picks and places. Once it
runs past its limit, it is not run on the larger sizes.

    python benchmarks/rg_vs_planner.py                 # n = 3 ... 24, FD limit 300 s
    python benchmarks/rg_vs_planner.py --sizes 3 5 8 --fd-timeout 120
    python benchmarks/rg_vs_planner.py --fd-max 8 --fd-timeout 120   # the peer up to n = 8
    python benchmarks/rg_vs_planner.py --no-fd --layout ring --sizes 8 12 16
    python benchmarks/rg_vs_planner.py --baseline /tmp/old   # beside an older tamp checkout

``--baseline DIR``: also time the search of the ``tamp`` package found in DIR (e.g. made by
``git archive REV tamp | tar -x -C DIR``), each size in a fresh process, in the same run.
Prints a table and one JSON line (``{"benchmark": "rg_vs_planner", "rows": [...]}``);
``--out FILE`` also writes the JSON there. Times: ``time_s`` wall, ``cpu_s`` process CPU.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

from tamp.demo import cyclic_swap
from tamp.rg.costs import CostModel
from tamp.rg.search import OrderProblem, astar
from tamp.world import Point


def mm(a: Point, b: Point) -> float:
    """Planar distance in whole millimetres, rounded up."""
    return float(math.ceil(1000.0 * a.planar_distance(b) - 1e-9))


def ours(n: int, layout: str) -> dict:
    demo = cyclic_swap(n, layout=layout)
    c0, t0 = time.process_time(), time.perf_counter()
    problem = OrderProblem(demo, CostModel("distance", 1.0, 0.0, mm))
    result = astar(problem)
    dt, cpu = time.perf_counter() - t0, time.process_time() - c0
    assert result is not None
    return {"cost": result.cost, "time_s": dt, "cpu_s": cpu, "expanded": result.expanded}


def baseline(n: int, layout: str, src: str) -> dict:
    """`ours` with the ``tamp`` package of ``src``, in a fresh process (warm-up included)."""
    env = {**os.environ, "PYTHONPATH": os.path.abspath(src)}
    argv = [sys.executable, __file__, "--sizes", str(n), "--layout", layout, "--no-fd"]
    out = subprocess.run([*argv, "--quiet"], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])["rows"][0]["ours"]


def fast_downward(n: int, layout: str, timeout: float) -> dict:
    """Solve the same instance with Fast Downward's optimal configuration."""
    import unified_planning.shortcuts as up
    from unified_planning.engines import PlanGenerationResultStatus as S

    up.get_environment().credits_stream = None
    demo = cyclic_swap(n, layout=layout)
    Loc, Obj = up.UserType("Loc"), up.UserType("Obj")
    robot_at = up.Fluent("robot_at", up.BoolType(), l=Loc)
    at = up.Fluent("at", up.BoolType(), o=Obj, l=Loc)
    holding = up.Fluent("holding", up.BoolType(), o=Obj)
    hand_empty = up.Fluent("hand_empty", up.BoolType())
    occupied = up.Fluent("occupied", up.BoolType(), l=Loc)
    buffered = up.Fluent("buffered", up.BoolType(), o=Obj)
    is_buffer = up.Fluent("is_buffer", up.BoolType(), o=Obj, l=Loc)
    is_target = up.Fluent("is_target", up.BoolType(), o=Obj, l=Loc)
    dist = up.Fluent("dist", up.IntType(), a=Loc, b=Loc)

    points = {"home": demo.robot_start.pos}
    for o, p in demo.objects.items():
        points[f"P_{o}"] = p
    for g in demo.goals[:n]:
        points[f"F_{g.object}"] = g.pos
    locs = {name: up.Object(name, Loc) for name in points}
    objs = {o: up.Object(o, Obj) for o in demo.objects}

    move = up.InstantaneousAction("move", a=Loc, b=Loc)
    a, b = move.parameters
    move.add_precondition(robot_at(a))
    move.add_precondition(up.Not(up.Equals(a, b)))
    move.add_effect(robot_at(a), False)
    move.add_effect(robot_at(b), True)
    pick = up.InstantaneousAction("pick", o=Obj, l=Loc)
    o, l = pick.parameters
    for c in (robot_at(l), at(o, l), hand_empty):
        pick.add_precondition(c)
    pick.add_effect(at(o, l), False)
    pick.add_effect(occupied(l), False)
    pick.add_effect(hand_empty, False)
    pick.add_effect(holding(o), True)
    places = []
    for kind in ("buffer", "target"):
        act = up.InstantaneousAction(f"place_{kind}", o=Obj, l=Loc)
        o, l = act.parameters
        act.add_precondition(robot_at(l))
        act.add_precondition(holding(o))
        act.add_precondition(up.Not(occupied(l)))
        if kind == "buffer":
            act.add_precondition(is_buffer(o, l))
            act.add_effect(buffered(o), True)
        else:
            act.add_precondition(is_target(o, l))
            act.add_precondition(buffered(o))
        act.add_effect(at(o, l), True)
        act.add_effect(occupied(l), True)
        act.add_effect(holding(o), False)
        act.add_effect(hand_empty, True)
        places.append(act)

    problem = up.Problem(f"cyclic_swap_{n}")
    for f, default in (
        (robot_at, False),
        (at, False),
        (holding, False),
        (hand_empty, False),
        (occupied, False),
        (buffered, False),
        (is_buffer, False),
        (is_target, False),
        (dist, 0),
    ):
        problem.add_fluent(f, default_initial_value=default)
    for act in (move, pick, *places):
        problem.add_action(act)
    problem.add_objects([*locs.values(), *objs.values()])
    problem.set_initial_value(robot_at(locs["home"]), True)
    problem.set_initial_value(hand_empty, True)
    for name_a, pa in points.items():
        for name_b, pb in points.items():
            problem.set_initial_value(dist(locs[name_a], locs[name_b]), int(mm(pa, pb)))
    names = list(demo.objects)
    for i, obj in enumerate(names):
        problem.set_initial_value(at(objs[obj], locs[f"P_{obj}"]), True)
        problem.set_initial_value(occupied(locs[f"P_{obj}"]), True)
        problem.set_initial_value(is_buffer(objs[obj], locs[f"F_{obj}"]), True)
        target = f"P_{names[(i + 1) % n]}"
        problem.set_initial_value(is_target(objs[obj], locs[target]), True)
        problem.add_goal(at(objs[obj], locs[target]))
    costs = {move: dist(a, b), pick: up.Int(0), places[0]: up.Int(0), places[1]: up.Int(0)}
    problem.add_quality_metric(up.MinimizeActionCosts(costs))

    here = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:  # FD's translator writes output.sas to cwd
        os.chdir(scratch)
        try:
            t0 = time.perf_counter()
            with up.OneshotPlanner(name="fast-downward-opt") as planner:
                res = planner.solve(problem, timeout=timeout)
            dt = time.perf_counter() - t0
        finally:
            os.chdir(here)
    if res.status not in (S.SOLVED_OPTIMALLY, S.SOLVED_SATISFICING) or res.plan is None:
        return {"cost": None, "time_s": dt, "status": res.status.name}
    cost = 0
    for ai in res.plan.actions:
        if ai.action.name == "move":
            pa, pb = (points[str(p)] for p in ai.actual_parameters)
            cost += int(mm(pa, pb))
    return {"cost": float(cost), "time_s": dt, "status": res.status.name}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[3, 5, 8, 10, 12, 16, 20, 24])
    ap.add_argument("--fd-timeout", type=float, default=300.0)
    ap.add_argument("--no-fd", action="store_true", help="skip the Fast Downward peer")
    ap.add_argument(
        "--fd-max", type=int, metavar="N", help="run the Fast Downward peer only up to size N"
    )
    ap.add_argument("--layout", default="shelf", choices=("shelf", "staging", "ring"))
    ap.add_argument("--baseline", metavar="DIR", help="also time the tamp package in DIR")
    ap.add_argument("--out", metavar="FILE", help="also write the JSON document to FILE")
    ap.add_argument("--quiet", action="store_true", help="print the JSON line only")
    args = ap.parse_args(argv)

    def say(text: str) -> None:
        if not args.quiet:
            print(text, flush=True)

    ours(3, args.layout)  # warm-up: imports and first-call costs stay out of the table
    rows = []
    header = (
        f"{'n':>3} {'goals':>5} {'ours cost':>11} {'ours cpu s':>10}"
        + (f" {'base cpu s':>10}" if args.baseline else "")
        + f" {'FD cost':>11} {'FD s':>9} {'speed-up':>9}"
    )
    say(f"layout={args.layout}; costs in mm (rounded up); cpu s = process CPU seconds")
    say(header)
    say("-" * len(header))
    fd_over = None  # the size at which Fast Downward first ran past its limit
    for n in args.sizes:
        row = {"n": n, "goals": 2 * n, "layout": args.layout, "ours": ours(n, args.layout)}
        if args.baseline:
            row["baseline"] = baseline(n, args.layout, args.baseline)
            row["same_cost_as_baseline"] = abs(row["baseline"]["cost"] - row["ours"]["cost"]) < 0.5
        fd = None
        above = args.fd_max is not None and n > args.fd_max
        if not args.no_fd and fd_over is None and not above:
            fd = fast_downward(n, args.layout, args.fd_timeout)
            row["fd"] = fd
            if fd["cost"] is None:
                fd_over = n
        elif not args.no_fd:
            why = f"past its limit at n = {fd_over}" if fd_over else f"above --fd-max {args.fd_max}"
            row["fd"] = {"cost": None, "status": f"not run: {why}"}
        o = row["ours"]
        fd_cost = f"{fd['cost']:.0f}" if fd and fd["cost"] is not None else "-"
        fd_time = (
            f"{fd['time_s']:.2f}" if fd and fd["cost"] is not None else (">limit" if fd else "-")
        )
        speed = f"{fd['time_s'] / o['time_s']:.0f}x" if fd and fd["cost"] is not None else "-"
        if fd and fd["cost"] is not None:
            row["same_cost"] = abs(fd["cost"] - o["cost"]) < 0.5
        base = f" {row['baseline']['cpu_s']:>10.3f}" if args.baseline else ""
        say(
            f"{n:>3} {2 * n:>5} {o['cost']:>11.0f} {o['cpu_s']:>10.3f}{base} {fd_cost:>11} "
            f"{fd_time:>9} {speed:>9}"
        )
        rows.append(row)
    doc = {
        "benchmark": "rg_vs_planner",
        "machine": {"cpus": os.cpu_count(), "load_1min": os.getloadavg()[0]},
        "rows": rows,
    }
    print(json.dumps(doc))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(doc, fh, indent=1)
            fh.write("\n")
    ok = all(r.get("same_cost", True) and r.get("same_cost_as_baseline", True) for r in rows)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
