"""The ``--execute`` part of ``tamp plan``: argument definitions and the run function.

``tamp plan DEMO.yaml --execute [--appear OBJ@PLACE[@WHEN]] [--fail ACTION[(ARGS)][xTIMES]]
[--skill-ticks N] [--max-ticks N] [--max-expansions N] [--verify-budget N] [--json]
[--bt-xml out.xml] [--bt-dot out.dot]``

- ``--max-ticks`` and ``--max-expansions`` default to caps that scale with the number of
  goals (`default_max_ticks`, `tamp.bt.executor.default_max_expansions`); a run stopped by
  one says which cap and how to raise it.

- The demonstration's own ``appear:`` entries happen (Case 3's O_a at l_1); ``--appear``
  adds objects or overrides an object's entry (`tamp.commands.events_args`).
- ``--fail Pick(O1)`` the first attempt of Pick(O1) fails; ``--fail 'Place(O1, L1)x2'`` the
  first two attempts of Place(O1, L1); ``--fail MoveTo`` the first MoveTo, whatever its target.
- Before it runs, the grown tree passes the verification gate as in ``tamp simulate``:
  every execution over the symbolic domain (the appearances, one skill failure) against
  the safety properties and ``F goal`` (`tamp.verification.gate.gate_tree`). ``--verify-budget
  N`` bounds the states it explores; a tree it cannot cover within them is refused as
  unknown (exit 1, the message names the budget); a long check logs its progress.
- exit status 0 when every goal was reached, 1 otherwise (the reason is printed).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from tamp.commands.events_args import add_event_arguments, demo_events
from tamp.errors import EXIT_INFEASIBLE, EXIT_OK, InputError


def add_execute_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--execute`` and its options to the ``tamp plan`` parser."""
    g = parser.add_argument_group("execution (behavior tree in the symbolic world)")
    g.add_argument(
        "--execute",
        action="store_true",
        help="run the grown behavior tree for the chosen order in the symbolic world",
    )
    add_event_arguments(g)
    g.add_argument("--skill-ticks", type=int, default=1, metavar="N", help="ticks per skill")
    g.add_argument(
        "--max-ticks",
        type=int,
        default=None,
        metavar="N",
        help="tick budget, the symbolic run's limit: it has no sim time, hence no "
        "--max-sim-time or --meshcat (default: scales with the goals, see default_max_ticks)",
    )
    g.add_argument(
        "--max-expansions",
        type=int,
        default=None,
        metavar="N",
        help="tree expansions before the executor gives up (default: 20 per goal, >= 200)",
    )
    g.add_argument(
        "--verify-budget",
        type=int,
        default=None,
        metavar="N",
        help="states the tree gate may explore before its verdict is unknown (exit 1) "
        "(default 200000)",
    )
    g.add_argument(
        "--bt-xml", metavar="PATH", help="write the grown tree as BehaviorTree.CPP v4 XML"
    )
    g.add_argument(
        "--bt-dot",
        metavar="FILE",
        help="draw the grown tree (format by suffix: .dot, .svg, .png)",
    )


def default_max_ticks(goals: int, skill_ticks: int) -> int:
    """The tick budget that scales with the task: at least 5,000, and 10 ticks per goal for
    each tick a skill takes plus two (the tree's own ticks), so long tasks are not cut."""
    return max(5000, 10 * goals * (max(skill_ticks, 0) + 2))


def check_execute_arguments(args: argparse.Namespace) -> None:
    """Options that only make sense with ``--execute`` are refused without it (exit 2)."""
    if getattr(args, "execute", False):
        if getattr(args, "bt_dot", None):
            from tamp.pictures import check_picture

            check_picture(args.bt_dot, "--bt-dot")
        return
    for option in ("bt_xml", "bt_dot"):
        if getattr(args, option, None):
            raise InputError(
                "needs --execute (the tree is grown while executing)",
                field="--" + option.replace("_", "-"),
            )
    for option in ("appear", "fail"):
        if getattr(args, option, None):
            raise InputError("needs --execute", field="--" + option)


def execution_payload(args: argparse.Namespace, demo: Any, plan_result: Any, *, verify: bool):
    """Gate and run the execution; returns (report, JSON document, exit status)."""
    from tamp.bt.run import execute_plan
    from tamp.commands.output import output_file

    domain = demo.domain()  # the robot's templates named in the demonstration (or youBot's)
    for option in ("bt_xml", "bt_dot"):
        if getattr(args, option, None):
            output_file(getattr(args, option), "--" + option.replace("_", "-"))
    if args.skill_ticks < 0:
        raise InputError("must be >= 0", field="--skill-ticks")
    if args.max_ticks is not None and args.max_ticks < 1:
        raise InputError("must be >= 1", field="--max-ticks")
    if args.max_expansions is not None and args.max_expansions < 1:
        raise InputError("must be >= 1", field="--max-expansions")
    if args.verify_budget is not None and args.verify_budget < 1:
        raise InputError("must be >= 1", field="--verify-budget")
    goals = len(plan_result.c_goal)
    max_ticks = args.max_ticks or default_max_ticks(goals, args.skill_ticks)
    appear, fail = demo_events(args, demo)
    verified = None
    if verify:
        from tamp.verification.bt import executor_for
        from tamp.verification.gate import gate_tree

        verified = gate_tree(
            executor_for(demo, list(plan_result.order)),
            demo.initial_world(),
            events=appear,
            budget=args.verify_budget,
        )
    report = execute_plan(
        demo,
        plan_result.c_goal,
        events=appear,
        failures=fail,
        skill_ticks=args.skill_ticks,
        domain=domain,
        max_ticks=max_ticks,
        max_expansions=args.max_expansions,
    )
    if not report.reached and report.ticks >= max_ticks:
        report.reason += f" (the --max-ticks cap, {max_ticks} here: raise it with --max-ticks)"
    if getattr(args, "bt_xml", None):
        from tamp.bt.export import write_btcpp_xml

        write_btcpp_xml(report.executor.root, args.bt_xml)
    if getattr(args, "bt_dot", None):
        from tamp.bt.export import to_dot
        from tamp.pictures import write_graph

        write_graph(to_dot(report.executor.root), args.bt_dot, "--bt-dot")
    doc = {
        "source": getattr(demo, "source", None),
        "order": list(getattr(plan_result, "order", [])),
        "cost": getattr(plan_result, "cost", None),
        "appear": [str(a) for a in appear],
        "fail": [str(f) for f in fail],
        "verified": None if verified is None else verified.holds,
        **(
            {"buffers": [b.to_json() for b in demo.buffers]} if getattr(demo, "buffers", ()) else {}
        ),
        **report.to_json(),
    }
    return report, doc, EXIT_OK if report.reached else EXIT_INFEASIBLE


def run_execute(args: argparse.Namespace, demo: Any, plan_result: Any, *, verify: bool) -> int:
    """Print the execution (text, or one JSON document with ``--json``); 0 reached, 1 not."""
    from tamp.commands.output import print_json

    report, doc, code = execution_payload(args, demo, plan_result, verify=verify)
    if getattr(args, "json", False):
        print_json(doc)
    else:
        for b in getattr(demo, "buffers", ()):
            print(f"buffer goal {b}")
        print(report.text())
    if code != EXIT_OK:
        print(f"tamp plan: goal not reached: {report.reason}", file=sys.stderr)
    return code
