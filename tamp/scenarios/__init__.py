"""Packaged scenario files (the papers' cases), resolvable by name from any directory.

`resolve` is the one resolver of the project: every loader (`load_demonstration`,
`load_task`, `load_events`, `load_scenario`, refinement programs) calls it, so a packaged
name works the same in the CLI and the Python API. Layout: demonstrations at the top,
LOTS tasks and interference scripts in ``lots/``, Drake scenarios in ``sim/``.
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent


def path(name: str) -> Path:
    """Absolute path of a packaged scenario file, e.g. ``path("case2.yaml")``."""
    p = ROOT / name
    if not p.exists():
        raise FileNotFoundError(f"no packaged scenario {name!r} under {ROOT}")
    return p


def resolve(name_or_path: str | Path, kind: str | None = None) -> Path:
    """A user path if it exists, else the packaged file of that name.

    ``kind`` names the packaged folder to look in first (``"lots"``, ``"sim"``); the
    ``.yaml`` suffix may be left out. When nothing matches, the user's path comes back
    unchanged, so the loader's "file not found" error names what the user typed.
    """
    p = Path(name_or_path)
    if p.exists() or p.is_absolute():
        return p
    text = str(name_or_path)
    names = [text] if text.endswith((".yaml", ".yml")) else [text, f"{text}.yaml"]
    folders = ([ROOT / kind] if kind else []) + [ROOT]
    for folder in folders:
        for n in names:
            cand = folder / n
            if cand.is_file():
                return cand
    return p
