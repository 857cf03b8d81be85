"""The `tamp-verify` command: model-check traces, RG plans, behavior trees and LOTS tables.

    tamp-verify trace --formula F (--trace FILE | --word 'p1&!p2; …; cycle{…}') [--finite]
    tamp-verify plan DEMO.yaml [--order G1,G0,…] [--cost distance|time|success] [--no-graph]
    tamp-verify bt DEMO.yaml [--property F …] [--order G1,G0,…] [--appear OBJ@PLACE[@WHEN] …]
                   [--fail ACTION[(ARGS)] …] [--max-failures N] [--max-states N]
    tamp-verify lots TASK.yaml [--interference EVENTS.yaml]
    ... and, for every check: [--json] [--svg FILE]

Exit status: 0 the property holds, 1 violated (the counterexample is printed; with
``--json`` it is in the JSON document), 2 bad input (a formula or letter that does not
parse, a malformed file), 3 internal error, 4 unknown (``bt`` whose exploration hit
``--max-states`` without a counterexample: nothing established). ``--json`` prints at least
``{"status": "holds"|"violated"|"unknown", "holds": bool, "counterexample": …,
"states_explored": int}``. ``--svg FILE`` draws the counterexample on the automaton of the
property it violates (`tamp.verification.draw`; ``trace`` draws its trace whatever the verdict),
in the format of the file's suffix (``.svg``, ``.png``, ``.dot``: `tamp.pictures`).

Spot and the planning layers are imported inside each command, so ``--help`` stays fast.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from tamp.commands.main import add_version
from tamp.commands.main import run as run_cli
from tamp.errors import EXIT_INFEASIBLE, EXIT_OK, EXIT_UNKNOWN, InputError


def _emit(report, args, word=None) -> int:
    """Print ``report`` (text or JSON), draw it with ``--svg``, return the exit status."""
    from tamp.commands.output import print_json

    if getattr(args, "svg", None):
        _draw(report, args.svg, word)
    if args.json:
        print_json(report.to_json())
    else:
        print(report.text())
    return {"holds": EXIT_OK, "violated": EXIT_INFEASIBLE, "unknown": EXIT_UNKNOWN}[report.status]


def _add_output(p: argparse.ArgumentParser) -> None:
    """``--json`` and ``--svg``, the same on every check."""
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--svg",
        metavar="FILE",
        help="draw the counterexample on the automaton of the property it violates "
        "(format by suffix: .svg, .png or .dot)",
    )


def _checked(cmd):
    """``cmd`` with ``--svg`` checked before any work (a wrong suffix: exit 2)."""

    def run(args) -> int:
        if getattr(args, "svg", None):
            from tamp.commands.output import output_file
            from tamp.pictures import check_picture

            output_file(check_picture(args.svg, "--svg"), "--svg")
        return cmd(args)

    run.__doc__ = cmd.__doc__
    return run


def _draw(report, path: str, word=None) -> None:
    """The first violated verdict's counterexample on its automaton (else ``word``, the
    checked trace, on the first verdict's), written at ``path``."""
    import logging

    from tamp.pictures import write_graph
    from tamp.verification.draw import trace_dot

    failed = [v for v in report.failed if v.counterexample is not None]
    if failed:
        verdict, drawn = failed[0], failed[0].counterexample.word
    elif word is not None and report.verdicts:
        verdict, drawn = report.verdicts[0], word
    else:
        logging.getLogger("tamp").info("--svg: no counterexample to draw (%s)", report.status)
        return
    finite = verdict.semantics == "finite"
    write_graph(trace_dot(verdict.formula, drawn, finite=finite), path, "--svg")


# -- trace ----------------------------------------------------------------------------------


def _cmd_trace(args) -> int:
    from tamp.ltl.formula import parse as parse_formula
    from tamp.verification.traces import check_trace
    from tamp.verification.verdict import Report
    from tamp.verification.words import load_trace, parse_word

    formula = parse_formula(args.formula, field="--formula")
    word = load_trace(args.trace) if args.trace is not None else parse_word(args.word)
    if args.finite and word.is_lasso:
        raise InputError("the trace has a cycle (an infinite word)", field="--finite")
    if not args.finite and not word.is_lasso:
        raise InputError(
            "the trace has no cycle: add cycle{…} (infinite word) or pass --finite (LTLf)",
            field="--trace" if args.trace is not None else "--word",
        )
    verdict = check_trace(formula, word, finite=args.finite)
    return _emit(Report([verdict]), args, word)


def _add_trace(sub) -> None:
    p = sub.add_parser("trace", help="check a finite or lasso trace against an LTL formula")
    p.add_argument("--formula", required=True, help="LTL formula in Spot syntax")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--trace", metavar="FILE", help="trace file (YAML/JSON, version: 1)")
    src.add_argument("--word", help="trace in word syntax, e.g. 'p1 & !p2; p2; cycle{p1}'")
    p.add_argument("--finite", action="store_true", help="finite-trace (LTLf) semantics")
    _add_output(p)
    p.set_defaults(func=_checked(_cmd_trace))


# -- plan -----------------------------------------------------------------------------------


def _order(text: str) -> list[str]:
    """``--order G1,G0`` -> ``["G1", "G0"]``; an order naming no goal is bad input."""
    order = [g.strip() for g in text.split(",") if g.strip()]
    if not order:
        raise InputError(f"expected goal ids such as G1,G0, got {text!r}", field="--order")
    return order


def _cmd_plan(args) -> int:
    from tamp.demo import load_demonstration
    from tamp.verification.rg import check_graph, check_order
    from tamp.verification.verdict import Report

    demo = load_demonstration(args.demo)
    if args.order is not None:
        order = _order(args.order)
    else:
        from tamp.rg import plan

        order = list(plan(demo, cost=args.cost).order)
    verdicts = [check_order(demo, order)]
    if not args.no_graph:
        verdicts.append(check_graph(demo))
    return _emit(Report(verdicts), args)


def _add_plan(sub) -> None:
    p = sub.add_parser("plan", help="check an RG goal order and the whole RG against C")
    p.add_argument("demo", metavar="DEMO.yaml", help="demonstration file")
    p.add_argument("--order", help="goal order to check, e.g. G1,G0,G3,G2 (default: tamp plan's)")
    p.add_argument(
        "--cost",
        default="distance",
        choices=("distance", "time", "success"),
        help="edge weights of tamp plan's order (default distance)",
    )
    p.add_argument("--no-graph", action="store_true", help="skip the whole-RG model check")
    _add_output(p)
    p.set_defaults(func=_checked(_cmd_plan))


# -- bt -------------------------------------------------------------------------------------


def _cmd_bt(args) -> int:
    from tamp.commands.events_args import demo_events
    from tamp.demo import load_demonstration
    from tamp.verification.bt import DEFAULT_PROPERTIES, check_tree, executor_for
    from tamp.verification.rg import check_order_ids

    demo = load_demonstration(args.demo)
    if args.max_failures < 0:
        raise InputError(f"must be >= 0, got {args.max_failures}", field="--max-failures")
    if args.max_states is None:
        from tamp.verification.bt import DEFAULT_MAX_STATES

        args.max_states = DEFAULT_MAX_STATES
    if args.max_states < 1:
        raise InputError(f"must be >= 1, got {args.max_states}", field="--max-states")
    order = None
    if args.order is not None:
        order = _order(args.order)
        check_order_ids(demo.goal_ids, order)
    appear, fail = demo_events(args, demo)
    report = check_tree(
        executor_for(demo, order),
        demo.initial_world(),
        args.property or list(DEFAULT_PROPERTIES),
        events=appear,
        failures=fail or None,
        max_failures=args.max_failures,
        max_states=args.max_states,
    )
    return _emit(report, args)


def _add_bt(sub) -> None:
    from tamp.commands.events_args import add_event_arguments

    p = sub.add_parser("bt", help="explore every execution of the grown BT and check properties")
    p.add_argument("demo", metavar="DEMO.yaml", help="demonstration file")
    p.add_argument(
        "--property",
        action="append",
        default=[],
        metavar="F",
        help="LTL property (repeatable); default: G !placed_in_occupied, "
        "G (holding_count <= 1), F goal",
    )
    p.add_argument("--order", help="goal order for C_goal (default: tamp plan's)")
    add_event_arguments(p, verify=True)
    p.add_argument(
        "--max-failures", type=int, default=1, help="skill failures per execution (default 1)"
    )
    p.add_argument(
        "--max-states",
        type=int,
        default=None,
        metavar="N",
        help="states to explore before the verdict is unknown (default 200000, "
        "the budget of the gate in tamp plan --execute and tamp simulate smp-mro)",
    )
    _add_output(p)
    p.set_defaults(func=_checked(_cmd_bt))


# -- lots -------------------------------------------------------------------------------------


def _cmd_lots(args) -> int:
    from tamp.verification.lots import check_task_file

    return _emit(check_task_file(args.task, args.interference), args)


def _add_lots(sub) -> None:
    from tamp.commands.lots import add_interference_argument

    p = sub.add_parser(
        "lots",
        help="check every LOTS table the controller builds (planned run and every entry of T)",
    )
    p.add_argument("task", metavar="TASK.yaml", help="LTL task file")
    add_interference_argument(p)
    _add_output(p)
    p.set_defaults(func=_checked(_cmd_lots))


def make_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tamp-verify",
        description="Model-check traces, RG plans, behavior trees and LOTS tables (Spot).",
    )
    add_version(parser)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    _add_trace(sub)
    _add_plan(sub)
    _add_bt(sub)
    _add_lots(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    return run_cli(argv, make_parser)


if __name__ == "__main__":
    sys.exit(main())
