"""``tamp simulate smp-mro``: run an SMP-MRO case in the Drake simulation (seed §V).

    tamp simulate smp-mro --case 1|2|3 [--scenario FILE] [--record out.html] [--json]
                          [--appear OBJ@PLACE[@WHEN]] [--fail ACTION[(ARGS)][xTIMES]]
                          [--meshcat] [--rate R] [--no-verify] [--max-sim-time S]

Plans the order (RG + A*), passes the verification gate, then simulates the youBot-like
robot executing the grown behavior tree. Prints the executed actions with their sim
start/end times, the final object poses (from the plant), sim time, wall time and the
real-time factor. Exit 0 when the tree succeeded and every object rests in its final goal
area on the plant, 1 otherwise (or when verification fails), 2 on a bad scenario.
"""

from __future__ import annotations

import argparse

from tamp.commands.events_args import add_event_arguments, events_for
from tamp.commands.output import (
    add_no_verify,
    output_file,
    print_json,
    progress,
    warn_unverified,
)


def register(subparsers) -> None:
    p = subparsers.add_parser("simulate", help="run a case in the Drake simulation")
    sub = p.add_subparsers(dest="system", metavar="SYSTEM", required=True)
    s = sub.add_parser("smp-mro", help="SMP-MRO cases 1-3 (youBot pick-and-place)")
    s.add_argument("--case", type=int, choices=(1, 2, 3), help="packaged case (default 1)")
    s.add_argument("--scenario", help="simulation scenario file (overrides --case)")
    s.add_argument("--record", metavar="HTML", help="write a Meshcat animation (static HTML)")
    s.add_argument("--meshcat", action="store_true", help="live view in a local Meshcat")
    s.add_argument(
        "--rate",
        type=float,
        help="target real-time rate (default: as fast as possible; 1.0 with --meshcat)",
    )
    add_event_arguments(s)
    add_no_verify(s)
    s.add_argument("--max-sim-time", type=float, help="override the scenario's time limit (s)")
    s.add_argument("--json", action="store_true", help="machine-readable output")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import os

    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    import math

    from tamp.errors import InputError
    from tamp.sim.smp.scenario import load_scenario, scenario_path
    from tamp.sim.smp.simulate import simulate_smp_mro

    if args.max_sim_time is not None and not (
        math.isfinite(args.max_sim_time) and args.max_sim_time > 0
    ):
        raise InputError(
            f"must be a positive number of seconds, got {args.max_sim_time}", field="--max-sim-time"
        )
    if args.rate is not None and not (math.isfinite(args.rate) and args.rate >= 0):
        raise InputError(f"must be >= 0 (0: as fast as possible), got {args.rate}", field="--rate")
    if args.record:
        output_file(args.record, "--record", make_parents=True)
    name = args.scenario or f"case{args.case or 1}.yaml"
    scenario = load_scenario(args.scenario or scenario_path(name))
    if args.appear or args.fail:
        demo = scenario.demo
        appear, fail = events_for(
            args,
            objects=[o.id for o in scenario.objects],
            areas=demo.initial_world().areas,
            domain=demo.domain(),
        )
        scenario = scenario.with_events(appear, fail)
    if args.no_verify:
        warn_unverified("tamp simulate", "the plan and its tree")
    progress(f"simulating {scenario.name} ({scenario.source})", quiet=args.json)
    meshcat = None
    if args.meshcat:
        from tamp.sim.core.recording import new_meshcat

        meshcat = new_meshcat()
        progress(f"meshcat: {meshcat.web_url()}", quiet=args.json)
    result, prepared, _ = simulate_smp_mro(
        scenario,
        verify=not args.no_verify,
        meshcat=meshcat,
        record=args.record,
        max_sim_time=args.max_sim_time,
        realtime_rate=args.rate if args.rate is not None else (1.0 if args.meshcat else 0.0),
    )
    ok = result.status == "SUCCESS" and all(result.goals.values())
    if args.json:
        payload = result.to_json()
        payload["order"] = list(prepared.plan.order)
        payload["verified"] = {k: r.holds for k, r in prepared.reports.items()}
        payload["ok"] = ok
        print_json(payload)
        return 0 if ok else 1
    print(f"scenario {scenario.name}: order {' -> '.join(prepared.plan.order)}", end="")
    if prepared.reports:
        print(f"  (verified: {', '.join(prepared.reports)})")
    else:
        print("  (not verified)")
    print(f"{'action':<22} {'start':>8} {'end':>8}  status")
    for a in result.actions:
        end = "-" if a.end is None else f"{a.end:8.2f}"
        print(f"{a.action:<22} {a.start:8.2f} {end:>8}  {a.status or 'RUNNING'}")
    print("final object poses (plant, m / rad):")
    for uid, p in sorted(result.final_poses.items()):
        print(f"  {uid:<4} x={p.x:7.3f} y={p.y:7.3f} z={p.z:6.3f} yaw={p.yaw:6.2f}")
    for goal, inside in result.goals.items():
        print(f"  {goal}: {'inside' if inside else 'NOT inside'}")
    print(
        f"{result.status}: {result.reason}; sim {result.sim_time:.2f} s, "
        f"wall {result.wall_time:.2f} s, real-time factor {result.realtime_factor:.1f}x "
        f"(CPU {result.cpu_time:.2f} s: {result.cpu_realtime_factor:.1f}x)"
    )
    if result.recording:
        print(f"recording: {result.recording}")
    return 0 if ok else 1
