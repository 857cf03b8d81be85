"""Packaged scenario files: the papers' cases, used by the CLI, notebooks and tests."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent


def path(name: str) -> Path:
    """Absolute path of a packaged scenario file, e.g. ``path("case2.yaml")``."""
    p = ROOT / name
    if not p.exists():
        raise FileNotFoundError(f"no packaged scenario {name!r} under {ROOT}")
    return p


def resolve(name_or_path: str | Path, folder: str = "") -> Path:
    """A user path if it exists, else the packaged scenario of that name (under ``folder``,
    ``.yaml`` optional); the given path when neither exists (the loader reports it)."""
    p = Path(name_or_path)
    if p.exists():
        return p
    base = ROOT / folder if folder else ROOT
    for packaged in (base / str(name_or_path), base / f"{name_or_path}.yaml"):
        if packaged.exists():
            return packaged
    return p
