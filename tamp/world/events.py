"""What can happen during a run, said one way everywhere: flags, scenario files, verification.

The run vocabulary (docs/architecture.md, "Command line"): ``--appear OBJ@PLACE[@WHEN]`` and
``--fail ACTION[(ARGS)][xTIMES]``.

- PLACE is an area name (``L1``) or a point ``x,y[,z]`` in the robot frame (metres).
- WHEN is a tick (``5``; ``0``: there from the start), a time ``t=SECONDS`` (simulated time;
  a symbolic world converts with its tick period), or ``after:Action(args)`` (right after
  that skill succeeds). Without WHEN the object is *discovered*: it appears when the robot
  first comes within reach of the place (SMP-MRO §V-D2, Case 3's O_a at l_1).
- ``--fail Pick(O1)`` makes the first attempt of Pick(O1) fail; ``Place(O1, L1)x2`` the first
  two attempts; ``MoveTo`` the first MoveTo whatever its target. For verification the same
  entries name the set of skills that *may* fail, with a bound on failures per execution.

`parse_call` is the project's one parser of ``NAME(args)`` strings (actions in flags, in
scenario files and in ground predicates of properties).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from tamp.errors import InputError, short_repr
from tamp.world.geometry import Point

_NAME = r"[A-Za-z_][\w\-]*"
_CALL = re.compile(rf"^\s*({_NAME})\s*(?:\(\s*([^()]*?)\s*\))?\s*$")
_TIMES = re.compile(r"^(.*?)\s*x\s*(\d+)\s*$")
_OBJ = re.compile(rf"^{_NAME}$")


def parse_call(
    text: object, *, field: str = "action", file: str | None = None
) -> tuple[str, tuple[str, ...]]:
    """``"Pick(O1)"`` -> ``("Pick", ("O1",))``; ``"MoveTo"`` -> ``("MoveTo", ())``.

    Arguments are separated by commas, blanks around them ignored. Anything else is bad
    input naming ``field`` (and ``file``).
    """
    m = _CALL.match(str(text))
    if not m:
        raise InputError(f"expected NAME or NAME(args), got {_short(text)}", field=field, file=file)
    name, inner = m.group(1), m.group(2)
    args = tuple(a.strip() for a in inner.split(",")) if inner else ()
    if any(not a for a in args):
        raise InputError(f"empty argument in {_short(text)}", field=field, file=file)
    return name, args


def format_call(name: str, args: tuple[str, ...] | None) -> str:
    """The inverse of `parse_call`: ``Pick(O1)``, or the bare name when ``args`` is None."""
    return name if args is None else f"{name}({', '.join(args)})"


@dataclass(frozen=True)
class AtTick:
    """At executor tick ``tick`` (0: present from the start)."""

    tick: int

    def __str__(self) -> str:
        return str(self.tick)


@dataclass(frozen=True)
class AtTime:
    """At simulated time ``seconds``."""

    seconds: float

    def __str__(self) -> str:
        return f"t={self.seconds:g}"


@dataclass(frozen=True)
class AfterAction:
    """Right after the skill ``name(args)`` succeeds (the first time it does)."""

    name: str
    args: tuple[str, ...]

    def matches(self, name: str, args: tuple[str, ...]) -> bool:
        return self.name == name and self.args == tuple(args)

    def __str__(self) -> str:
        return f"after:{format_call(self.name, self.args)}"


#: When an event fires; None means "when the robot first comes within reach of the place".
When = AtTick | AtTime | AfterAction | None


@dataclass(frozen=True)
class Appear:
    """Object ``obj`` is put at ``place`` (an area name or a point) at ``when``.

    Used for objects that are not in the demonstration (Case 3's O_a) and, with a known
    object, for a person moving it (it is dropped from the hand if held). ``kind``: the class
    of a new object (LOTS tasks name objects by class); a known object keeps its own.
    ``count``: how many interchangeable objects of ``kind`` a new pile holds, or how many a
    person takes off a known pile (`tamp.world.state.WorldState.split`).
    """

    obj: str
    place: str | Point
    when: When = None
    kind: str = ""
    count: int = 1

    def __str__(self) -> str:
        where = self.place if isinstance(self.place, str) else _point_text(self.place)
        return f"{self.obj}@{where}" + (f"@{self.when}" if self.when is not None else "")


@dataclass(frozen=True)
class Remove:
    """Object ``obj`` leaves the workcell now (a person takes it away: LOTS dis_2);
    ``count`` of a pile takes that many of its objects (None: all of them)."""

    obj: str
    count: int | None = None

    def __str__(self) -> str:
        return f"remove {self.obj}" + (f" x{self.count}" if self.count is not None else "")


@dataclass(frozen=True)
class Fail:
    """The first ``times`` attempts of ``action`` (with ``args``, if given) fail."""

    action: str
    args: tuple[str, ...] | None = None
    times: int = 1

    def matches(self, name: str, args: tuple[str, ...]) -> bool:
        return name == self.action and (self.args is None or tuple(args) == self.args)

    def __str__(self) -> str:
        return format_call(self.action, self.args) + (f"x{self.times}" if self.times != 1 else "")


def parse_when(text: str, *, field: str, file: str | None = None) -> When:
    """``5`` | ``t=2.5`` | ``after:Pick(O1)`` -> `AtTick` | `AtTime` | `AfterAction`."""
    s = text.strip()
    if s.startswith("after:"):
        name, args = parse_call(s[len("after:") :], field=field, file=file)
        return AfterAction(name, args)
    if s.startswith("t="):
        seconds = _number(s[2:], field=field, file=file)
        if seconds < 0:
            raise InputError(f"time must be >= 0, got {_short(s)}", field=field, file=file)
        return AtTime(seconds)
    if s.isdigit():
        return AtTick(int(s))
    raise InputError(
        f"WHEN must be a tick, t=SECONDS or after:Action(args), got {_short(s)}",
        field=field,
        file=file,
    )


def parse_place(text: str, *, field: str, file: str | None = None) -> str | Point:
    """An area name, or ``x,y[,z]`` -> `Point` (finite numbers, z defaults to 0)."""
    s = text.strip()
    if _OBJ.match(s):
        return s
    parts = s.split(",")
    if len(parts) not in (2, 3):
        raise InputError(
            f"PLACE must be an area name or x,y[,z], got {_short(s)}", field=field, file=file
        )
    xyz = [_number(p, field=field, file=file) for p in parts]
    return Point(xyz[0], xyz[1], xyz[2] if len(xyz) == 3 else 0.0)


def parse_appear(text: str, *, field: str = "--appear", file: str | None = None) -> Appear:
    """``OBJ@PLACE[@WHEN]`` -> `Appear` (see the module docstring)."""
    s = str(text).strip()
    obj, sep, rest = s.partition("@")
    if not sep or not _OBJ.match(obj.strip()):
        raise InputError(f"expected OBJ@PLACE[@WHEN], got {_short(s)}", field=field, file=file)
    place_text, sep2, when_text = rest.partition("@")
    when = parse_when(when_text, field=field, file=file) if sep2 else None
    return Appear(obj.strip(), parse_place(place_text, field=field, file=file), when)


def parse_fail(text: str, *, field: str = "--fail", file: str | None = None) -> Fail:
    """``ACTION[(ARGS)][xTIMES]`` -> `Fail` (a bare name matches any arguments)."""
    s = str(text).strip()
    times = 1
    m = _TIMES.match(s)
    if m and (m.group(1).endswith(")") or _OBJ.match(m.group(1))):
        s, times = m.group(1), int(m.group(2))
    if times < 1:
        raise InputError("TIMES must be at least 1", field=field, file=file)
    name, args = parse_call(s, field=field, file=file)
    return Fail(name, args if "(" in s else None, times)


def override(base: Sequence[Appear], flags: Sequence[Appear]) -> list[Appear]:
    """``base`` (a file's events) with every object named in ``flags`` replaced by the flags'."""
    named = {a.obj for a in flags}
    return [a for a in base if a.obj not in named] + list(flags)


def check_events(
    appear: Sequence[Appear],
    fail: Sequence[Fail],
    *,
    objects: Iterable[str],
    areas: Iterable[str],
    domain: Any,
    fields: Mapping[str, str] | None = None,
    file: str | None = None,
) -> None:
    """Refuse events that could never happen as written (exit 2 naming the field).

    An area PLACE must exist; ``after:`` and ``--fail`` must name an action of ``domain``
    (a `tamp.world.actions.Domain`) with the right number of arguments, and object
    arguments must be objects of the task or objects that appear. ``fields`` names the
    flag or file field of each kind (default ``--appear`` / ``--fail``).
    """
    fields = {"appear": "--appear", "fail": "--fail", **(fields or {})}
    area_names = set(areas)
    known = set(objects) | {a.obj for a in appear}
    for a in appear:
        field = fields["appear"]
        if isinstance(a.place, str) and a.place not in area_names:
            raise InputError(
                f"{a}: unknown area {a.place!r} (known: {', '.join(sorted(area_names))})",
                field=field,
                file=file,
            )
        if isinstance(a.when, AfterAction):
            _check_action(a.when.name, a.when.args, domain, known, field=field, file=file)
    for f in fail:
        _check_action(f.action, f.args, domain, known, field=fields["fail"], file=file)


def _check_action(
    name: str, args: tuple[str, ...] | None, domain: Any, known: set[str], *, field: str, file
) -> None:
    templates = domain.templates
    if name not in templates:
        raise InputError(
            f"unknown action {name!r} (known: {', '.join(templates)})", field=field, file=file
        )
    if args is None:
        return
    params = templates[name].params
    if len(args) != len(params):
        raise InputError(
            f"{name} takes {len(params)} argument(s), got {len(args)}", field=field, file=file
        )
    for (_, kind), arg in zip(params, args, strict=True):
        if kind == "object" and arg not in known:
            raise InputError(
                f"{name}: unknown object {arg!r} (known: {', '.join(sorted(known))})",
                field=field,
                file=file,
            )


def _number(text: str, *, field: str, file: str | None) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"not a number: {_short(text)}", field=field, file=file) from None
    if not math.isfinite(v) or abs(v) > 1e6:
        raise InputError(f"number out of range: {_short(text)}", field=field, file=file)
    return v


def _point_text(p: Point) -> str:
    return f"{p.x:g},{p.y:g},{p.z:g}"


def _short(value: object) -> str:
    return short_repr(str(value))
