"""Test-only runners (no Drake): a deterministic function of the seed that succeeds, fails,
times out in sim, raises, kills its process or hangs, so the engines' handling of each can be
checked quickly. Registered as kinds by the tests (`tamp.campaign.kinds.register`)."""

from __future__ import annotations

import os
import time
from pathlib import Path

from tamp.campaign.kinds import Kind

CRASH, HANG, DIE = 13, 15, 21


def check(scenario: str, note: str | None = None) -> None:
    """The driver-side validation: the scenario file must exist."""
    from tamp.errors import InputError

    if not Path(scenario).is_file():
        raise InputError("no such file", file=scenario)


def outcome(seed: int) -> tuple[str, str | None]:
    """What seed ``seed`` does: every 4th fails, every 5th times out in sim, else success."""
    if seed % 4 == 3:
        return "FAILURE", "dropped O1"
    if seed % 5 == 4:
        return "TIMEOUT", "no result within 9 s of sim time"
    return "SUCCESS", None


def run(scenario: str, seed: int, *, record=None, max_sim_time=None, note=None) -> dict:
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
    return {
        "status": status,
        "cause": cause,
        "task_time": 30.0 + 0.5 * seed,
        "seed": seed,
        "perturbation": {"size": 0.01 * seed},
        "note": note,  # the kind's own option, echoed
    }


FAKE = Kind(
    "test-fake",
    folder="sim",
    key="test_fake",
    runner="tests.campaign.faulty:run",
    check="tests.campaign.faulty:check",
    replay="fake {scenario} --seed {seed}",
    options=("note",),
)
