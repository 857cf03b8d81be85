"""What a campaign can run: every registered workcell (`tamp.sim.core.workcell`).

A campaign's ``--kind`` is a workcell's name; its packaged scenario folder, the top-level
YAML key that tells its files apart, its options and its replay command are the workcell's
own declarations, and every run is the one generic `tamp.sim.core.workcell.run_seeded`.
Nothing here imports Drake or Ray.
"""

from __future__ import annotations

from pathlib import Path

from tamp import scenarios
from tamp.errors import InputError
from tamp.sim.core import workcell as registry
from tamp.sim.core.workcell import Workcell, register, unregister

__all__ = ["Workcell", "get_kind", "kinds", "register", "resolve_scenario", "unregister"]


def kinds() -> dict[str, Workcell]:
    """Every workcell a campaign can run, by name."""
    return registry.workcells()


def get_kind(name: str) -> Workcell:
    """The workcell ``name`` (`InputError` naming ``--kind`` otherwise)."""
    if name not in registry.names():
        known = ", ".join(registry.names())
        raise InputError(f"unknown kind {name!r} (known: {known})", field="--kind")
    return registry.get(name)


def resolve_scenario(scenario: str, kind: str | None) -> tuple[Workcell, Path]:
    """The workcell and the file of SCENARIO (a path, or a packaged name via the one resolver).

    Without ``kind``: a packaged name is looked up in every workcell's folder (``case3.yaml``
    is an SMP-MRO scenario, ``tower.yaml`` a LOTS task, ``task4`` a refinement program; a name
    found in two folders needs ``--kind``); a user file is recognised by its top-level key.
    """
    if kind is not None:
        k = get_kind(kind)
        path = scenarios.resolve(scenario, k.folder)
        if not path.is_file():
            raise InputError(f"no such file or packaged {k.name} scenario", field="SCENARIO")
        return k, path
    user = Path(scenario)
    if user.is_file():
        return _kind_of_file(user), user
    found = []
    for k in kinds().values():
        path = scenarios.resolve(scenario, k.folder)
        if path.is_file() and path.parent == scenarios.ROOT / k.folder:
            found.append((k, path))
    if not found:
        raise InputError(f"no such file or packaged scenario: {scenario!r}", field="SCENARIO")
    if len(found) > 1:
        names = ", ".join(k.name for k, _ in found)
        raise InputError(f"{scenario!r} is packaged for {names}: give --kind", field="--kind")
    return found[0]


def _kind_of_file(path: Path) -> Workcell:
    """The workcell of a user file, from the top-level key only its files have."""
    from tamp.fileio import load_yaml

    data, file = load_yaml(path, kind="campaign scenario")
    keys = set(data) if isinstance(data, dict) else set()
    cells = kinds().values()
    matches = [k for k in cells if k.key in keys]
    if len(matches) != 1:
        known = ", ".join(f"{k.key!r} ({k.name})" for k in cells)
        raise InputError(
            f"cannot tell the kind of this file (top-level keys: {known}): give --kind",
            file=file,
            field="--kind",
        )
    return matches[0]
