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


def _turn(cell: tuple[int, int], quarters: int) -> tuple[int, int]:
    i, j = cell
    for _ in range(quarters % 4):
        i, j = -j, i
    return i, j


@st.composite
def symmetric_demonstrations(draw, max_objects: int = 2, max_goals: int = 8):
    """A demonstration made of 2 or 4 copies of one pattern turned about the robot (at the
    origin): a task with rotational symmetry, each copy in its own sector of the grid."""
    copies = draw(st.sampled_from([2, 4]))
    quarter = 4 // copies  # quarter turns between copies
    if copies == 4:
        sector = [(i, j) for i in range(1, 4) for j in range(0, 4)]
    else:
        sector = [(i, j) for i in range(-3, 4) for j in range(0, 4) if j > 0 or i > 0]
    n_obj = draw(st.integers(1, max_objects))
    starts = draw(st.lists(st.sampled_from(sector), min_size=n_obj, max_size=n_obj, unique=True))
    where = {f"O{k}": c for k, c in enumerate(starts)}
    seed_steps = []
    for _ in range(draw(st.integers(1, max(1, max_goals // copies)))):
        obj = draw(st.sampled_from(sorted(where)))
        to = draw(st.sampled_from([c for c in sector if c not in where.values()]))
        where[obj] = to
        seed_steps.append((obj, to))
    objects, steps = {}, []
    for k in range(copies):
        for o, c in enumerate(starts):
            ci, cj = _turn(c, k * quarter)
            objects[f"O{o}_{k}"] = Point(ci * CELL, cj * CELL)
    for obj, to in seed_steps:  # each step, then its copies: the order turns with the task
        for k in range(copies):
            ti, tj = _turn(to, k * quarter)
            steps.append((f"{obj}_{k}", Point(ti * CELL, tj * CELL)))
    return make_demonstration(objects, steps, 0.15)
