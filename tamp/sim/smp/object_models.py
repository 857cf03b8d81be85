"""Object models a scenario declares itself (``models:``), beside the packaged ones.

A user brings an object of their own to the SMP-MRO workcell without code: an SDFormat
model file and the few numbers the skills and the scenario checks need (what
`tamp.sim.smp.robot.ObjectKind` holds for the packaged bottle and obstacle). The scenario's
``objects[].model`` then names it like a packaged model. Example::

    models:
      can:                            # the model's name, used by objects[].model
        sdf: models/can.sdf           # relative to the scenario file, or package://tamp_models/...
        height: 0.12                  # m, floor to top; the model's origin is at its centre
        radius: 0.033                 # m, footprint radius (overlaps, base paths)
        half_width: 0.033             # m, half the width the fingers close on (default: radius)
        colour: [0.9, 0.1, 0.1]       # RGB(A) in [0, 1]: replaces the SDF's visual colours
    objects:
      - {id: C1, model: can, pose: [1.2, -0.4, 0.0]}

The model file is read when the scenario loads (no Drake import here): it must exist, be an
SDFormat file with one ``<model>``, and have the link the gripper holds (``body``, or its
only link). `object_sdf` gives the text the station parses for one object of any kind: the
model renamed to the object's id, a run's drawn friction, the declared colour, and relative
``<uri>`` references made absolute (the text is parsed from a string, without a folder).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

from tamp.fileio import Fields
from tamp.schema import spec
from tamp.sim.core.models import absolute_uris, model_path, renamed_model, with_friction
from tamp.sim.smp.robot import ROBOT, ObjectKind

#: the finger pads reach this far above the grasp point (``youbot.sdf``: pads 0 and 3 cm
#: above it, 2 cm tall): an object is held by both pads when its top is at least this high
PAD_REACH = 0.04
#: the fingers approach from 2 mm outside the object (`tamp.sim.smp.skills`) and open to
#: `RobotSpec.finger_open` from the centre line
MAX_HALF_WIDTH = ROBOT.finger_open - 0.002
_DIFFUSE = re.compile(r"<diffuse>[^<]*</diffuse>")


@dataclass(frozen=True)
class ObjectModel:
    """One entry of ``models:`` (module docstring): the file and the numbers skills need."""

    sdf: str = spec(
        help="the SDFormat file: a path relative to the scenario file, or a "
        "package://tamp_models/... URL"
    )
    height: float = spec(
        min=2 * PAD_REACH,
        max=0.4,
        unit="m",
        help="floor to top; the model's origin is at its centre (as the packaged models)",
    )
    radius: float = spec(
        min=0.01, max=0.3, unit="m", help="footprint radius: overlap checks and base paths"
    )
    half_width: float | None = spec(
        None,
        min=0.005,
        max=MAX_HALF_WIDTH,
        unit="m",
        help="half the width the fingers close on (default: radius)",
    )
    grasp_height: float | None = spec(
        None,
        min=0.0,
        unit="m",
        help="where the fingers close, above the centre (default: as high as the finger "
        "pads allow, 4 cm below the top, as on the packaged models)",
    )
    body: str | None = spec(None, help="the link the gripper holds (default: the only link)")
    colour: tuple[float, ...] | None = spec(
        None,
        min=0.0,
        max=1.0,
        min_items=3,
        help="RGB or RGBA in [0, 1] for every visual of the model (default: the SDF's)",
    )

    def check(self, f: Fields) -> None:
        """Relations between the numbers: a grip within the fingers' reach and the
        footprint, a grasp point the pads can hold, a colour of 3 or 4 values."""
        grip = self.radius if self.half_width is None else self.half_width
        if self.half_width is None and grip > MAX_HALF_WIDTH:
            raise f.error(
                "half_width",
                f"missing: the radius {self.radius:g} m is wider than the fingers close on "
                f"(at most {MAX_HALF_WIDTH:g} m): give the half-width they grip",
            )
        if grip > self.radius:
            raise f.error("half_width", f"must be <= radius ({self.radius:g} m), got {grip:g}")
        top = self.height / 2 - PAD_REACH
        if self.grasp_height is not None and self.grasp_height > top + 1e-12:
            raise f.error(
                "grasp_height",
                f"must be <= {top:g} m (half the height less the {PAD_REACH:g} m the finger "
                f"pads reach above the grasp point), got {self.grasp_height:g}",
            )
        if self.colour is not None and len(self.colour) > 4:
            raise f.error("colour", f"expected [r, g, b] or [r, g, b, a], got {list(self.colour)}")

    def kind(self, name: str, f: Fields) -> ObjectKind:
        """The `ObjectKind` of this model, its file read (``f``: this entry, for errors)."""
        path = model_path(self.sdf, Path(f.file).parent, f)
        body, mass = _read_sdf(path, self.body, f)
        colour = None if self.colour is None else (tuple(self.colour) + (1.0,))[:4]
        return ObjectKind(
            name=name,
            body=body,
            half_height=self.height / 2,
            radius=self.radius,
            half_width=self.radius if self.half_width is None else self.half_width,
            grasp_height=(
                self.height / 2 - PAD_REACH if self.grasp_height is None else self.grasp_height
            ),
            mass=mass,
            path=path,
            colour=colour,
        )


def declared_kinds(models: dict[str, ObjectModel], f: Fields) -> dict[str, ObjectKind]:
    """The kinds of a scenario's ``models:`` (``f``: the scenario's top-level fields)."""
    if not models:
        return {}
    section = f.sub("models")
    return {name: model.kind(name, section.sub(name)) for name, model in models.items()}


def _read_sdf(path: Path, body: str | None, f: Fields) -> tuple[str, float]:
    """(the held link's name, its mass) of the one model in SDFormat file ``path``."""
    try:
        root = ElementTree.fromstring(_with_prefixes(path.read_text(encoding="utf-8")))
    except (ElementTree.ParseError, UnicodeDecodeError) as exc:
        raise f.error("sdf", f"not an SDFormat file: {exc}") from None
    models = root.findall("model") if root.tag == "sdf" else []
    if root.tag != "sdf" or len(models) != 1:
        raise f.error(
            "sdf", f"expected an <sdf> file with one <model>, found {len(models)} in {path.name}"
        )
    links = {link.get("name"): link for link in models[0].findall("link")}
    if body is None:
        if len(links) != 1:
            raise f.error(
                "body",
                f"missing: the model has {len(links)} links ({', '.join(map(str, links))}): "
                "name the one the gripper holds",
            )
        body = next(iter(links))
    elif body not in links:
        raise f.error("body", f"no link {body!r} in {path.name} (links: {', '.join(links)})")
    mass = links[body].findtext("inertial/mass")
    try:
        return str(body), 1.0 if mass is None else float(mass)  # SDFormat's default: 1 kg
    except ValueError:
        raise f.error("sdf", f"link {body!r}: mass {mass!r} is not a number") from None


def _with_prefixes(text: str) -> str:
    """``text`` with every XML prefix it uses declared on the root: SDFormat files write
    ``<drake:mu_static>`` without declaring ``drake`` (Drake's parser allows it; XML not)."""
    used = set(re.findall(r"</?([A-Za-z_][\w.-]*):", text))
    missing = sorted(used - set(re.findall(r"xmlns:([\w.-]+)\s*=", text)))
    if not missing:
        return text
    declared = " ".join(f'xmlns:{p}="urn:{p}"' for p in missing)
    return re.sub(r"<sdf\b", f"<sdf {declared}", text, count=1)


def object_sdf(kind: ObjectKind, uid: str, friction: float | None = None) -> str:
    """The SDF text of one object of ``kind`` named ``uid`` (module docstring)."""
    text = renamed_model(kind.sdf.read_text(encoding="utf-8"), uid)
    if friction is not None:  # the run's drawn coefficient
        text = with_friction(text, friction)
    if kind.colour is not None:
        rgba = " ".join(f"{c:.4f}" for c in kind.colour)
        text = _DIFFUSE.sub(f"<diffuse>{rgba}</diffuse>", text)
    return absolute_uris(text, kind.sdf.parent)
