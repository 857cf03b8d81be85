"""``tamp simulate WORKCELL``: one run of a scenario in a Drake workcell.

    tamp simulate smp-mro [SCENARIO | --case 1|2|3] [--appear ...] [--fail ...] [--rate R]
    tamp simulate lots TASK [--cell CELL.yaml] [--interference EVENTS.yaml] [--grasp NETWORK]
    tamp simulate refine PROGRAM
    ... and, for every workcell: [--seed N] [--record out.html] [--max-sim-time S]
                                 [--no-verify] [--json]

One subcommand per registered workcell (`tamp.sim.core.workcell`), built from the options
the workcell declares; every run goes the same way: load the scenario (bad input: exit 2,
naming the file and field), pass the verification gate (a failed check: exit 1 with the
counterexample; ``--no-verify`` skips it with a warning), draw the seeded perturbation,
simulate, judge on the plant. The text report is the cell's; ``--json`` prints the run's
`RunResult` document, whose common keys (``status``, ``ok``, ``cause``, ``task_time``,
``sim_time``, ``wall_time``, ``realtime_factor``, ``seed``, ``perturbation``,
``verified`` ...) are the same for every workcell. Exit 0 on SUCCESS, 1 otherwise.
"""

from __future__ import annotations

import argparse

from tamp.commands.output import add_no_verify, output_file, print_json, progress, warn_unverified


def register(subparsers) -> None:
    from tamp.sim.core.workcell import workcells

    p = subparsers.add_parser("simulate", help="run a scenario in a Drake workcell")
    sub = p.add_subparsers(dest="system", metavar="WORKCELL", required=True)
    for cell in workcells().values():
        s = sub.add_parser(cell.name, help=cell.title, description=cell.title)
        cell.main.add_to(s)
        for option in cell.options:
            option.add_to(s)
        add_seed(s)
        s.add_argument("--record", metavar="HTML", help="write a Meshcat animation (static HTML)")
        s.add_argument(
            "--max-sim-time", type=float, help="override the scenario's sim-time limit (s)"
        )
        add_no_verify(s)
        s.add_argument("--json", action="store_true", help="machine-readable output")
        s.set_defaults(func=run, workcell=cell.name)


def add_seed(parser) -> None:
    """``--seed N``: the run's draw of the scenario's ``perturbation`` section (same seed,
    same run, bit for bit on one machine)."""
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of the scenario's perturbation draw and of every seeded choice (default 0)",
    )


def check_common(args: argparse.Namespace) -> None:
    """The flags every ``tamp simulate`` workcell has, checked before any work is done."""
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


def run(args: argparse.Namespace) -> int:
    """Load, verify, simulate and report one run of ``args.workcell``."""
    from tamp.sim.core.workcell import get, split_options

    cell = get(args.workcell)
    check_common(args)
    load, run_options = split_options(cell, {o.dest: getattr(args, o.dest) for o in cell.options})
    scenario = cell.load(getattr(args, cell.main.dest), **load)
    if args.no_verify:
        warn_unverified(f"tamp simulate {cell.name}", "the plan")
    progress(f"simulating in the {cell.name} workcell", quiet=args.json)
    result = cell.run(
        scenario,
        seed=args.seed,
        record=args.record,
        max_sim_time=args.max_sim_time,
        verify=not args.no_verify,
        **run_options,
    )
    if args.json:
        print_json(result.to_json())
    else:
        print("\n".join(result.report_lines()))
    return result.exit_code
