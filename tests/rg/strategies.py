"""Hypothesis strategies for random *feasible* demonstrations (robot frame, grid places)."""

from __future__ import annotations

from hypothesis import strategies as st

from tamp.demo import make_demonstration
from tamp.world import Point

CELL = 0.5  # grid pitch; areas of radius 0.15 overlap only within one cell


@st.composite
def demonstrations(draw, max_objects: int = 4, max_steps: int = 7, min_steps: int = 1):
    """A demonstration a person could really perform: every step targets a free cell."""
    n_obj = draw(st.integers(1, max_objects))
    cells = [(i, j) for i in range(-3, 4) for j in range(-3, 4) if (i, j) != (0, 0)]
    starts = draw(st.lists(st.sampled_from(cells), min_size=n_obj, max_size=n_obj, unique=True))
    where = {f"O{k}": c for k, c in enumerate(starts)}
    objects = {o: Point(c[0] * CELL, c[1] * CELL) for o, c in where.items()}
    steps = []
    n_steps = draw(st.integers(min_steps, max_steps))
    for _ in range(n_steps):
        obj = draw(st.sampled_from(sorted(where)))
        free = [c for c in cells if c not in where.values()]
        to = draw(st.sampled_from(free))
        where[obj] = to
        steps.append((obj, Point(to[0] * CELL, to[1] * CELL)))
    return make_demonstration(objects, steps, 0.15)
