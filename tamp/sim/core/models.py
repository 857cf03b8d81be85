"""Where the project's model data lives: the SDF models and the network weights.

They are the ``tamp/models/`` folder, package data of ``tamp`` (``pyproject.toml``), found
with `importlib.resources`, so a wheel works from any directory. The SDFs resolve in Drake as
``package://tamp_models/sdf/...`` through ``tamp/models/package.xml``
(`tamp.sim.core.parsing.make_parser`); nothing is fetched. What each workcell knows about
its models (joints, gains, object sizes) lives in its own subpackage. No Drake import here,
so scenario validation and the grasp CLI run without Drake.
"""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

from tamp.errors import TampError
from tamp.fileio import MAX_BYTES, Fields

#: The Drake package name of the model folder (``package://tamp_models/...``, its package.xml).
PACKAGE = "tamp_models"


def models_dir() -> Path:
    """The ``tamp/models/`` folder (package data of ``tamp``), found with `importlib.resources`
    so that a wheel works from any directory."""
    root = resources.files("tamp.models")
    if not isinstance(root, Path) or not (root / "package.xml").is_file():
        raise TampError(
            "the model data (tamp/models: package.xml, sdf/, weights/) is not installed; "
            "reinstall tamp-hrc (pip install .)"
        )
    return root


def package_xml() -> Path:
    """``tamp/models/package.xml``, which makes the SDFs ``package://tamp_models/...``."""
    return models_dir() / "package.xml"


#: what reads a workcell camera's views: the renderer's label image as a perfect detector
#: (``oracle``: ground truth, for judging and comparing), or the learned detector on colour +
#: depth (``learned``: `tamp.sim.core.detector`, the camera's shipped weights)
DETECTORS = ("oracle", "learned")


def sdf_path(name: str) -> Path:
    """The file of model ``name`` (``tamp/models/sdf/<name>.sdf``), for text substitution."""
    return models_dir() / "sdf" / f"{name}.sdf"


def model_url(name: str) -> str:
    """``package://tamp_models/sdf/<name>.sdf``."""
    return f"package://{PACKAGE}/sdf/{name}.sdf"


def with_friction(sdf: str, mu: float) -> str:
    """A model's SDF text with every Coulomb coefficient (static and dynamic) set to ``mu``:
    how a run's drawn friction (`tamp.perturbation`) reaches the objects."""
    for tag in ("drake:mu_dynamic", "drake:mu_static"):
        sdf = re.sub(rf"<{tag}>[^<]*</{tag}>", f"<{tag}>{mu:.6f}</{tag}>", sdf)
    return sdf


_MODEL_NAME = re.compile(r"""<model(\s+)name\s*=\s*(["'])[^"']*\2""")
_URI = re.compile(r"<uri>\s*([^<]*?)\s*</uri>")


def model_path(ref: str, folder: Path, f: Fields, key: str = "sdf") -> Path:
    """The SDFormat file a scenario declares for a model of its own (``key: ref``): a
    ``package://tamp_models/`` URL or a path relative to ``folder`` (the scenario's);
    `InputError` at ``key`` when it is not such a file."""
    if "://" in ref:
        scheme, _, rest = ref.partition("://")
        package, _, inner = rest.partition("/")
        if scheme != "package":
            raise f.error(key, f"expected a path or a package:// URL, got {ref!r}")
        if package != PACKAGE:
            raise f.error(key, f"unknown package {package!r} (known: {PACKAGE})")
        path = models_dir() / inner
    else:
        path = folder / ref
    if not path.is_file():
        raise f.error(key, f"no model file {ref!r} (looked for {path})")
    if path.suffix.lower() != ".sdf":
        raise f.error(key, f"expected an SDFormat file (.sdf), got {ref!r}")
    if path.stat().st_size > MAX_BYTES:
        raise f.error(key, f"larger than {MAX_BYTES // (1024 * 1024)} MiB")
    return path.resolve()


def renamed_model(sdf: str, name: str) -> str:
    """A model's SDF text with its (first) model named ``name``: one model instance per
    object, each named by the object's id."""
    return _MODEL_NAME.sub(lambda m: f'<model{m.group(1)}name="{name}"', sdf, count=1)


def absolute_uris(sdf: str, folder: Path) -> str:
    """A model's SDF text with each relative ``<uri>`` (a mesh beside the file) made an
    absolute ``file://`` URI: the text is parsed from a string, without its folder."""

    def absolute(m: re.Match) -> str:
        uri = m.group(1)
        if "://" in uri or uri.startswith("/") or not uri:
            return m.group(0)
        return f"<uri>{(folder / uri).resolve().as_uri()}</uri>"

    return _URI.sub(absolute, sdf)
