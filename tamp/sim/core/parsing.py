"""A Drake `Parser` that knows only our models (``package://tamp_models``).

Drake's default package map registers the remote package ``drake_models``; with
``DRAKE_ALLOW_NETWORK=meshcat`` (tests, CLI) that registration itself throws, because the
download cache is empty and fetching is forbidden. We register it with the package-map
permission for the duration of the constructor only, then *remove* ``drake_models`` from
the map: a model that refers to it fails at once with "unknown package", and nothing can
ever be downloaded.
"""

from __future__ import annotations

import os

from pydrake.multibody.parsing import Parser

from tamp.sim.core.models import package_xml


def make_parser(plant) -> Parser:
    """``Parser(plant)`` with ``package://tamp_models`` registered and no remote packages."""
    key = "DRAKE_ALLOW_NETWORK"
    saved = os.environ.get(key)
    if saved is not None and "package_map" not in saved.split(":"):
        os.environ[key] = f"{saved}:package_map" if saved and saved != "none" else "package_map"
    try:
        parser = Parser(plant)
    finally:
        if saved is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = saved
    pm = parser.package_map()
    if pm.Contains("drake_models"):
        pm.Remove("drake_models")
    pm.AddPackageXml(str(package_xml()))
    return parser
