"""The shortened Task 4 the simulation tests run (about 17 s of sim time per run)."""

from __future__ import annotations

from tamp.refine.architecture import Architecture, load_architecture
from tamp.refine.loader import load_program
from tamp.refine.program import Program
from tamp.scenarios import path

SHORT = path("refine/task4_short.yaml")


def short() -> Program:
    return load_program(SHORT)


def fast_architecture() -> Architecture:
    """The packaged service times with 3 Hz steps and 1.5 s probes."""
    return load_architecture(path("refine/fast_probe_architecture.yaml"))
