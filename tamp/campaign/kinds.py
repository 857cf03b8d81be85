"""What a campaign can run: one `Kind` per workcell, each naming the function that runs ONE
seeded simulation and returns a JSON-able dict (the runner contract below).

Runners and checks are named as ``"module:function"`` strings and imported only where they
run (a Ray worker, or this process for the in-process engine), so importing this module
imports neither Drake nor Ray, and nothing Drake-made is ever pickled.

Runner contract: ``runner(scenario: str, seed: int, *, record: str | None,
max_sim_time: float | None, **options) -> dict`` (``options``: the kind's own, e.g. a LOTS
run's ``interference`` file) with at least ``status`` (``SUCCESS`` | ``FAILURE`` |
``TIMEOUT``, the simulation's verdict), ``cause`` (None on success, else why), ``task_time``
(sim s), ``seed`` and ``perturbation`` (its size, a number, or a mapping with ``size``).
A runner may raise `tamp.errors.TampError` for a run that cannot be planned (a failure with
that cause); any other exception is a crash of that run.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tamp import scenarios
from tamp.errors import InputError

Runner = Callable[..., dict[str, Any]]


@dataclass(frozen=True)
class Kind:
    """A workcell a campaign can run.

    ``folder``: its packaged scenario folder (`tamp.scenarios.resolve`); ``key``: the
    top-level YAML key that only its files have (how ``--kind`` is inferred from a user
    file); ``runner`` and ``check``: ``"module:function"`` of the one-run function and of
    the loader that validates the file (raises `InputError`) before anything starts;
    ``replay``: the command that reruns one seed (``{scenario}`` and ``{seed}`` filled in);
    ``options``: the runner's (and the check's) extra keyword options, each a CLI flag of the
    same name (``interference`` -> ``--interference``; LOTS's ``scenario`` -> ``--scenario``,
    its workcell file, as in ``tamp simulate lots``), passed on as strings.
    """

    name: str
    folder: str
    key: str
    runner: str
    check: str
    replay: str
    options: tuple[str, ...] = ()


KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        Kind(
            "smp-mro",
            folder="sim",
            key="demonstration",
            runner="tamp.sim.smp.simulate:run_seeded",
            check="tamp.campaign.checks:check_smp_mro",
            replay="tamp simulate smp-mro --scenario {scenario} --seed {seed}",
        ),
        Kind(
            "lots",
            folder="lots",
            key="formula",
            runner="tamp.sim.lots.simulate:run_seeded",
            check="tamp.campaign.checks:check_lots",
            replay="tamp simulate lots --task {scenario} --seed {seed}",
            options=("interference", "scenario"),
        ),
        Kind(
            "refine",
            folder="refine",
            key="robots",
            runner="tamp.sim.refine.seeded:run_seeded",
            check="tamp.campaign.checks:check_refine",
            replay="tamp refine {scenario} --seed {seed}",
        ),
    )
}

#: The kinds ``--kind`` offers (test-only kinds added by `register` are not listed).
PUBLIC_KINDS = tuple(KINDS)


def register(kind: Kind) -> None:
    """Add (or replace) a kind, e.g. a test-only runner that crashes or hangs on purpose."""
    KINDS[kind.name] = kind


def get_kind(name: str) -> Kind:
    """The registered kind ``name`` (`InputError` naming ``--kind`` otherwise)."""
    if name not in KINDS:
        raise InputError(f"unknown kind {name!r} (known: {', '.join(KINDS)})", field="--kind")
    return KINDS[name]


def import_target(target: str) -> Callable[..., Any]:
    """The function named by ``"module:function"``."""
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def resolve_scenario(scenario: str, kind: str | None) -> tuple[Kind, Path]:
    """The kind and the file of SCENARIO (a path, or a packaged name via the one resolver).

    Without ``kind``: a packaged name is looked up in every kind's folder (``case3.yaml`` is
    an SMP-MRO scenario, ``tower.yaml`` a LOTS task, ``task4`` a refinement program; a name
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
    for k in KINDS.values():
        path = scenarios.resolve(scenario, k.folder)
        if path.is_file() and path.parent == scenarios.ROOT / k.folder:
            found.append((k, path))
    if not found:
        raise InputError(f"no such file or packaged scenario: {scenario!r}", field="SCENARIO")
    if len(found) > 1:
        names = ", ".join(k.name for k, _ in found)
        raise InputError(f"{scenario!r} is packaged for {names}: give --kind", field="--kind")
    return found[0]


def _kind_of_file(path: Path) -> Kind:
    """The kind of a user file, from the top-level key only its kind's files have."""
    from tamp.fileio import load_yaml

    data, file = load_yaml(path, kind="campaign scenario")
    keys = set(data) if isinstance(data, dict) else set()
    matches = [k for k in KINDS.values() if k.key in keys]
    if len(matches) != 1:
        known = ", ".join(f"{k.key!r} ({k.name})" for k in KINDS.values())
        raise InputError(
            f"cannot tell the kind of this file (top-level keys: {known}): give --kind",
            file=file,
            field="--kind",
        )
    return matches[0]
