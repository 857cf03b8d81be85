"""``tamp schema FORMAT``: the JSON Schema of a YAML file format, for editors to validate with.

The formats read by the typed loader (`tamp.schema`: the simulation scenarios, the
refinement scenes and architectures) have their schema derived from the dataclasses the
loader reads (`tamp.schema.json_schema`), so it follows the code. The formats read by
hand-written loaders (demonstrations, domains, LTL tasks, interference events and refinement
programs) have their schema written here, beside the registry, from the loaders'
constants (choices, sides, sections); the tests validate every packaged file against its
format's schema, and a packaged file no format claims fails them. A schema states the keys,
types, bounds and choices; relations between fields (a goal named in a constraint exists, a
period no shorter than the step) stay the loader's to check.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path
from typing import Any

from tamp.errors import InputError

_DIALECT = "https://json-schema.org/draft/2020-12/schema"
_VERSION = {"const": 1, "description": "file format version"}
_NAME = {"type": "string", "minLength": 1}
_NUMBER = {"type": "number"}
_POSITIVE = {"type": "number", "exclusiveMinimum": 0}
_NONNEGATIVE = {"type": "number", "minimum": 0}


def _vec(n: int, description: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {"type": "array", "items": _NUMBER, "minItems": n, "maxItems": n}
    if description:
        out["description"] = description
    return out


def _obj(props: dict[str, Any], required: tuple[str, ...] = (), **more: Any) -> dict[str, Any]:
    """A mapping with exactly these keys (unknown keys are refused, as the loaders do)."""
    out: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    if required:
        out["required"] = list(required)
    out.update(more)
    return out


# --- hand-written schemas (their loaders read the files field by field) ----------------------


def _demonstration() -> dict[str, Any]:
    """`tamp.demo.loader.load_demonstration` (SMP-MRO §IV-A)."""
    return _obj(
        {
            "version": _VERSION,
            "name": _NAME,
            "description": {"type": "string"},
            "frame": _obj(
                {
                    "robot_position": _vec(3, "the robot's origin in the MR frame"),
                    "rotation": {
                        "type": "array",
                        "items": _vec(3),
                        "minItems": 3,
                        "maxItems": 3,
                        "description": "3x3 rotation MR -> robot (eq. 4-5)",
                    },
                    "handedness": {"type": "string", "enum": ["left", "right"]},
                },
                ("robot_position",),
            ),
            "area_radius": {**_POSITIVE, "description": "radius of every area [m]"},
            "object_height": {**_POSITIVE, "default": 0.2, "description": "[m]"},
            "robot": _obj(
                {
                    "start": _vec(3, "x, y, yaw in the robot frame"),
                    "domain": {"type": "string", "minLength": 1, "description": "domain file"},
                }
            ),
            "objects": {
                "type": "array",
                "items": _obj({"id": _NAME, "position": _vec(3)}, ("id", "position")),
            },
            "steps": {
                "type": "array",
                "items": _obj({"object": _NAME, "to": _vec(3)}, ("object", "to")),
            },
            "free_areas": {
                "type": "array",
                "items": _obj(
                    {"id": _NAME, "position": _vec(3), "radius": _POSITIVE}, ("id", "position")
                ),
            },
            "constraints": {
                "type": "array",
                "items": {"type": "array", "items": _NAME, "minItems": 2, "maxItems": 2},
                "description": "[Gi, Gj]: goal Gi before goal Gj",
            },
            "appear": {
                "type": "array",
                "items": {"type": "string", "description": "OBJ@PLACE[@WHEN]"},
            },
        },
        ("version", "frame", "area_radius", "objects", "steps"),
    )


def _domain() -> dict[str, Any]:
    """`tamp.world.actions.load_domain` (SMP-MRO §V-A3)."""
    from tamp.world.actions import PARAM_KINDS

    condition = {"type": "string", "description": "Predicate(args), e.g. IsRobotCloseTo(o)"}
    action = _obj(
        {
            "name": _NAME,
            "params": {"type": "object", "additionalProperties": {"enum": list(PARAM_KINDS)}},
            "con": {"type": "array", "items": condition},
            "eff": {"type": "array", "items": condition, "minItems": 1},
            "duration": {**_NONNEGATIVE, "default": 0.0, "description": "[s]"},
            "success_rate": {"type": "number", "exclusiveMinimum": 0, "maximum": 1},
        },
        ("name", "eff"),
    )
    return _obj(
        {
            "version": _VERSION,
            "robot": _NAME,
            "reach": {**_POSITIVE, "description": "IsRobotCloseTo distance [m]"},
            "base_speed": {**_POSITIVE, "default": 0.3, "description": "[m/s]"},
            "actions": {"type": "array", "items": action},
        },
        ("version", "robot", "actions"),
    )


def _lots_task() -> dict[str, Any]:
    """`tamp.lots.task.load_task` (Zhou et al., IEEE T-ASE 2023, §III)."""
    from tamp.lots.task import SIDES

    counts = {"type": "object", "additionalProperties": {"type": "integer", "minimum": 0}}
    return _obj(
        {
            "version": _VERSION,
            "name": _NAME,
            "description": {"type": "string"},
            "formula": {**_NAME, "description": "LTL over the propositions (Spot syntax)"},
            "propositions": {
                "type": "object",
                "additionalProperties": _obj(
                    {"class": _NAME, "cost": {**_POSITIVE, "default": 1.0}}, ("class",)
                ),
            },
            "initial": _obj({side: counts for side in SIDES}, description="objects per class"),
            "remove_cost": {**_POSITIVE, "default": 1.0},
            "actions": _obj({"return": {"type": "boolean", "default": False}}),
        },
        ("version", "formula", "propositions", "initial"),
    )


def _lots_interference() -> dict[str, Any]:
    """`tamp.lots.task.load_events`: the scripted person's events."""
    from tamp.lots.task import SIDES

    event = _obj(
        {
            "after": {"type": "integer", "minimum": 0, "description": "after this many actions"},
            "phase": {"enum": ["idle", "holding"], "default": "idle"},
            "kind": {"enum": ["move", "add", "remove"]},
            "class": _NAME,
            "count": {"type": "integer", "minimum": 1, "default": 1},
            "from": {"enum": list(SIDES)},
            "to": {"enum": list(SIDES)},
            "side": {"enum": list(SIDES)},
            "note": {"type": "string"},
        },
        ("after", "kind", "class"),
    )
    return _obj(
        {
            "version": _VERSION,
            "description": {"type": "string"},
            "events": {"type": "array", "items": event},
        },
        ("version",),
    )


def _refine_program() -> dict[str, Any]:
    """`tamp.refine.loader.load_program` (Figueroa Heredia et al. 2018, §2)."""
    from tamp.refine.program import CATEGORIES, MODELS, SECTIONS, SENSORS

    behavior = _obj(
        {
            "name": {"type": "string", "pattern": "^[A-Za-z][A-Za-z0-9_]*$"},
            "section": {"enum": list(SECTIONS)},
            "motion": _obj(
                {
                    "distance": {**_NUMBER, "description": "[m]"},
                    "angle": {**_NUMBER, "description": "[rad]"},
                    "speed": {**_POSITIVE, "description": "[m/s or rad/s]"},
                }
            ),
            "event": _obj(
                {
                    "sensor": {"enum": list(SENSORS)},
                    "above": _NUMBER,
                    "below": _NUMBER,
                    "reaches": _POSITIVE,
                    "after": {"type": "string", "description": "ROBOT.behavior"},
                }
            ),
            "waits_for": {"type": "array", "items": {"type": "string"}},
            "parallel_with": _NAME,
            "manipulates": {"type": "boolean", "default": False},
            "rate_hz": _POSITIVE,
        },
        ("name", "section", "motion", "event"),
    )
    robot = _obj(
        {
            "name": {"type": "string", "pattern": "^[A-Za-z][A-Za-z0-9_]*$"},
            "model": {"enum": list(MODELS)},
            "start": _vec(3, "x, y, yaw"),
            "behaviors": {"type": "array", "items": behavior},
        },
        ("name", "model", "start", "behaviors"),
    )
    return _obj(
        {
            "version": _VERSION,
            "name": _NAME,
            "description": {"type": "string"},
            "scene": {**_NAME, "description": "a packaged scene or a scene file"},
            "architecture": {**_NAME, "description": "architecture file"},
            "communication": _obj(
                {
                    "category": {"enum": list(CATEGORIES)},
                    "sensor_rate_hz": _POSITIVE,
                    "command_rate_hz": _POSITIVE,
                    "base_speed": {**_POSITIVE, "description": "[m/s]"},
                },
                ("sensor_rate_hz", "command_rate_hz", "base_speed"),
            ),
            "ordering": {**_NAME, "description": "LTL over ROBOT.behavior events"},
            "robots": {"type": "array", "items": robot},
            "perturbation": {"type": "object", "description": "seeded runs: tamp.perturbation"},
        },
        ("version", "scene", "communication", "ordering", "robots"),
    )


# --- derived schemas (the typed loader's dataclasses) ----------------------------------------


def _sim_smp() -> dict[str, Any]:
    from tamp.schema import json_schema
    from tamp.sim.smp.scenario import ScenarioFile

    return json_schema(ScenarioFile, extra={"version": _VERSION}, required_extra=["version"])


def _sim_lots() -> dict[str, Any]:
    from tamp.schema import json_schema
    from tamp.sim.lots.scenario import CellScenario, ObjectEntry

    entry = json_schema(ObjectEntry)
    entry.pop("$schema")
    return json_schema(
        CellScenario,
        extra={"version": _VERSION, "objects": {"type": "array", "items": entry}},
        required_extra=["version"],
    )


def _refine_architecture() -> dict[str, Any]:
    """`tamp.refine.architecture.load_architecture` (Figueroa Heredia et al. 2018, Table 1)."""
    from tamp.refine.architecture import Architecture
    from tamp.refine.program import CATEGORIES
    from tamp.schema import json_schema

    doc = json_schema(Architecture, extra={"version": _VERSION}, required_extra=["version"])
    doc["properties"]["categories"]["required"] = list(CATEGORIES)  # the loader needs each
    return doc


def _refine_scene() -> dict[str, Any]:
    from tamp.schema import json_schema
    from tamp.sim.refine.scenario import Scene

    return json_schema(Scene, extra={"version": _VERSION}, required_extra=["version"])


@dataclass(frozen=True)
class Format:
    """One YAML file format: its name, what it is, the function that reads it, the packaged
    files written in it (globs under the ``tamp`` package) and how its schema is made."""

    name: str
    title: str
    loader: str
    examples: tuple[str, ...]
    make: Callable[[], dict[str, Any]]

    def schema(self) -> dict[str, Any]:
        """The JSON Schema document (draft 2020-12)."""
        doc = self.make()
        doc.pop("$schema", None)
        return {"$schema": _DIALECT, "title": f"tamp {self.name} file ({self.title})", **doc}

    def example_files(self) -> list[Path]:
        """The packaged files of this format."""
        root = Path(str(files("tamp")))
        return sorted(p for pattern in self.examples for p in root.glob(pattern))

    def example_paths(self) -> list[str]:
        """The packaged files as paths under the package (``tamp/scenarios/...``)."""
        root = Path(str(files("tamp"))).parent
        return [p.relative_to(root).as_posix() for p in self.example_files()]


#: Every YAML format, by the name ``tamp schema`` takes.
FORMATS: dict[str, Format] = {
    f.name: f
    for f in (
        Format(
            "demonstration",
            "a mixed-reality demonstration: objects, steps, constraints",
            "tamp.demo.loader.load_demonstration",
            ("scenarios/case*.yaml",),
            _demonstration,
        ),
        Format(
            "domain",
            "a robot's action templates",
            "tamp.world.actions.load_domain",
            ("world/domains/*.yaml",),
            _domain,
        ),
        Format(
            "lots-task",
            "an LTL task over object classes in W^A and W^B",
            "tamp.lots.task.load_task",
            ("scenarios/lots/example1.yaml", "scenarios/lots/model_building.yaml")
            + ("scenarios/lots/tower.yaml",),
            _lots_task,
        ),
        Format(
            "lots-interference",
            "the scripted person's interference events",
            "tamp.lots.task.load_events",
            ("scenarios/lots/*_interference.yaml", "scenarios/lots/model_building_fig*.yaml"),
            _lots_interference,
        ),
        Format(
            "sim-smp",
            "an SMP-MRO simulation scenario (Drake)",
            "tamp.sim.smp.scenario.load_scenario",
            ("scenarios/sim/*.yaml",),
            _sim_smp,
        ),
        Format(
            "sim-lots",
            "a LOTS workcell scenario (Drake)",
            "tamp.sim.lots.scenario.load_cell_scenario",
            ("scenarios/lots_sim/*.yaml",),
            _sim_lots,
        ),
        Format(
            "refine-program",
            "a two-robot program",
            "tamp.refine.loader.load_program",
            ("scenarios/refine/task*.yaml", "scenarios/refine/table_collision.yaml"),
            _refine_program,
        ),
        Format(
            "refine-architecture",
            "a communication architecture",
            "tamp.refine.architecture.load_architecture",
            ("scenarios/refine/*architecture.yaml", "scenarios/refine/architecture_*.yaml"),
            _refine_architecture,
        ),
        Format(
            "refine-scene",
            "a refinement scene: task objects, placement, goals",
            "tamp.sim.refine.scenario.load_scene",
            ("scenarios/refine/scenes/*.yaml",),
            _refine_scene,
        ),
    )
}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "schema",
        help="print the JSON Schema of a YAML file format",
        description="Print the JSON Schema (draft 2020-12) of a YAML file format, for an "
        "editor to validate files with.",
    )
    p.add_argument(
        "format",
        metavar="FORMAT",
        nargs="?",
        help=f"one of: {', '.join(FORMATS)} (none: list them)",
    )
    p.add_argument(
        "--out",
        metavar="DIR",
        help="write FORMAT.json into the folder DIR (every format's when no FORMAT is given) "
        "instead of printing",
    )
    p.set_defaults(func=run)


def _text(name: str) -> str:
    return json.dumps(FORMATS[name].schema(), indent=2, ensure_ascii=False) + "\n"


def run(args: argparse.Namespace) -> int:
    if args.format is not None and args.format not in FORMATS:
        raise InputError(f"unknown format {args.format!r} (formats: {', '.join(FORMATS)})")
    if args.out:  # a folder, as --out is everywhere
        from tamp.commands.output import output_dir

        folder = output_dir(args.out, "--out")
        folder.mkdir(parents=True, exist_ok=True)
        for name in [args.format] if args.format else list(FORMATS):
            (folder / f"{name}.json").write_text(_text(name), encoding="utf-8")
        return 0
    if args.format is None:
        for f in FORMATS.values():
            print(f"{f.name:<20} {f.title}")
        return 0
    sys.stdout.write(_text(args.format))
    return 0
