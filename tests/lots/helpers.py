"""Helpers for the LOTS tests: packaged task and interference files by name."""

from __future__ import annotations

from tamp.lots.task import load_events
from tamp.scenarios import path


def scenario(name: str):
    return path(f"lots/{name}")


def events(name: str, task):
    return load_events(scenario(name), task)


#: A task with two ways (the cheaper cup, or the mug): ``formula`` and ``name`` are fields.
TWO_CLASSES = """version: 1
name: {name}
formula: "{formula}"
propositions:
  p: {{class: cup}}
  q: {{class: mug, cost: 2.0}}
initial:
  A: {{cup: 1, mug: 1}}
"""


def take_away(cls: str, side: str = "A") -> str:
    """An interference file: a person removes one ``cls`` from ``side`` before action 1."""
    return f"version: 1\nevents:\n  - {{after: 0, kind: remove, class: {cls}, side: {side}}}\n"


def write_files(tmp_path, **texts):
    """Write ``name=text`` pairs to ``tmp_path/name.yaml``; returns the paths by name."""
    out = {}
    for name, text in texts.items():
        out[name] = tmp_path / f"{name}.yaml"
        out[name].write_text(text)
    return out
