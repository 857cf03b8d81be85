"""Where a workcell run's time goes: wall and process-CPU seconds of named parts.

A workcell's Python parts (camera renders, perception, a grasp network, the skills'
differential IK) each keep a `Stopwatch`; what the whole run cost minus those parts is the
plant's step (contact, SAP) and the framework (`breakdown`; which parts a cell has is the
cell's to say, e.g. `tamp.sim.lots.station.cell_parts`). Stopwatches are measurements, never
simulation state: they live on the systems, not in the Context, and a run's results do
not depend on them. Process CPU time counts every thread of the process (the renderer's and
torch's too), so on a machine shared with other jobs it measures what the run itself costs,
while wall time also counts the waits for a core.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass
class Stopwatch:
    """Accumulated wall and CPU seconds over the ``with`` blocks it timed, and their count."""

    wall: float = 0.0
    cpu: float = 0.0
    calls: int = 0
    _start: tuple[float, float] | None = field(default=None, repr=False)

    def __enter__(self) -> Stopwatch:
        self._start = (time.perf_counter(), time.process_time())
        return self

    def __exit__(self, *exc) -> None:
        w0, c0 = self._start
        self.wall += time.perf_counter() - w0
        self.cpu += time.process_time() - c0
        self.calls += 1
        self._start = None

    def reset(self) -> None:
        self.wall = self.cpu = 0.0
        self.calls = 0

    def as_dict(self) -> dict[str, float | int]:
        return {"wall": round(self.wall, 4), "cpu": round(self.cpu, 4), "calls": self.calls}


def breakdown(total_wall: float, total_cpu: float, parts: dict[str, Stopwatch]) -> dict:
    """``parts`` plus ``physics`` (the rest: plant step, contact, framework), each with its
    share of the total wall and CPU time. ``parts`` must not overlap."""
    out = {name: sw.as_dict() for name, sw in parts.items()}
    out["physics"] = {
        "wall": round(max(total_wall - sum(sw.wall for sw in parts.values()), 0.0), 4),
        "cpu": round(max(total_cpu - sum(sw.cpu for sw in parts.values()), 0.0), 4),
        "calls": 0,
    }
    for row in out.values():
        row["wall_share"] = round(row["wall"] / total_wall, 3) if total_wall > 0 else 0.0
        row["cpu_share"] = round(row["cpu"] / total_cpu, 3) if total_cpu > 0 else 0.0
    return out
