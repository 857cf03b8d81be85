"""`tamp lots TASK.yaml`: run the LOTS reactive planner (Zhou et al. Alg. 1-3) symbolically.

Prints the automaton size, Lemma 1's number of W^B states, the planned run, the robot's
actions under the scripted human interference, the number of replans, the final counts, and
the run's word (the robot's deliveries and the W^B states the camera saw) with the task
automaton's verdict on it: the task is satisfied only when that word is accepted. The robot
has Zhou et al.'s actions (deliver from W^A to W^B, discard into the waste basket);
--return-action adds our extension, taking an object from W^B back to W^A.
Exit status: 0 task satisfied, 1 infeasible (with the reason), 2 bad input.
"""

from __future__ import annotations

import argparse
import sys

from tamp.commands.output import add_no_verify, warn_unverified


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "lots",
        help="LTL task with local observation: Spot automaton, LOTS table, reactive replanning",
        description=__doc__,
    )
    p.add_argument("task", help="LTL task file (YAML, version 1) or a packaged scenario name")
    add_interference_argument(p)
    add_return_argument(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the random tree update")
    p.add_argument(
        "--tree",
        choices=("bfs", "random"),
        default="bfs",
        help="tree update variant (Alg. 3): breadth-first (default) or random as in the paper",
    )
    p.add_argument(
        "--max-waits", type=int, default=3, help="consecutive waits before declaring infeasible"
    )
    add_no_verify(p)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--dot",
        metavar="FILE",
        help="draw the task's Büchi automaton (format by suffix: .dot, .svg, .png)",
    )
    p.set_defaults(func=run)


def add_interference_argument(p: argparse.ArgumentParser) -> None:
    """``--interference EVENTS.yaml``, the same on ``tamp lots`` and ``tamp-verify lots``."""
    p.add_argument("--interference", metavar="EVENTS.yaml", help="human interference script")


def add_return_argument(p: argparse.ArgumentParser) -> None:
    """``--return-action``, the same on ``tamp lots`` and ``tamp simulate lots``."""
    p.add_argument(
        "--return-action",
        action="store_true",
        help=(
            "allow our extension of Zhou et al.'s action set: take an object from W^B back "
            "to W^A (to deliver it again); same as 'actions: {return: true}' in the task file"
        ),
    )


def with_returns(task, args: argparse.Namespace):
    """``task`` with the return action switched on when ``--return-action`` asks for it."""
    import dataclasses

    if getattr(args, "return_action", False):
        return dataclasses.replace(task, returns=True)
    return task


def run(args: argparse.Namespace) -> int:
    from tamp.commands.output import output_file, print_json
    from tamp.errors import InfeasibleError, InputError
    from tamp.lots.run import run_task, run_word_json
    from tamp.lots.task import load_events, load_task
    from tamp.pictures import check_picture, write_graph

    if args.max_waits < 1:
        raise InputError("must be >= 1", field="--max-waits")
    if args.dot:
        output_file(check_picture(args.dot, "--dot"), "--dot")
    task = with_returns(load_task(args.task), args)
    events = load_events(args.interference, task) if args.interference else []
    if args.no_verify:
        warn_unverified("tamp lots", "every LOTS table")
    from tamp.verification import gate
    from tamp.verification.lots import judge_verdict

    report = run_task(
        task,
        events,
        mode=args.tree,
        seed=args.seed,
        max_waits=args.max_waits,
        check=None if args.no_verify else gate,
        judge=judge_verdict,
    )
    c = report.controller
    if args.dot:
        write_graph(c.aut.to_dot(), args.dot, "--dot")
    if args.json:
        print_json(report.to_json())
    else:
        lots = c.lots
        print(f"task {task.name}: {task.formula}")
        print(
            f"automaton: {c.aut.num_states} states, {len(c.aut.edges)} edges, "
            f"accepting {sorted(c.aut.accepting)}"
        )
        print(f"W^B states (Lemma 1): {lots.num_wb_states()}  final W^B: {lots.format(lots.final)}")
        run_letters = [next(iter(x)) for x in c.initial_plan.prefix if x]
        print(f"planned round: {' '.join(run_letters) or '(nothing to do)'}")
        human: dict[tuple[int, int], list[str]] = {}
        for n, phase, e in report.person.log:
            # idle events after action n come before action n + 1; 'holding' ones during it
            slot = (n, 0) if phase == "idle" else (n, 1)
            human.setdefault(slot, []).append(e.describe())
        for i in range(len(report.actions) + 1):
            for text in human.get((i, 0), []):
                print(f"      human: {text}")
            for text in human.get((i, 1), []):
                print(f"      human (while the robot carries): {text}")
            if i < len(report.actions):
                a = report.actions[i]
                print(f"  {a.index:2d}. {a.text()}")
        counts = report.counts()
        for e in report.unfired_events:
            print(f"      {e.never_happened()}")
        print(f"replans: {report.replans}")
        print(f"final: W^A {counts['A']}  W^B {counts['B']}  waste {counts['waste']}")
        word = " ".join("{" + ",".join(x) + "}" for x in run_word_json(c)["trace"])
        verdict_word = "accepted" if report.word_accepted else "rejected"
        print(f"run's word: {word or '(empty)'}  — {verdict_word} by the task automaton")
        verdict = "task satisfied" if report.satisfied else f"task infeasible: {report.reason}"
        if report.unfired_events:
            verdict += f" ({len(report.unfired_events)} scripted event(s) never happened)"
        print(verdict)
    if not report.satisfied:
        if args.json:  # the JSON document above already says why; no second document
            print(f"tamp lots: error: {report.reason or 'task not satisfied'}", file=sys.stderr)
            return InfeasibleError.exit_code
        raise InfeasibleError(report.reason or "task not satisfied")
    return 0
