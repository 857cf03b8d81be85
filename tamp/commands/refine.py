"""``tamp refine TASK.yaml``: refine a two-robot program in Drake (Figueroa Heredia et al. 2018).

    tamp refine TASK.yaml [--category I|II|III] [--scale base|all] [--json]
                          [--timeline out.svg] [--plot out.svg] [--record out.html]
                          [--diagram out.svg]
                          [--refined refined.yaml] [--no-verify] [--seed N]
                          [--from-log RUN.json|RUN.csv] [--meshcat] [--max-sim-time S]
                          [--tune-online]

Simulates the original program, then the program after each refinement phase
(parallelized, speed-adjusted, rate-refined; `tamp.refine.refinement`, every run measured
by the Drake workcell's `tamp.sim.refine.simulate.simulate`). A phase is accepted only if
its run finishes, meets the task's goal on the plant and adds no collision the original
run did not have; otherwise its change is reverted, undone or (the rate) backed off. Prints
what each phase tried, measured and kept, the reduction and the refined program (the last
accepted one; ``--refined`` writes it). Every program passes the LTL ordering gate before it is
simulated; a parallelization the property refuses is dropped. ``--from-log RUN`` refines
from a measured run's log instead (`tamp.refine.predict`: the same steps, every phase a
prediction from the logged durations; the JSON of ``tamp refine --json`` is such a log).
``--scale`` (Step 3): the rate scales the base's speed (the paper's, default) or every
section's. ``--seed N`` draws the program file's ``perturbation`` section (robot start
poses). Exit 0 when the refined program meets the goal, 1 when no accepted program does
(the original misses it) or the original cannot finish (with the reason), 2 on a bad file
or option.
"""

from __future__ import annotations

import argparse

from tamp.commands.output import add_no_verify, output_file, print_json, progress, warn_unverified
from tamp.commands.simulate import add_live_view, add_seed, check_max_sim_time
from tamp.errors import InfeasibleError


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "refine",
        help="two-robot program refinement: parallelize, adjust speed, tune the command rate",
        description=__doc__.splitlines()[0],
    )
    p.add_argument("task", help="program file (YAML, version 1) or a packaged name (task4)")
    p.add_argument("--category", choices=("I", "II", "III"), help="architecture category")
    p.add_argument(
        "--scale",
        choices=("base", "all"),
        default="base",
        help="Step 3: the new rate scales the base's speed (the paper's) or every section's",
    )
    p.add_argument(
        "--timeline",
        "--gantt",  # the 0.1 name, kept as an alias
        dest="timeline",
        metavar="FILE",
        help="draw each phase's run over sim time, Fig. 12 style (.svg, .png or .pdf; "
        "--gantt is the old name)",
    )
    p.add_argument(
        "--diagram",
        metavar="FILE",
        help="draw the original program's Drake diagram with Graphviz (.dot, .svg or .png)",
    )
    p.add_argument(
        "--plot",
        metavar="SVG",
        help="write Fig. 14-style bars of the phases' task times (Task 4: beside the paper's)",
    )
    p.add_argument("--record", metavar="HTML", help="Meshcat animation of the refined run")
    p.add_argument(
        "--refined",
        metavar="FILE.yaml",
        help="write the refined program (the last accepted one) to FILE.yaml",
    )
    add_no_verify(p)
    add_live_view(p)
    add_seed(p)
    p.add_argument(
        "--from-log",
        metavar="RUN",
        help="refine from a measured run's log (JSON or CSV; tamp refine --json writes one) "
        "without simulating: the phases are predictions",
    )
    p.add_argument(
        "--tune-online",
        action="store_true",
        help="Fig. 5 probes the publish rates in one more simulated run (per robot and trigger "
        "sensor) instead of on the architecture's queue model (per behavior)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import os

    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    from pathlib import Path

    from tamp.pictures import GRAPH_FORMATS, PLOT_FORMATS, check_picture
    from tamp.refine.loader import dump_program

    for flag, formats in (("--timeline", PLOT_FORMATS), ("--diagram", tuple(GRAPH_FORMATS))):
        path = getattr(args, flag[2:])
        if path:
            output_file(check_picture(path, flag, formats), flag, make_parents=True)
    for option, value, parents in (
        ("--plot", args.plot, True),
        ("--record", args.record, True),
        ("--refined", args.refined, True),
    ):
        if value:
            output_file(value, option, make_parents=parents)
    from tamp.perturbation import check_seed
    from tamp.sim.refine.simulate import WORKCELL

    check_seed(args.seed)
    check_max_sim_time(args.max_sim_time)
    simulated = [
        flag
        for flag, given in (
            ("--record", args.record),
            ("--meshcat", args.meshcat),
            ("--max-sim-time", args.max_sim_time is not None),
            ("--tune-online", args.tune_online),
        )
        if given
    ]
    if args.from_log and simulated:
        from tamp.errors import InputError

        raise InputError("needs a simulation; --from-log predicts without one", field=simulated[0])
    scenario, applied = WORKCELL.perturbed(WORKCELL.load(args.task), args.seed)
    program, arch, scene = scenario.program, scenario.architecture, scenario.scene
    if args.no_verify:
        warn_unverified("tamp refine", "each refined program")
    if args.diagram:
        from tamp.pictures import write_graph

        diagram = WORKCELL.build(scenario)
        write_graph(diagram.GetGraphvizString(max_depth=1), args.diagram, "--diagram")

    from tamp.refine.refinement import refine
    from tamp.sim.refine.simulate import simulate
    from tamp.verification.gate import gate_program
    from tamp.verification.refine import check_run

    viewer = None
    if args.meshcat:  # one live view that every phase's run draws into
        from tamp.sim.core.recording import new_meshcat

        viewer = new_meshcat()
        progress(f"meshcat: {viewer.web_url()}", quiet=False)

    def measure(p, a, **kw):  # every phase's run, in the live view when there is one
        if args.max_sim_time is not None and kw.get("max_sim_time") is None:
            kw["max_sim_time"] = args.max_sim_time
        if viewer is not None:
            kw["meshcat"] = viewer
        return simulate(p, a, scene=scene, **kw)

    if args.from_log:
        from tamp.refine.predict import load_log, predicting

        measure = predicting(program, load_log(args.from_log, program))
    result = refine(
        program,
        arch,
        measure,
        gate=None if args.no_verify else gate_program,
        check_run=check_run,
        category=args.category,
        scale=args.scale,
        record=args.record,
        tune_online=args.tune_online,
        progress=lambda m: progress(m, quiet=args.json),
    )
    if args.timeline:
        from tamp.refine.gantt import draw_gantt

        Path(args.timeline).parent.mkdir(parents=True, exist_ok=True)
        draw_gantt(
            [(p.name, p.run.timeline) for p in result.phases],
            args.timeline,
            title=f"{program.name}, Category {result.program.communication.category}",
        )
    if args.plot:
        from tamp.refine.gantt import PAPER_TASK4, draw_phases

        Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
        draw_phases(
            [(p.name, p.task_time) for p in result.phases],
            args.plot,
            title=f"{program.name}, Category {result.program.communication.category}",
            paper=PAPER_TASK4 if program.name == "task4" else None,
            label="ours (predicted)" if args.from_log else "ours (measured)",
        )
    if args.refined and result.goal_met:  # the last accepted program; none when none meets the goal
        Path(args.refined).parent.mkdir(parents=True, exist_ok=True)
        Path(args.refined).write_text(dump_program(result.program))
    if args.json:
        payload = result.to_json()
        refined = dump_program(result.program) if result.goal_met else None
        payload["refined_program"] = None if args.refined else refined
        payload["timeline"] = args.timeline
        payload["diagram"] = args.diagram
        payload["plot"] = args.plot
        payload["recording"] = result.phases[-1].run.recording
        payload["seed"] = applied.seed
        payload["predicted_from"] = args.from_log
        payload["perturbation"] = applied.to_json()
        print_json(payload)
    else:
        _print_text(result, args)
    code = 0
    if not result.goal_met:
        import sys

        print(f"tamp refine: error: {result.failure}", file=sys.stderr)
        code = InfeasibleError.exit_code
    if viewer is not None:
        from tamp.sim.core.recording import hold_open

        hold_open(viewer)
    return code


def _print_text(result, args: argparse.Namespace) -> None:
    from tamp.refine.loader import dump_program

    program = result.phases[0].program
    cat = result.program.communication.category
    predicted = f", predicted from {args.from_log}" if args.from_log else ""
    print(f"program {program.name} (Category {cat}{predicted}):")
    first = result.phases[0].task_time
    for p in result.phases:
        change = "" if p is result.phases[0] else f"  ({p.task_time / first - 1:+.1%})"
        line = f"  {p.name:<15} {p.task_time:8.1f} s{change:<10}  {p.run.outcome.summary()}"
        print(line.rstrip())
    print("tried:")
    for a in result.attempts:
        t = f"{a.run.task_time:.1f} s" if a.run.finished else "unfinished"
        verdict = "accepted" if a.rejected is None else f"NOT accepted: {a.rejected}"
        what = "; ".join(a.tried) or "as given"
        print(f"  {a.phase:<15} {what}: {t}, {verdict}")
    for p in result.relaxed:
        print(f"  relaxed across the robots: {p.describe()}")
    for p, report in result.refused:
        print(f"  refused by the ordering property: {p.describe()}")
        print("    " + report.splitlines()[0][:200])
    for p, why, _ in result.reverted:
        print(f"  reverted: {p.describe()} ({why})")
    if result.speed_undone:
        print(f"  speed change undone ({result.speed_undone})")
    found = ", ".join(f"{k} {v:g} Hz" for k, v in result.rates_found.items()) or "none"
    print(f"  rates found (Fig. 5, {result.rate_source}): {found}")
    if result.behavior_rates:
        kept = ", ".join(f"{k} {v:g}" for k, v in result.behavior_rates.items())
        print(f"  rates kept per behavior (Hz; Step 3 scales the {result.scale} speed): {kept}")
    else:
        print("  no rate kept")
    print(
        f"reduction {result.reduction:.1%}; sim {result.sim_time:.0f} s in "
        f"{result.wall_time:.0f} s wall, {result.cpu_time:.0f} s CPU"
    )
    if not result.goal_met:
        print(f"NOT refined: {result.failure}")
    elif args.refined:
        print(f"refined program: {args.refined}")
    else:
        print("refined program:")
        print(dump_program(result.program))
    if args.timeline:
        print(f"timeline: {args.timeline}")
    if args.diagram:
        print(f"diagram: {args.diagram}")
    if args.plot:
        print(f"plot: {args.plot}")
    if args.record:
        print(f"recording: {result.phases[-1].run.recording}")
