"""Running a workcell's diagram in chunks, with work done *between* simulator steps.

Some state of a Drake diagram can only be changed from outside the simulator: a weld
constraint's active flag lives in the plant's context and is no system's output, and a
person putting an object down is not part of any system. A workcell's runner therefore
advances the simulator one chunk (its controller period) at a time with
`Simulator.AdvanceTo` and does that work between chunks (`run_in_chunks`). What is done
between chunks is the workcell's (weld toggling, appearances: `tamp.sim.smp.runner`).
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from dataclasses import dataclass

from pydrake.systems.analysis import ApplySimulatorConfig, Simulator, SimulatorConfig
from tqdm import tqdm


def make_simulator(diagram, *, realtime_rate: float = 0.0) -> Simulator:
    """A simulator of ``diagram``; ``realtime_rate`` 0 runs as fast as possible, 1.0 paces a
    live Meshcat view. Publishing happens on the visualizer's own period only."""
    simulator = Simulator(diagram)
    ApplySimulatorConfig(
        SimulatorConfig(target_realtime_rate=realtime_rate, publish_every_time_step=False),
        simulator,
    )
    return simulator


#: what Drake says when the physics has gone non-finite or the contact solver gave up
_DIVERGED = re.compile(r"non-finite|\bNaN\b|failed to converge|did not converge")


@dataclass(frozen=True)
class ChunkedRun:
    """Where a chunked run stopped (sim time, s) and what it cost (wall and process CPU, s);
    ``diverged``: why the physics stopped the run early (None: it did not)."""

    sim_time: float
    wall_time: float
    cpu_time: float
    stopped: bool  # True: ``between`` asked to stop or the physics diverged; False: time limit
    diverged: str | None = None


def run_in_chunks(
    simulator: Simulator,
    *,
    chunk: float,
    limit: float,
    between: Callable[[float], bool],
) -> ChunkedRun:
    """Initialize, then advance to ``chunk``, ``2 chunk``, ... (at most ``limit``), calling
    ``between(t)`` after each step; stop early when it returns True.

    Chunk ends are computed as ``chunk * n`` (not summed), so they are the same sim times
    in every run. When the plant's state goes non-finite (Drake raises from `AdvanceTo`), the
    run stops there with ``diverged`` saying when and what Drake said: a failure of the run
    (cause ``sim_diverged``), not of the program. Any other error propagates.
    """
    simulator.Initialize()
    wall0 = time.perf_counter()
    cpu0 = time.process_time()
    t = simulator.get_context().get_time()
    stopped, diverged = False, None
    n = 0
    # progress in sim seconds on stderr (tqdm turns itself off when stderr is no TTY)
    bar = tqdm(total=round(limit, 1), desc="simulating", unit=" sim s", disable=None, leave=False)
    while t < limit - 1e-9:
        n += 1
        t = min(chunk * n, limit)
        try:
            simulator.AdvanceTo(t)
        except RuntimeError as e:
            if not _DIVERGED.search(str(e)):
                raise
            t = simulator.get_context().get_time()
            said = re.split(r"\.\s", str(e), maxsplit=1)[0]  # Drake's first sentence
            diverged = f"the simulation diverged at {t:.2f} s ({said})"
            stopped = True
            break
        bar.update(round(t - bar.n, 1))
        if between(t):
            stopped = True
            break
    bar.close()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    return ChunkedRun(t, wall, cpu, stopped, diverged)
