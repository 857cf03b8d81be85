"""Helpers for the LOTS tests: packaged task and interference files by name."""

from __future__ import annotations

from hypothesis import strategies as st

from tamp.lots.task import Proposition, Task, load_events
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


CLASSES = ("cup", "mug", "jar")


def random_tasks(shapes: tuple[str, ...]):
    """Hypothesis strategy: a formula shape over p0..p2, each of a random class and cost,
    0-2 objects of each class in W^A and 0-1 in W^B."""

    @st.composite
    def task(draw):
        shape = draw(st.sampled_from(shapes))
        props = tuple(
            Proposition(f"p{i}", draw(st.sampled_from(CLASSES)), draw(st.sampled_from((1.0, 2.0))))
            for i in range(3)
        )
        init_a = {c: draw(st.integers(0, 2)) for c in CLASSES}
        init_b = {c: draw(st.integers(0, 1)) for c in CLASSES}
        # ways that deliver one object twice need our return action (W^B back to W^A)
        return Task(shape.format("p0", "p1", "p2"), props, init_a, init_b, returns=True)

    return task()
