"""`tamp plan DEMO.yaml`: demonstration → goals + constraints → RG → cheapest order (§IV-A/B).

With ``--execute`` the chosen order is run as a behavior tree grown at run time in the
symbolic world (options from `tamp.commands.execute_args`).
"""

from __future__ import annotations

import argparse

from tamp.commands.execute_args import add_execute_arguments, check_execute_arguments
from tamp.commands.output import add_no_verify, output_file, print_json, warn_unverified
from tamp.errors import InputError
from tamp.pictures import check_picture, write_graph

MAX_DOT_STATES = 5000


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan",
        help="derive goals and constraints from a demonstration and pick the cheapest order",
        description=__doc__.splitlines()[0],
    )
    p.add_argument(
        "demo", help="demonstration YAML (or the name of a packaged one, e.g. case2.yaml)"
    )
    p.add_argument(
        "--cost", choices=("distance", "time", "success"), default="distance", help="edge weights"
    )
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument(
        "--dot",
        metavar="FILE",
        help="draw the RG with the chosen path highlighted (format by suffix: .dot, .svg, .png)",
    )
    add_no_verify(p)
    add_execute_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tamp.demo import load_demonstration
    from tamp.rg import plan

    if args.dot:
        output_file(check_picture(args.dot, "--dot"), "--dot")
    check_execute_arguments(args)
    demo = load_demonstration(args.demo)
    result = plan(demo, args.cost)
    verify = not args.no_verify
    if verify:
        from tamp.verification.gate import gate_order

        gate_order(result)
    else:
        warn_unverified("tamp plan", "the goal order" + (" and its tree" if args.execute else ""))
    if args.dot:
        _write_dot(result, args.dot)
    if args.execute:
        from tamp.commands.execute_args import run_execute

        return run_execute(args, demo, result, verify=verify)
    if args.json:
        print_json(result.to_json())
    else:
        _print_human(result)
    return 0


def _write_dot(result, path: str) -> None:
    from tamp.rg.dot import rg_to_dot

    if result.rg.states is None or result.rg.states > MAX_DOT_STATES:
        raise InputError(
            f"the RG has more than {MAX_DOT_STATES} states: too large to draw", field="--dot"
        )
    write_graph(rg_to_dot(result.demo, result.graph(), result.order).to_string(), path, "--dot")


def _print_human(result) -> None:
    d = result.demo
    print(f"demonstration: {d.source}")
    print("goals (robot frame):")
    for g in d.goals:
        x, y, z = g.pos.as_tuple()
        print(f"  {g.id}: {g.object} -> ({x:.3f}, {y:.3f}, {z:.3f})  area {g.area.name}")
    if d.buffers:
        print("buffer goals (a swap with no room passes through a free area):")
        for b in d.buffers:
            print(f"  {b}")
    print("constraints:")
    for (a, b), why in sorted(d.constraint_reasons.items()):
        print(f"  {a} <= {b}   ({why})")
    if not d.constraint_reasons:
        print("  (none)")
    rg = result.rg
    states = rg.states if rg.states is not None else "> limit"
    print(
        f"reachability graph: {states} states, {rg.edges} edges "
        f"(Alg. 1 would generate {rg.alg1_nodes} nodes)"
    )
    print(f"order ({result.cost_model}): {' -> '.join(result.order)}   cost {result.cost:.3f}")
    print("C_goal: " + ", ".join(str(c) for c in result.c_goal))
