"""What the refinement workcell loads: a program with its architecture and its scene.

`load_scenario` reads a program file (`tamp.refine.loader`), its communication
architecture (the packaged calibrated one unless the program names another) and the scene
it runs in into a `RefineScenario`; the program's ``perturbation`` section may ask only for
what this workcell simulates (`PERTURBED`: each robot's start pose). The scene is the
cell's own file format (YAML, ``version: 1``), below.

A scene (Figueroa Heredia et al. 2018, Fig. 9) declares the task's objects, where each lies
and what the task must achieve with them, measured on the plant at the end of a run. A
program names its scene (``scene:``, `tamp.refine.loader`): a packaged scene
(``tamp/scenarios/refine/scenes/<name>.yaml``: flip_briefcase, flip_scale, lift_scale,
open_chair, table) or the user's scene file, relative to the program file. The robots are
the program's (``robots[].start``); Robot 1 starts on the -x side facing +x, Robot 2 on the
+x side facing -x, the objects between them. No Drake import here.

Format (the fields, their defaults and bounds are stated once, in the dataclasses below)::

    version: 1
    name: open_chair                  # default: the file's stem
    description: The folded chair lying on the floor (Fig. 9(d)).
    objects:
      - model: folding_chair          # a packaged model (tamp/models/sdf/<name>.sdf), an .sdf
                                      # file relative to this file, or a
                                      # package://tamp_models/... URL
        name: folding_chair           # the object's name in the plant (default: the model's)
        x: 0.0                        # m, its first body's origin in the world
        y: 0.0
        z: 0.0
        yaw: 0.0                      # rad about the vertical (default 0)
        fixed: false                  # true: welded to the world, scenery (default false)
    time_step: 0.02                   # s, the coarsest plant step and systems' tick, for
                                      # slow programs (default 0.01; at most 0.02, so P can
                                      # reach 50 Hz; `tamp.sim.refine.station.time_step`)
    goals:                            # all must hold for the task to succeed (default none)
      - quantity: folding_chair.hinge # <object>.<revolute joint> (rad), <object>.tilt (rad
                                      # between its up axis and the world's), <object>.rise
                                      # (m its origin rose)
        at_least: 0.35
        at_most: 1.2                  # optional
        what: the chair opened at its hinge

A fixed object is scenery: a robot touching it is a collision (Step 2's check). Every
error is an `InputError` naming the file and the dotted field (CLI exit 2); a goal naming a
joint the object's model does not have is refused when the station is built.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path

from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml
from tamp.perturbation import Perturbation
from tamp.refine.architecture import Architecture, default_architecture, load_architecture
from tamp.refine.loader import load_program, scene_path
from tamp.refine.measure import Goal
from tamp.refine.program import Program
from tamp.schema import load_dataclass, spec
from tamp.sim.core.models import PACKAGE, model_path, model_url, sdf_path

#: the ``perturbation`` fields this workcell simulates
PERTURBED = ("robot",)
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def _model(raw: object, f: Fields, key: str) -> str:
    """An object's ``model`` as Drake loads it: a packaged model's ``package://`` URL, or the
    absolute SDFormat file of a model of the user's (`tamp.sim.core.models.model_path`)."""
    ref = f.str(key)
    if "://" in ref or "/" in ref or ref.endswith(".sdf"):
        return str(model_path(ref, Path(f.file).parent, f, key))
    if not sdf_path(ref).is_file():
        raise f.error(
            key,
            f"no packaged model {ref!r} (tamp/models/sdf/{ref}.sdf); a model of your own is an "
            f".sdf file relative to the scene file or a package://{PACKAGE}/ URL",
        )
    return model_url(ref)


@dataclass(frozen=True)
class SceneObject:
    """One object of a scene: its model, placed at ``(x, y, z, yaw)``, free or welded."""

    model: str = spec(
        parse=_model,
        help="a packaged model name, an .sdf file relative to the scene file, or a "
        "package:// URL (stored as the packaged model's URL or the absolute file)",
    )
    x: float = spec(unit="m")
    y: float = spec(unit="m")
    z: float = spec(unit="m")
    name: str | None = spec(None, help="its name in the plant (default: the model's)")
    yaw: float = spec(0.0, unit="rad")
    fixed: bool = spec(False, help="welded to the world: scenery no robot may touch")

    def check(self, f: Fields) -> None:
        if self.name is not None and not _NAME.match(self.name):
            raise f.error("name", f"names are identifiers (letters, digits, _), got {self.name!r}")


@dataclass(frozen=True)
class Scene:
    """A scene (module docstring); ``objects`` have their names filled in."""

    objects: tuple[SceneObject, ...] = spec(min_items=1)
    goals: tuple[Goal, ...] = spec(())
    name: str | None = spec(None, help="default: the file's stem")
    description: str = spec("")
    time_step: float = spec(
        0.01,
        min=0.001,
        max=0.02,
        unit="s",
        help="the coarsest plant step and tick of the channels, state machines and "
        "supervisor, used for programs whose motions advance at most 1 mm (or 1 mrad) per "
        "step (a command leaves on a tick: P is at most 1 / step); larger than 0.01 only "
        "where the scene's objects stay put and the task's verdicts hold (docs/refinement.md)",
    )
    file: str | None = None

    def object(self, name: str) -> SceneObject:
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(name)


def default_name(model: str) -> str:
    """The name of a model's object when the scene gives none: the model file's stem."""
    return Path(model.rpartition("/")[2]).stem


def load_scene(name_or_path: str | Path) -> Scene:
    """Read and validate a scene file (a path, or a packaged scene's name resolved by
    `tamp.refine.loader.scene_path`); any problem is an `InputError` (file, field)."""
    data, file = load_yaml(scene_path(name_or_path), kind="refinement scene")
    f = Fields(data, file)
    scene = load_dataclass(Scene, f, extra_keys=("version",))
    objects = tuple(
        dataclasses.replace(o, name=o.name or default_name(o.model)) for o in scene.objects
    )
    seen: set[str] = set()
    for i, o in enumerate(objects):
        if o.name in seen:
            raise InputError(
                f"two objects are named {o.name!r} (give one a name)",
                file=file,
                field=f"objects[{i}].name",
            )
        seen.add(o.name)
    for i, g in enumerate(scene.goals):
        obj = g.quantity.partition(".")[0]
        if obj not in seen:
            raise InputError(
                f"no object {obj!r} in this scene (objects: {', '.join(sorted(seen))})",
                file=file,
                field=f"goals[{i}].quantity",
            )
    return dataclasses.replace(
        scene,
        objects=objects,
        name=scene.name or Path(file).stem,
        description=scene.description.strip(),
        file=file,
    )


@dataclass(frozen=True)
class RefineScenario:
    """One run's input: the program, the architecture it is measured under, its scene."""

    program: Program
    architecture: Architecture
    scene: Scene


def program_perturbation(program: Program) -> Perturbation:
    """``program``'s ``perturbation`` section, refused (`InputError` naming the field) when
    it asks for what this workcell does not simulate."""
    program.perturbation.require(PERTURBED, "refinement")
    return program.perturbation


def load_scenario(name_or_path: str | Path) -> RefineScenario:
    """A program file (or packaged name such as ``task4``) with its architecture and its
    scene, every file validated (`InputError` naming file and field, nothing half-done)."""
    program = load_program(name_or_path)
    program_perturbation(program)
    if program.architecture:
        architecture = load_architecture(program.architecture)
    else:
        architecture = default_architecture()
    return RefineScenario(program, architecture, load_scene(program.scene))
