"""The ``--execute`` part of ``tamp plan``: argument definitions and the run function.

``tamp plan DEMO.yaml --execute [--obstacle OBJ@x,y,z[@tick]] [--fail NAME[:ARGS][:TIMES]]
[--skill-ticks N] [--max-ticks N] [--json] [--bt-xml out.xml] [--bt-dot out.dot]``

- ``--obstacle O_a@2.2,0.8,0.1`` an object that is not in the demonstration appears at that
  point (robot frame, metres) when the robot first comes within reach of it;
  ``--obstacle O_a@2.2,0.8,0.1@5`` makes it appear at tick 5 (``@0``: there from the start).
- ``--fail Pick:O1`` the first attempt of Pick(O1) fails; ``--fail Place:O1,L1:2`` the first
  two attempts of Place(O1, L1); ``--fail MoveTo`` the first MoveTo, whatever its target.
- exit status 0 when every goal was reached, 1 otherwise (the reason is printed).

The lead's ``tamp/commands/plan.py`` calls `add_execute_arguments` on its parser and, when
``args.execute`` is set, `run_execute(args, demo, plan_result)`.
"""

from __future__ import annotations

import argparse
import re
import sys
from typing import Any

from tamp.errors import EXIT_INFEASIBLE, EXIT_OK, InputError
from tamp.world.events import Appear, AtTick, Fail
from tamp.world.geometry import Point

_NAME = r"[A-Za-z_][\w\-]*"
_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_OBSTACLE = re.compile(rf"^({_NAME})@({_NUM}),({_NUM})(?:,({_NUM}))?(?:@(\d+))?$")
_FAIL = re.compile(rf"^({_NAME})(?::([\w\-]+(?:,[\w\-]+)*))?(?::(\d+))?$")


def add_execute_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--execute`` and its options to the ``tamp plan`` parser."""
    g = parser.add_argument_group("execution (behavior tree in the symbolic world)")
    g.add_argument(
        "--execute",
        action="store_true",
        help="run the grown behavior tree for the chosen order in the symbolic world",
    )
    g.add_argument(
        "--obstacle",
        action="append",
        default=[],
        metavar="OBJ@x,y,z[@tick]",
        help="an object that appears during execution (default: when the robot reaches it)",
    )
    g.add_argument(
        "--fail",
        action="append",
        default=[],
        metavar="NAME[:ARGS][:TIMES]",
        help="scripted skill failure, e.g. Pick:O1 (first attempt fails) or Place:O1,L1:2",
    )
    g.add_argument("--skill-ticks", type=int, default=1, metavar="N", help="ticks per skill")
    g.add_argument("--max-ticks", type=int, default=5000, metavar="N", help="tick budget")
    g.add_argument(
        "--bt-xml", metavar="PATH", help="write the grown tree as BehaviorTree.CPP v4 XML"
    )
    g.add_argument("--bt-dot", metavar="PATH", help="write the grown tree as Graphviz DOT")


def parse_obstacle(text: str, known: set[str] | None = None) -> Appear:
    """``OBJ@x,y[,z][@tick]`` -> `Appear`; InputError (exit 2) names ``--obstacle``."""
    m = _OBSTACLE.match(text.strip())
    if not m:
        raise InputError(f"expected OBJ@x,y,z[@tick], got {text!r}", field="--obstacle")
    name, x, y, z, tick = m.groups()
    if known is not None and name in known:
        raise InputError(f"{name!r} is already an object of the demonstration", field="--obstacle")
    return Appear(
        name,
        Point(float(x), float(y), float(z) if z is not None else 0.0),
        AtTick(int(tick)) if tick is not None else None,
    )


def parse_failure(text: str, domain: Any = None) -> Fail:
    """``NAME[:ARG,ARG][:TIMES]`` -> `Fail`; InputError names ``--fail``."""
    m = _FAIL.match(text.strip())
    if not m:
        raise InputError(f"expected NAME[:ARGS][:TIMES], got {text!r}", field="--fail")
    name, args, times = m.groups()
    if domain is not None and name not in domain.templates:
        raise InputError(
            f"unknown action {name!r} (known: {', '.join(domain.templates)})", field="--fail"
        )
    parsed = tuple(args.split(",")) if args else None
    if domain is not None and parsed is not None:
        n = len(domain.templates[name].params)
        if len(parsed) != n:
            raise InputError(f"{name} takes {n} argument(s), got {len(parsed)}", field="--fail")
    count = int(times) if times is not None else 1
    if count < 1:
        raise InputError("TIMES must be at least 1", field="--fail")
    return Fail(name, parsed, count)


def execution_payload(args: argparse.Namespace, demo: Any, plan_result: Any):
    """Run the execution; returns (report, JSON document, exit status)."""
    from tamp.bt.run import execute_plan
    from tamp.commands.output import output_file

    domain = demo.domain()  # the robot's templates named in the demonstration (or youBot's)
    for option in ("bt_xml", "bt_dot"):
        if getattr(args, option, None):
            output_file(getattr(args, option), "--" + option.replace("_", "-"))
    if args.skill_ticks < 0:
        raise InputError("must be >= 0", field="--skill-ticks")
    if args.max_ticks < 1:
        raise InputError("must be >= 1", field="--max-ticks")
    known = set(demo.objects)
    obstacles = []
    for text in args.obstacle:
        ob = parse_obstacle(text, known)
        known.add(ob.obj)
        obstacles.append(ob)
    failures = [parse_failure(t, domain) for t in args.fail]
    for f in failures:  # a misspelt object would make the scripted failure never happen
        params = domain.templates[f.action].params
        for (_, kind), arg in zip(params, f.args or (), strict=False):
            if kind == "object" and arg not in known:
                raise InputError(
                    f"{f.action}: unknown object {arg!r} (known: {', '.join(sorted(known))})",
                    field="--fail",
                )
    report = execute_plan(
        demo,
        plan_result.c_goal,
        events=obstacles,
        failures=failures,
        skill_ticks=args.skill_ticks,
        domain=domain,
        max_ticks=args.max_ticks,
    )
    if getattr(args, "bt_xml", None):
        from tamp.bt.export import write_btcpp_xml

        write_btcpp_xml(report.executor.root, args.bt_xml)
    if getattr(args, "bt_dot", None):
        from tamp.bt.export import write_dot

        write_dot(report.executor.root, args.bt_dot)
    doc = {
        "source": getattr(demo, "source", None),
        "order": list(getattr(plan_result, "order", [])),
        "cost": getattr(plan_result, "cost", None),
        **report.to_json(),
    }
    return report, doc, EXIT_OK if report.reached else EXIT_INFEASIBLE


def run_execute(args: argparse.Namespace, demo: Any, plan_result: Any) -> int:
    """Print the execution (text, or one JSON document with ``--json``); 0 reached, 1 not."""
    from tamp.commands.output import print_json

    report, doc, code = execution_payload(args, demo, plan_result)
    if getattr(args, "json", False):
        print_json(doc)
    else:
        print(report.text())
    if code != EXIT_OK:
        print(f"tamp plan: goal not reached: {report.reason}", file=sys.stderr)
    return code
