"""Helpers for the LOTS tests: packaged task and interference files by name."""

from __future__ import annotations

from tamp.lots.task import load_events
from tamp.scenarios import path


def scenario(name: str):
    return path(f"lots/{name}")


def events(name: str, task):
    return load_events(scenario(name), task)
