"""A test-only workcell (no Drake): a deterministic function of the seed that succeeds, fails,
times out in sim, raises, kills its process or hangs, so the engines' handling of each can be
checked quickly. Registered by the tests (`tamp.sim.core.workcell.register`); a Ray worker
unpickles it by reference to this module."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

from tamp.errors import InputError
from tamp.perturbation import Applied
from tamp.sim.core.workcell import Option, RunResult

CRASH, HANG, DIE = 13, 15, 21


def outcome(seed: int) -> tuple[str, str | None]:
    """What seed ``seed`` does: every 4th fails, every 5th times out in sim, else success."""
    if seed % 4 == 3:
        return "FAILURE", "dropped O1"
    if seed % 5 == 4:
        return "TIMEOUT", "no result within 9 s of sim time"
    return "SUCCESS", None


@dataclass(kw_only=True)
class FakeResult(RunResult):
    note: str | None = None  # the cell's own option, echoed

    def details_json(self) -> dict:
        return {"note": self.note}


class FakeWorkcell:
    """The `Workcell` protocol, with a scripted outcome per seed."""

    name = "test-fake"
    title = "a scripted stand-in (tests)"
    folder = "sim"
    key = "test_fake"
    main = Option("scenario", "the scenario file")
    options = (Option("note", "echoed in the run's JSON", campaign=True),)
    replay = "fake {scenario} --seed {seed}"

    def load(self, name_or_path, note: str | None = None):
        """The driver-side validation: the scenario file must exist."""
        if not Path(name_or_path).is_file():
            raise InputError("no such file", file=str(name_or_path))
        return (str(name_or_path), note)

    def perturbed(self, scenario, seed: int):
        return scenario, Applied(seed=seed)

    def build(self, scenario, **options):
        raise NotImplementedError("the scripted stand-in has no diagram")

    def run(self, scenario, *, seed=0, record=None, max_sim_time=None, verify=True):
        """Deterministic per seed; raises at `CRASH`, dies at `DIE`, hangs at `HANG`."""
        if seed == CRASH:
            raise RuntimeError(f"boom at seed {seed}")
        if seed == DIE:
            os._exit(3)  # a worker death (only ever run in a Ray worker)
        if seed == HANG:
            time.sleep(3600)
        status, cause = outcome(seed)
        if record:
            Path(record).write_text(f"<html>seed {seed}</html>")
        path, note = scenario
        return FakeResult(
            workcell=self.name,
            scenario=path,
            status=status,
            cause=cause,
            reason=cause or "done",
            task_time=30.0 + 0.5 * seed,
            sim_time=30.0 + 0.5 * seed,
            seed=seed,
            perturbation={"size": 0.01 * seed},
            note=note,
        )


FAKE = FakeWorkcell()
