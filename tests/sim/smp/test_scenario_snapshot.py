"""The typed scenario loader reads every packaged SMP-MRO scenario as the loader it replaced
did: the same values, field by field (``data/packaged_scenarios.json``, `snapshot`)."""

from __future__ import annotations

import json

import pytest

from tamp.sim.smp.scenario import load_scenario

from .snapshot import SNAPSHOT, normalise, packaged_files, recorded_layout

RECORDED = json.loads(SNAPSHOT.read_text())


def test_the_snapshot_holds_every_packaged_file():
    assert sorted(RECORDED) == [p.name for p in packaged_files()]


@pytest.mark.parametrize("path", packaged_files(), ids=lambda p: p.name)
def test_the_loader_reads_what_was_recorded(path):
    assert recorded_layout(normalise(load_scenario(path))) == RECORDED[path.name]
