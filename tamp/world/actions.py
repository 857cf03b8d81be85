"""Action templates with preconditions ``con`` and effects ``eff`` (SMP-MRO §IV-C1, §V-A3).

Templates are loaded from a per-robot YAML domain file (``tamp/world/domains/youbot.yaml``
is the paper's youBot: MoveTo, Pick, Place; ``lots_arm.yaml`` the LOTS arm of Zhou et al.:
LookAt, Pick, Place, Wait over object kinds), so another robot needs only another file.
A template grounded with argument values is an `Action`; applying it to a `WorldState`
makes each effect true in the listed order (``a.eef(s)`` of §IV-C1).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.world.events import parse_call
from tamp.world.predicates import DEFAULT_REACH, PREDICATES, IsRobotCloseTo, Predicate
from tamp.world.state import WorldState

#: place = an object or an area; kind = an object class (LOTS: "hammer")
PARAM_KINDS = ("object", "area", "place", "kind")
DOMAINS_DIR = Path(__file__).parent / "domains"


@dataclass(frozen=True, slots=True)
class CondPattern:
    """A condition with parameter names for arguments, e.g. ``IsRobotCloseTo(o)``."""

    predicate: str
    args: tuple[str, ...]

    def ground(self, binding: Mapping[str, str], reach: float = DEFAULT_REACH) -> Predicate:
        cls, _ = PREDICATES[self.predicate]
        values = [binding[a] for a in self.args]
        if cls is IsRobotCloseTo:
            return IsRobotCloseTo(values[0], reach)
        return cls(*values)

    def __str__(self) -> str:
        return f"{self.predicate}({', '.join(self.args)})"


def parse_pattern(text: object, params: Mapping[str, str], file: str, field: str) -> CondPattern:
    """Parse ``Name(a, b)`` (any YAML value: what is not such text is bad input) against the
    template's parameters, checking kinds."""
    name, args = parse_call(text, field=field, file=file)
    if name not in PREDICATES:
        raise InputError(
            f"unknown predicate {name!r} (known: {', '.join(PREDICATES)})", file=file, field=field
        )
    _, kinds = PREDICATES[name]
    if len(args) != len(kinds):
        raise InputError(
            f"{name} takes {len(kinds)} argument(s), got {len(args)}", file=file, field=field
        )
    for a, kind in zip(args, kinds, strict=True):
        if a not in params:
            raise InputError(f"{a!r} is not a parameter of this action", file=file, field=field)
        if kind != "place" and params[a] not in (kind,):
            raise InputError(
                f"{name} needs a {kind} for {a!r}, but {a!r} is a {params[a]}",
                file=file,
                field=field,
            )
    return CondPattern(name, args)


@dataclass(frozen=True)
class ActionTemplate:
    """An action schema: typed parameters, preconditions, effects, duration, success rate."""

    name: str
    params: tuple[tuple[str, str], ...]
    con: tuple[CondPattern, ...]
    eff: tuple[CondPattern, ...]
    duration: float = 0.0
    success_rate: float = 1.0

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p for p, _ in self.params)

    def ground(self, *args: str, reach: float = DEFAULT_REACH) -> Action:
        if len(args) != len(self.params):
            raise ValueError(f"{self.name} takes {len(self.params)} arguments, got {len(args)}")
        binding = dict(zip(self.param_names, args, strict=True))
        return Action(
            self,
            tuple(args),
            tuple(c.ground(binding, reach) for c in self.con),
            tuple(e.ground(binding, reach) for e in self.eff),
        )

    def bindings_achieving(self, cond: Predicate) -> list[dict[str, str]]:
        """Partial bindings making an effect equal ``cond`` (Alg. 3 GetAllActTemplatesFor)."""
        out = []
        for e in self.eff:
            if e.predicate != cond.name:
                continue
            values = cond.args[: len(e.args)]
            binding: dict[str, str] = {}
            ok = True
            for a, v in zip(e.args, values, strict=True):
                if binding.get(a, v) != v:
                    ok = False
                binding[a] = str(v)
            if ok:
                out.append(binding)
        return out


@dataclass(frozen=True)
class Action:
    """A ground action: template + argument values, with ground ``con`` and ``eff``."""

    template: ActionTemplate
    args: tuple[str, ...]
    con: tuple[Predicate, ...]
    eff: tuple[Predicate, ...]

    @property
    def name(self) -> str:
        return self.template.name

    def applicable(self, state: WorldState) -> bool:
        return all(c.holds(state) for c in self.con)

    def apply(self, state: WorldState) -> WorldState:
        for e in self.eff:
            state = e.achieve(state)
        return state

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.args)})"


@dataclass(frozen=True)
class Domain:
    """A robot's action templates plus the numbers cost models need."""

    robot: str
    templates: dict[str, ActionTemplate]
    reach: float = DEFAULT_REACH
    base_speed: float = 0.3
    source: str = "<builtin>"
    extra: dict = field(default_factory=dict)

    def template(self, name: str) -> ActionTemplate:
        return self.templates[name]

    def action(self, name: str, *args: str) -> Action:
        return self.templates[name].ground(*args, reach=self.reach)


def load_domain(path: str | Path) -> Domain:
    """Load and validate a domain file; every error names the file and field."""
    data, file = load_yaml(path, kind="domain")
    f = Fields(data, file)
    f.check_keys({"version", "robot", "reach", "base_speed", "actions"})
    robot = f.str("robot")
    reach = f.float("reach", DEFAULT_REACH, min=0.0, strict_min=True)
    speed = f.float("base_speed", 0.3, min=0.0, strict_min=True)
    templates: dict[str, ActionTemplate] = {}
    for item in f.items("actions"):
        if not isinstance(item, Fields):
            raise InputError("each action must be a mapping", file=file, field="actions")
        item.check_keys({"name", "params", "con", "eff", "duration", "success_rate"})
        name = item.str("name")
        if name in templates:
            raise item.error("name", f"duplicate action {name!r}")
        praw = item.raw("params", {})
        if not isinstance(praw, Mapping):
            raise item.error("params", "expected a mapping parameter: kind")
        params = {}
        for p, kind in praw.items():
            if kind not in PARAM_KINDS:
                raise item.error(f"params.{p}", f"kind must be one of {PARAM_KINDS}, got {kind!r}")
            params[str(p)] = kind
        con = tuple(
            parse_pattern(c, params, file, f"{item.path}.con[{i}]")
            for i, c in enumerate(item.items("con", []))
        )
        eff = tuple(
            parse_pattern(c, params, file, f"{item.path}.eff[{i}]")
            for i, c in enumerate(item.items("eff"))
        )
        if not eff:
            raise item.error("eff", "an action needs at least one effect")
        for i, e in enumerate(eff):
            cls, _ = PREDICATES[e.predicate]
            if cls.achieve is Predicate.achieve:  # e.g. IsAreaFree: a consequence, not an effect
                achievable = [
                    n for n, (c, _) in PREDICATES.items() if c.achieve is not Predicate.achieve
                ]
                raise item.error(
                    f"eff[{i}]",
                    f"no skill can make {e.predicate} true directly "
                    f"(effects may be: {', '.join(achievable)})",
                )
        templates[name] = ActionTemplate(
            name=name,
            params=tuple(params.items()),
            con=con,
            eff=eff,
            duration=item.float("duration", 0.0, min=0.0),
            success_rate=item.float("success_rate", 1.0, min=0.0, max=1.0, strict_min=True),
        )
    return Domain(robot=robot, templates=templates, reach=reach, base_speed=speed, source=file)


def default_domain() -> Domain:
    """The youBot domain of §V-A3 shipped with the package."""
    return packaged_domain("youbot")


def packaged_domain(name: str) -> Domain:
    """A domain shipped in ``tamp/world/domains`` by file stem (``youbot``, ``lots_arm``)."""
    path = DOMAINS_DIR / f"{name}.yaml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in DOMAINS_DIR.glob("*.yaml")))
        raise InputError(f"unknown domain {name!r} (known: {known})", field="domain")
    return load_domain(path)
