"""The run-vocabulary flags, the same in every command that executes or verifies a plan.

``--appear OBJ@PLACE[@WHEN]`` and ``--fail ACTION[(ARGS)][xTIMES]`` (grammar and meaning in
`tamp.world.events`) are added to ``tamp plan --execute``, ``tamp simulate`` and
``tamp-verify bt`` by `add_event_arguments`, and turned into checked `Appear` / `Fail`
lists by `events_for`: a flag naming an object replaces that object's entry of the file (a
demonstration's ``appear:``), and every entry must name existing areas, actions and objects.
For verification the ``--fail`` entries are the set of skills that *may* fail (none given:
every skill may fail), bounded by ``--max-failures`` per execution.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable, Sequence
from typing import Any

from tamp.world.events import Appear, Fail, check_events, override, parse_appear, parse_fail


def add_event_arguments(parser: argparse.ArgumentParser | Any, *, verify: bool = False) -> None:
    """Add ``--appear`` and ``--fail`` (repeatable) to ``parser`` (a parser or a group)."""
    parser.add_argument(
        "--appear",
        action="append",
        default=[],
        metavar="OBJ@PLACE[@WHEN]",
        help="an object is put at PLACE (area name or x,y[,z] in the robot frame) at WHEN "
        "(tick, t=SECONDS or after:Action(args)); without WHEN when the robot reaches it. "
        "Overrides the file's entry for that object",
    )
    parser.add_argument(
        "--fail",
        action="append",
        default=[],
        metavar="ACTION[(ARGS)][xTIMES]",
        help=(
            "a skill that may fail (default: every skill), e.g. Pick or Pick(O1)"
            if verify
            else "scripted skill failure: the first TIMES attempts fail, e.g. Pick(O1) or "
            "Place(O1, L1)x2"
        ),
    )


def events_for(
    args: argparse.Namespace,
    *,
    objects: Iterable[str],
    areas: Iterable[str],
    domain: Any,
    base: Sequence[Appear] = (),
) -> tuple[list[Appear], list[Fail]]:
    """Parse and check the flags; ``base`` holds the file's appearances (flags override)."""
    flags = [parse_appear(t, field="--appear") for t in getattr(args, "appear", [])]
    appear = override(base, flags)
    fail = [parse_fail(t, field="--fail") for t in getattr(args, "fail", [])]
    check_events(appear, fail, objects=objects, areas=areas, domain=domain)
    return appear, fail


def demo_events(args: argparse.Namespace, demo: Any) -> tuple[list[Appear], list[Fail]]:
    """`events_for` a demonstration: its objects, areas (goals and free), domain, ``appear:``."""
    state = demo.initial_world()
    return events_for(
        args, objects=demo.objects, areas=state.areas, domain=demo.domain(), base=demo.appear
    )
