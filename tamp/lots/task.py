"""LTL task and interference-script files (YAML, ``version: 1``), strictly validated.

Task file (what each proposition moves, the formula in Spot syntax, the initial counts)::

    version: 1
    name: tower
    formula: "F(p1 & F(p2 & F p3))"
    propositions:
      p1: {class: bottom}          # move one 'bottom' from W^A to W^B
      p2: {class: body, cost: 1.0}
      p3: {class: peak}
    initial:
      A: {bottom: 1, body: 2, peak: 1}
      B: {}
    remove_cost: 1.0   # optional: one object out of W^B (into the waste basket)
    actions: {return: false}   # optional: true switches on our return action (W^B -> W^A)

The robot's actions are Zhou et al.'s (Def. 3): ``a_B^A(o_i)`` picks an object from W^A and
places it in W^B, and discarding an object into the waste basket. ``actions: {return: true}``
adds an extension of ours, not in the paper: taking an object out of W^B *back to W^A*, so
that it can be delivered again (one hammer delivered twice for ``F(p1 & F p2)``). Lemma 1
and Theorem 1 assume that W^B's counts never go back under the robot's own actions; with
the return action they do, so it is off unless the task (or ``--return-action``) asks for it.

Interference file (human actions, §III-B: dis_1 moves, dis_2 adds/removes)::

    version: 1
    events:
      - {after: 1, kind: add, class: body, side: B}        # dis_2
      - {after: 2, phase: holding, kind: remove, class: body, side: B}
      - {after: 4, kind: move, class: body, from: B, to: A} # dis_1

``after: N`` means after the robot's N-th action (0: before the first); ``phase: holding``
means while the robot carries the object of its next action (between pick and place), which
is how a person changes W^B unseen by the eye-in-hand camera.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass, field
from pathlib import Path

from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.scenarios import resolve

SIDES = ("A", "B")
#: what a class (and a proposition) is named: a lower-case identifier
CLASS_NAME = _NAME = re.compile(r"^[a-z_][a-z0-9_]*$")


@dataclass(frozen=True)
class Proposition:
    """``p``: move one object of class ``cls`` from W^A to W^B, at ``cost``."""

    name: str
    cls: str
    cost: float = 1.0


@dataclass(frozen=True)
class Task:
    """An LTL task over object deliveries, with the initial object counts per workspace."""

    formula: str
    propositions: tuple[Proposition, ...]
    initial_a: dict[str, int]
    initial_b: dict[str, int] = field(default_factory=dict)
    remove_cost: float = 1.0
    name: str = "task"
    file: str | None = None
    #: our extension (not Zhou et al.'s action set): an object may go back from W^B to W^A
    returns: bool = False

    @property
    def props(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.propositions)

    @property
    def classes(self) -> tuple[str, ...]:
        """Task-related object classes, in order of first use by a proposition."""
        out: list[str] = []
        for p in self.propositions:
            if p.cls not in out:
                out.append(p.cls)
        return tuple(out)

    def prop(self, name: str) -> Proposition:
        for p in self.propositions:
            if p.name == name:
                return p
        raise KeyError(name)


@dataclass(frozen=True)
class Event:
    """One human action. ``kind``: ``move`` (dis_1) or ``add``/``remove`` (dis_2)."""

    after: int
    kind: str
    cls: str
    count: int = 1
    phase: str = "idle"
    src: str | None = None  # move: from
    dst: str | None = None  # move: to
    side: str | None = None  # add / remove
    note: str = ""
    where: str = ""  # "file: events[i]" for run-time errors

    @property
    def disturbance(self) -> str:
        return "dis_1" if self.kind == "move" else "dis_2"

    def describe(self) -> str:
        n = f"{self.count} " if self.count != 1 else ""
        if self.kind == "move":
            text = f"person moves {n}{self.cls} {self.src}→{self.dst}"
        elif self.kind == "add":
            text = f"person adds {n}{self.cls} to W^{self.side}"
        else:
            text = f"person removes {n}{self.cls} from W^{self.side}"
        return f"{text} ({self.disturbance})"

    def when(self) -> str:
        """When the script times it: ``after action N`` (``while carrying`` for holding)."""
        slot = "while the robot carries action" if self.phase == "holding" else "after action"
        n = self.after + 1 if self.phase == "holding" else self.after
        return f"{slot} {n}"

    def to_json(self) -> dict:
        """JSON-ready: timing, the description, and where the script declares it."""
        return {
            "after": self.after,
            "phase": self.phase,
            "event": self.describe(),
            "where": self.where,
        }

    def never_happened(self) -> str:
        """The line a run prints for a scripted event it ended before."""
        where = f" [{self.where}]" if self.where else ""
        return f"never happened: {self.describe()} {self.when()}{where}"

    def unfired_json(self) -> dict:
        """JSON of a scripted event the run ended before: `to_json` and the printed line."""
        return self.to_json() | {"message": self.never_happened()}


def load_task(path: str | Path) -> Task:
    """Read and validate a task file; any error is an `InputError` naming file and field."""
    data, name = load_yaml(resolve(path, "lots"), kind="LTL task")
    f = Fields(data, name)
    f.check_keys(
        [
            "version",
            "name",
            "description",
            "formula",
            "propositions",
            "initial",
            "remove_cost",
            "actions",
        ]
    )
    formula = f.str("formula")
    props_f = f.sub("propositions")
    if not props_f.data:
        raise props_f.error(None, "at least one proposition is needed")
    props: list[Proposition] = []
    for key in props_f.data:
        pname = str(key)
        if not _NAME.match(pname):
            raise props_f.error(pname, "proposition names are lower-case identifiers")
        pf = props_f.sub(pname)
        pf.check_keys(["class", "cost"])
        cls = pf.str("class")
        if not _NAME.match(cls):
            raise pf.error("class", f"class names are lower-case identifiers, got {cls!r}")
        props.append(Proposition(pname, cls, pf.float("cost", 1.0, min=0.0, strict_min=True)))
    init = f.sub("initial")
    init.check_keys(SIDES)
    counts = {side: _counts(init, side) for side in SIDES}
    task = Task(
        formula=formula,
        propositions=tuple(props),
        initial_a=counts["A"],
        initial_b=counts["B"],
        remove_cost=f.float("remove_cost", 1.0, min=0.0, strict_min=True),
        name=f.str("name", Path(name).stem),
        file=name,
        returns=_returns(f),
    )
    return task


def _returns(f: Fields) -> bool:
    """``actions: {return: BOOL}``: is our return action (W^B back to W^A) switched on?"""
    if not f.has("actions"):
        return False
    acts = f.sub("actions")
    if not isinstance(acts.data, dict):
        raise f.error("actions", "expected a mapping, e.g. {return: true}")
    acts.check_keys(["return"])
    return acts.bool("return", False)


def _counts(init: Fields, side: str) -> dict[str, int]:
    sub = init.sub(side, {})
    out: dict[str, int] = {}
    for key in sub.data:
        cls = str(key)
        if not _NAME.match(cls):
            raise sub.error(cls, "class names are lower-case identifiers")
        out[cls] = sub.int(cls, min=0)
    return out


def load_events(path: str | Path, task: Task) -> list[Event]:
    """Read and validate an interference script against ``task`` (classes, sides, counts)."""
    data, name = load_yaml(resolve(path, "lots"), kind="interference")
    f = Fields(data, name)
    f.check_keys(["version", "description", "events"])
    events: list[Event] = []
    for i, item in enumerate(f.items("events", [])):
        if not isinstance(item, Fields):
            raise InputError("expected a mapping", file=name, field=f"events[{i}]")
        events.append(_event(item, task))
    return events


def _event(e: Fields, task: Task) -> Event:
    e.check_keys(["after", "phase", "kind", "class", "count", "from", "to", "side", "note"])
    kind = e.str("kind", choices=("move", "add", "remove"))
    cls = e.str("class")
    if not _NAME.match(cls):
        raise e.error("class", f"class names are lower-case identifiers, got {cls!r}")
    event = functools.partial(
        Event,
        after=e.int("after", min=0),
        kind=kind,
        cls=cls,
        count=e.int("count", 1, min=1),
        phase=e.str("phase", "idle", choices=("idle", "holding")),
        note=e.str("note", "") if e.has("note") else "",
        where=f"{e.file}: {e.path}",
    )
    if kind == "move":
        for bad in ("side",):
            if e.has(bad):
                raise e.error(bad, "a move (dis_1) takes 'from' and 'to', not 'side'")
        src = e.str("from", choices=SIDES)
        dst = e.str("to", choices=SIDES)
        if src == dst:
            raise e.error("to", "'from' and 'to' must differ")
        if cls not in task.classes and cls not in task.initial_a and cls not in task.initial_b:
            raise e.error("class", f"no {cls!r} objects exist in this task to move")
        return event(src=src, dst=dst)
    for bad in ("from", "to"):
        if e.has(bad):
            raise e.error(bad, f"an {kind} (dis_2) takes 'side', not 'from'/'to'")
    return event(side=e.str("side", choices=SIDES))
