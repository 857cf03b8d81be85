"""The optional parts of the install: which extra brings which library, and the one message a
user reads when a command needs an extra that is not installed.

The core (``pip install tamp-hrc``) is the symbolic system: demonstrations, the reachability
graph and its search, behavior trees, LOTS, refinement's pure steps and every verification
gate, so ``tamp plan``, ``tamp lots`` and ``tamp-verify`` run without Drake and torch.
Everything else is an extra (``pip install 'tamp-hrc[sim]'``); ``all`` is every one of them.
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass

from tamp.errors import EXIT_BAD_INPUT, TampError

#: The distribution's name on the package index (the import package is ``tamp``).
DISTRIBUTION = "tamp-hrc"


@dataclass(frozen=True)
class Extra:
    """An optional dependency group of ``pyproject.toml``: its name, the top-level modules it
    installs (the first one is the one checked for), and what it is for."""

    name: str
    modules: tuple[str, ...]
    library: str
    purpose: str

    @property
    def install(self) -> str:
        return f"pip install '{DISTRIBUTION}[{self.name}]'"


EXTRAS = (
    Extra("sim", ("pydrake",), "Drake", "the Drake workcells (tamp simulate, tamp refine)"),
    Extra(
        "grasp",
        ("torch", "PIL", "tifffile"),
        "torch",
        "grasp and detector networks (tamp grasp, tamp detect)",
    ),
    Extra("campaign", ("ray",), "Ray", "seeded campaigns in parallel (tamp campaign)"),
    Extra("serve", ("websockets",), "websockets", "the live MR link (tamp serve)"),
)

#: Extra name -> extra.
BY_NAME = {e.name: e for e in EXTRAS}
#: Top-level module name -> the extra that installs it (matplotlib and tqdm: also pulled in
#: by others, named here by the one every simulating command needs).
_BY_MODULE = {m: e for e in EXTRAS for m in e.modules}
_BY_MODULE.update({"matplotlib": BY_NAME["sim"], "tqdm": BY_NAME["sim"]})


class MissingExtra(TampError):
    """A command needs an optional dependency that is not installed (exit 2, naming the extra
    and the install command)."""

    exit_code = EXIT_BAD_INPUT

    def __init__(self, extra: Extra, module: str, what: str | None = None):
        self.extra = extra
        self.module = module
        need = f"{what} needs" if what else "this needs"
        library = extra.library if module == extra.modules[0] else module
        super().__init__(
            f"{need} {library} ({module!r} is not installed), which comes with the "
            f"{extra.name!r} extra, for {extra.purpose}: {extra.install}"
        )


def extra_of(module: str) -> Extra | None:
    """The extra that installs top-level module ``module`` (``pydrake.systems`` counts as
    ``pydrake``), or None when no extra does."""
    return _BY_MODULE.get(module.partition(".")[0])


def missing(name: str) -> bool:
    """Is extra ``name``'s main module absent from this environment? (No import happens.)"""
    return importlib.util.find_spec(BY_NAME[name].modules[0]) is None


def require(name: str, what: str | None = None) -> None:
    """Raise `MissingExtra` when extra ``name`` is not installed (``what``: the command or
    feature that needs it, for the message)."""
    extra = BY_NAME[name]
    for module in extra.modules:
        if importlib.util.find_spec(module) is None:
            raise MissingExtra(extra, module, what)


def from_import_error(exc: ModuleNotFoundError, what: str | None = None) -> MissingExtra | None:
    """The `MissingExtra` an import failure stands for, when an extra provides the module
    (the CLI turns every such failure into the extra's install line)."""
    name = exc.name or ""
    extra = extra_of(name)
    return None if extra is None else MissingExtra(extra, name.partition(".")[0], what)
