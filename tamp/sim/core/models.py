"""Where the project's model data lives: the SDF models and the network weights.

They are the top-level ``models/`` folder, installed as the data package ``tamp_models``
(``pyproject.toml``) and found with `importlib.resources`, so a wheel works from any
directory. The SDFs resolve in Drake as ``package://tamp_models/sdf/...`` through
``models/package.xml`` (`tamp.sim.core.parsing.make_parser`); nothing is fetched. What each
workcell knows about its models (joints, gains, object sizes) lives in its own subpackage.
No Drake import here, so scenario validation and the grasp CLI run without Drake.
"""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import tamp
from tamp.errors import TampError

PACKAGE = "tamp_models"


def models_dir() -> Path:
    """The ``models/`` folder: the installed ``tamp_models`` package.

    A source checkout that was never installed (only ``PYTHONPATH`` set) has no
    ``tamp_models`` to import; then the folder beside the ``tamp`` package is used.
    """
    try:
        root = resources.files(PACKAGE)
    except ModuleNotFoundError:
        root = Path(tamp.__file__).resolve().parent.parent / "models"
    if not isinstance(root, Path) or not (root / "package.xml").is_file():
        raise TampError(
            f"the model data ({PACKAGE}: models/package.xml, models/sdf, models/weights) is "
            "not installed; reinstall tamp (pip install .)"
        )
    return root


def package_xml() -> Path:
    """``models/package.xml``, which makes the SDFs ``package://tamp_models/...``."""
    return models_dir() / "package.xml"


def sdf_path(name: str) -> Path:
    """The file of model ``name`` (``models/sdf/<name>.sdf``), for text substitution."""
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
