"""``tamp simulate smp-mro``: run an SMP-MRO case in the Drake simulation (seed §V).

    tamp simulate smp-mro --case 1|2|3 [--scenario FILE] [--record out.html] [--json]
                          [--appear OBJ@PLACE[@WHEN]] [--fail ACTION[(ARGS)][xTIMES]]
                          [--meshcat] [--rate R] [--no-verify] [--max-sim-time S]

Plans the order (RG + A*), passes the verification gate, then simulates the youBot-like
robot executing the grown behavior tree. Prints the executed actions with their sim
start/end times, the final object poses (from the plant), sim time, wall time and the
real-time factor. The status line is the one verdict (`tamp.sim.smp.runner.judge`):
SUCCESS when the tree succeeded and every object rests in its final goal area on the plant
in 3-D (inside it and upright on the floor, not on top of another object). Exit 0 on
SUCCESS, 1 otherwise (FAILURE, TIMEOUT, or when verification fails), 2 on a bad scenario
or flag (an appearance at time 0 onto an occupied place included). ``--json`` has the same
``status``; its ``ok`` is ``status == "SUCCESS"``.

    tamp simulate lots --task TASK.yaml [--scenario CELL.yaml] [--grasp hrgnet|grconvnet|ggcnn]
                       [--interference EVENTS.yaml] [--seed N] [--record out.html]
                       [--max-sim-time S] [--json]

Runs a LOTS task by the LOTS controller inside the Drake workcell (`tamp.sim.lots.simulate`);
exit 0 only when the plant's W^B ends a round of the task. ``--interference``: the same script
as ``tamp lots --interference``, carried out by a scripted person's hand in the cell
(`tamp.sim.lots.person`); a bad file exits 2 naming the field.
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
    add_seed(s)
    add_event_arguments(s)
    add_no_verify(s)
    s.add_argument("--max-sim-time", type=float, help="override the scenario's time limit (s)")
    s.add_argument("--json", action="store_true", help="machine-readable output")
    s.set_defaults(func=run)
    register_lots(sub)


def register_lots(sub) -> None:
    """``tamp simulate lots``: a LOTS task in the Drake workcell (seed 003)."""
    s = sub.add_parser(
        "lots",
        help="LOTS task in the Drake workcell (arm with wrist camera, LOTS controller)",
        description=(
            "Run a LOTS task (tamp lots' TASK.yaml) by the LOTS controller inside the Drake "
            "workcell; the verdict is measured on the plant. Exit 0 when the plant's W^B ends a "
            "round of the task, 1 otherwise, 2 on bad input."
        ),
    )
    s.add_argument("--task", required=True, help="LTL task file or packaged task name")
    s.add_argument(
        "--scenario",
        help="workcell scenario file (default: the packaged lots_sim scenario of the task's name)",
    )
    s.add_argument(
        "--interference",
        metavar="EVENTS.yaml",
        help="human interference script: a scripted person's hand carries it out",
    )
    s.add_argument("--grasp", choices=("hrgnet", "grconvnet", "ggcnn"), help="grasp network")
    add_seed(s, "and of the LOTS controller's tree update")
    s.add_argument("--record", metavar="HTML", help="write a Meshcat animation (static HTML)")
    s.add_argument("--max-sim-time", type=float, help="override the scenario's time limit (s)")
    s.add_argument("--json", action="store_true", help="machine-readable output")
    s.set_defaults(func=run_lots)


def add_seed(parser, also: str = "") -> None:
    """``--seed N``: the run's draw of the scenario's ``perturbation`` section (same seed,
    same run, bit for bit on one machine)."""
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        help=" ".join(["seed of the scenario's perturbation draw", also, "(default 0)"]).replace(
            "  ", " "
        ),
    )


def check_common(args: argparse.Namespace) -> None:
    """The flags every ``tamp simulate`` system has, checked before any work is done."""
    import math
    import os

    from tamp.errors import InputError

    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    from tamp.perturbation import check_seed

    check_seed(args.seed)
    if args.max_sim_time is not None and not (
        math.isfinite(args.max_sim_time) and args.max_sim_time > 0
    ):
        raise InputError(
            f"must be a positive number of seconds, got {args.max_sim_time}", field="--max-sim-time"
        )
    if args.record:
        output_file(args.record, "--record", make_parents=True)


def run_lots(args: argparse.Namespace) -> int:
    from tamp.errors import InputError
    from tamp.lots.task import load_events, load_task
    from tamp.scenarios import resolve
    from tamp.sim.lots.scenario import load_cell_scenario
    from verification import gate

    check_common(args)
    task = load_task(args.task)
    events = load_events(args.interference, task) if args.interference else None
    if args.scenario is None and not resolve(task.name, "lots_sim").is_file():
        raise InputError(
            f"no packaged workcell scenario for task {task.name!r}: give one", field="--scenario"
        )
    scenario = load_cell_scenario(args.scenario or task.name)
    from tamp.sim.lots.simulate import check_person_classes, simulate_lots

    if events:
        check_person_classes(events)

    progress(f"simulating task {task.name} in workcell {scenario.name}", quiet=args.json)
    result = simulate_lots(
        scenario,
        task,
        events,
        grasp=args.grasp,
        seed=args.seed,
        record=args.record,
        max_sim_time=args.max_sim_time,
        check=gate,
    )
    if args.json:
        print_json(result.to_json())
        return result.exit_code
    print(f"task {task.name}: {task.formula}  (workcell {scenario.name}, grasp {result.network})")
    print(f"{'skill':<22} {'start':>8} {'end':>8}  status")
    for a in result.actions:
        end = "-" if a.end is None else f"{a.end:8.2f}"
        print(f"{a.action:<22} {a.start:8.2f} {end:>8}  {a.outcome}  {a.detail}")
    for a in result.robot_actions:
        print(f"  {a.index:2d}. {a.text()}")
    for p in result.person_actions:
        end = "-" if p.end is None else f"{p.end:.2f}"
        what = f"{p.uid or '-'} {p.src}→{p.dst}"
        print(
            f"  person: {p.event.describe()} {p.event.when()}: {what} {p.start:.2f}–{end} s, "
            f"{p.outcome}{' (' + p.detail + ')' if p.detail else ''}"
        )
    for e in result.never_happened:
        print(e.never_happened())
    c = result.final_counts
    print(f"final (plant): W^A {c['A']}  W^B {c['B']}  waste {c['waste']}")
    if result.elsewhere:
        print(f"elsewhere: {', '.join(result.elsewhere)}")
    for stop in result.safety_stops:
        print(
            f"safety stop at {stop.time:.2f} s: {stop.cause} ({stop.detail}), "
            f"held {stop.duration:.2f} s"
        )
    g = result.grasps
    print(
        f"replans {result.replans}, grasps {g['successes']}/{g['attempts']}, "
        f"frames {result.frames_rendered}, safety stops {len(result.safety_stops)}"
    )
    if scenario.perturbation.fields():
        print(f"seed {result.seed}: perturbation size {result.perturbation['size']:.3f} m")
    if result.cause is not None:
        print(f"cause: {result.cause}")
    verdict = "task satisfied" if result.satisfied else f"task NOT satisfied: {result.reason}"
    print(
        f"{result.status}: {verdict}; sim {result.sim_time:.2f} s, wall {result.wall_time:.2f} s, "
        f"real-time factor {result.rtf:.2f}x"
    )
    if result.recording:
        print(f"recording: {result.recording}")
    return result.exit_code


def run(args: argparse.Namespace) -> int:
    import math

    from tamp.errors import InputError
    from tamp.sim.smp.scenario import load_scenario, scenario_path
    from tamp.sim.smp.simulate import run_json, simulate_smp_mro

    check_common(args)
    if args.rate is not None and not (math.isfinite(args.rate) and args.rate >= 0):
        raise InputError(f"must be >= 0 (0: as fast as possible), got {args.rate}", field="--rate")
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
        seed=args.seed,
        verify=not args.no_verify,
        meshcat=meshcat,
        record=args.record,
        max_sim_time=args.max_sim_time,
        realtime_rate=args.rate if args.rate is not None else (1.0 if args.meshcat else 0.0),
    )
    if args.json:
        print_json(run_json(result, prepared))
        return result.exit_code
    print(f"scenario {scenario.name}: order {' -> '.join(prepared.plan.order)}", end="")
    if prepared.reports:
        print(f"  (verified: {', '.join(prepared.reports)})")
    else:
        print("  (not verified)")
    print(f"{'action':<22} {'start':>8} {'end':>8}  status")
    for a in result.actions:
        end = "-" if a.end is None else f"{a.end:8.2f}"
        print(f"{a.action:<22} {a.start:8.2f} {end:>8}  {a.outcome}")
    print("final object poses (plant, m / rad):")
    for uid, p in sorted(result.final_poses.items()):
        print(f"  {uid:<4} x={p.x:7.3f} y={p.y:7.3f} z={p.z:6.3f} yaw={p.yaw:6.2f}")
    for goal, inside in result.goals.items():
        print(f"  {goal}: {'inside' if inside else 'NOT inside'}")
    for w in result.warnings:
        print(f"warning: {w}")
    for t, action, cause, detail in result.failures:
        print(f"skill failure: t={t:.2f} s {action}: {cause} ({detail})")
    if scenario.perturbation.fields():
        p = result.perturbation
        mu = "as modelled" if p["friction"] is None else f"{p['friction']:.3f}"
        print(
            f"seed {result.seed}: perturbation size {p['size']:.3f} m (largest object "
            f"displacement), robot moved {p['robot_displacement']:.3f} m, friction "
            f"{mu}, grasp {result.grasp}, perception {result.perception}"
        )
    if result.cause is not None:
        print(f"cause: {result.cause}")
    print(
        f"{result.status}: {result.reason}; sim {result.sim_time:.2f} s, "
        f"wall {result.wall_time:.2f} s, real-time factor {result.realtime_factor:.1f}x "
        f"(CPU {result.cpu_time:.2f} s: {result.cpu_realtime_factor:.1f}x)"
    )
    if result.recording:
        print(f"recording: {result.recording}")
    return result.exit_code
