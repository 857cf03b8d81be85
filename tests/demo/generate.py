"""Generated demonstrations of any size, for the scale tests and `benchmarks/demo_scale.py`.

``multi``: n steps over max(1, n // 3) objects (or a given number) standing in a row (0.4 m
apart), each moved up its own column in turn (independent goal chains). ``one``: n steps of
one object along a grid of places 0.4 m apart (one chain). ``wide``: n objects in a row,
each moved once, 1 m straight ahead (n interleavable goals, every order allowed; many orders
cost the same).
Area radius 0.15 m, so no two areas overlap.
"""

from __future__ import annotations

from pathlib import Path

import yaml


def demo_document(n: int, kind: str = "multi", n_objects: int | None = None) -> dict:
    """The YAML document (user frame, robot 1 m behind the origin) of an n-step demo.

    ``n_objects``: for ``multi``, how many objects share the n steps (default n // 3): 4
    objects and 72 steps is the 72-goal demonstration of four chains of 18 steps.
    """
    objects, steps = [], []
    if kind == "one":
        objects = [{"id": "O0", "position": [0.0, 0.0, 0.0]}]
        for k in range(n):
            steps.append(
                {
                    "object": "O0",
                    "to": [round(0.5 + (k % 50) * 0.4, 3), 0, round(1 + (k // 50) * 0.4, 3)],
                }
            )
    elif kind == "multi":
        m = max(1, n // 3) if n_objects is None else max(1, min(n_objects, n))
        objects = [{"id": f"O{i}", "position": [round(i * 0.4, 3), 0, 0]} for i in range(m)]
        for k in range(n):
            i, r = k % m, k // m
            steps.append({"object": f"O{i}", "to": [round(i * 0.4, 3), 0, round(1 + r * 0.4, 3)]})
    elif kind == "wide":
        objects = [{"id": f"O{i}", "position": [round(i * 0.4, 3), 0, 0]} for i in range(n)]
        steps = [{"object": f"O{i}", "to": [round(i * 0.4, 3), 0, 1.0]} for i in range(n)]
    else:
        raise ValueError(f"unknown kind {kind!r} (multi, one, wide)")
    return {
        "version": 1,
        "frame": {"robot_position": [0, 0, -1]},
        "area_radius": 0.15,
        "objects": objects,
        "steps": steps,
    }


def write_demo(path: str | Path, n: int, kind: str = "multi", n_objects: int | None = None) -> Path:
    """Write the n-step demonstration of ``kind`` to ``path``."""
    p = Path(path)
    p.write_text(yaml.safe_dump(demo_document(n, kind, n_objects)))
    return p
