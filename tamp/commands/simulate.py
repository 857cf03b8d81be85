"""``tamp simulate WORKCELL``: one run of a scenario in a Drake workcell.

    tamp simulate smp-mro [SCENARIO | --case 1|2|3] [--appear ...] [--fail ...] [--rate R]
    tamp simulate lots TASK [--cell CELL.yaml] [--interference EVENTS.yaml] [--grasp NETWORK]
                            [--detector oracle|learned]
    tamp simulate refine PROGRAM
    ... and, for every workcell: [--seed N] [--record out.html] [--meshcat]
                                 [--max-sim-time S] [--no-verify] [--timeline out.svg]
                                 [--diagram out.svg] [--json]

One subcommand per registered workcell (`tamp.sim.core.workcell`), built from the options
the workcell declares; every run goes the same way: load the scenario (bad input: exit 2,
naming the file and field), pass the verification gate (a failed check: exit 1 with the
counterexample; ``--no-verify`` skips it with a warning), draw the seeded perturbation,
simulate, judge on the plant. The text report is the cell's; ``--json`` prints the run's
`RunResult` document, whose common keys (``status``, ``ok``, ``cause``, ``task_time``,
``sim_time``, ``wall_time``, ``realtime_factor``, ``seed``, ``perturbation``,
``verified`` ...) are the same for every workcell. Exit 0 on SUCCESS, 1 otherwise.

Pictures: ``--timeline`` draws the run's skills over sim time (`tamp.sim.core.timeline`),
``--diagram`` the cell's Drake diagram (Graphviz, format by suffix: `tamp.pictures`).
``--meshcat`` shows the run in a local Meshcat that stays open after the run until Enter
or Ctrl-C (`tamp.sim.core.recording.hold_open`).
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

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
        add_run_arguments(s)
        s.set_defaults(func=run, workcell=cell.name)


def add_run_arguments(parser) -> None:
    """The flags every simulated run has, whatever its workcell."""
    parser.add_argument(
        "--record", metavar="HTML", help="write a Meshcat animation (static HTML, offline)"
    )
    add_live_view(parser)
    add_no_verify(parser)
    parser.add_argument(
        "--timeline",
        metavar="FILE",
        help="draw the run's skills over sim time (.svg, .png or .pdf)",
    )
    parser.add_argument(
        "--diagram",
        metavar="FILE",
        help="draw the workcell's Drake diagram with Graphviz (.dot, .svg or .png)",
    )
    parser.add_argument("--json", action="store_true", help="machine-readable output")


def add_live_view(parser) -> None:
    """``--meshcat`` and ``--max-sim-time``: what every command that simulates takes (each
    ``tamp simulate`` cell, ``tamp refine``)."""
    parser.add_argument(
        "--meshcat",
        action="store_true",
        help="watch the run in a local Meshcat (URL on stderr); it stays open after the run "
        "until you press Enter or Ctrl-C",
    )
    parser.add_argument(
        "--max-sim-time",
        type=float,
        metavar="S",
        help="override the scenario's sim-time limit (s)",
    )


def check_max_sim_time(value: float | None) -> None:
    """A given ``--max-sim-time`` is a positive, finite number of seconds (else exit 2)."""
    import math

    from tamp.errors import InputError

    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(
            f"must be a positive number of seconds, got {value}", field="--max-sim-time"
        )


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
    import os

    from tamp.pictures import GRAPH_FORMATS, PLOT_FORMATS, check_picture

    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    from tamp.perturbation import check_seed

    check_seed(args.seed)
    check_max_sim_time(args.max_sim_time)
    if args.record:
        output_file(args.record, "--record", make_parents=True)
    for flag, formats in (("--timeline", PLOT_FORMATS), ("--diagram", tuple(GRAPH_FORMATS))):
        path = getattr(args, flag[2:])
        if path:
            output_file(check_picture(path, flag, formats), flag, make_parents=True)


def run(args: argparse.Namespace) -> int:
    """Load, verify, simulate and report one run of ``args.workcell``."""
    from tamp.sim.core.workcell import get, split_options

    cell = get(args.workcell)
    check_common(args)
    load, run_options = split_options(cell, {o.dest: getattr(args, o.dest) for o in cell.options})
    if args.meshcat:
        run_options["meshcat"] = True
        check_meshcat(cell)
    scenario = cell.load(getattr(args, cell.main.dest), **load)
    if args.diagram:
        write_diagram(cell, scenario, args.diagram)
    if args.no_verify:
        warn_unverified(f"tamp simulate {cell.name}", "the plan")
    progress(f"simulating in the {cell.name} workcell", quiet=args.json)
    with watched(args.meshcat) as viewer:
        result = cell.run(
            scenario,
            seed=args.seed,
            record=args.record,
            max_sim_time=args.max_sim_time,
            verify=not args.no_verify,
            **run_options,
        )
        doc = result.to_json()
        if args.timeline:
            from tamp.sim.core.timeline import draw_timeline

            draw_timeline(doc, args.timeline)
        if args.json:
            print_json(doc)
        else:
            print("\n".join(result.report_lines()))
        if viewer is not None:
            wait_for_close(viewer)
    return result.exit_code


def check_meshcat(cell) -> None:
    """``--meshcat`` needs a cell whose ``run`` takes ``meshcat`` (a live view)."""
    import inspect

    from tamp.errors import InputError

    if "meshcat" not in inspect.signature(cell.run).parameters:
        raise InputError(
            f"the {cell.name} workcell has no live view (record the run with --record)",
            field="--meshcat",
        )


@contextmanager
def watched(live: bool) -> Iterator[Any]:
    """The live Meshcat every run in the block draws into (None without ``--meshcat``)."""
    if not live:
        yield None
        return
    from tamp.sim.core.recording import live_view

    with live_view() as viewer:
        logging.getLogger("tamp").info("meshcat: %s", viewer.web_url())
        yield viewer


def wait_for_close(viewer: Any) -> None:
    """Keep the live view served until the user closes it (`recording.hold_open`)."""
    from tamp.sim.core.recording import hold_open

    hold_open(viewer)


def write_diagram(cell, scenario: Any, path: str) -> None:
    """The cell's Drake diagram (`Workcell.build`, its top level) as a Graphviz picture."""
    from tamp.pictures import write_graph

    diagram = cell.build(scenario)
    write_graph(diagram.GetGraphvizString(max_depth=1), path, "--diagram")
