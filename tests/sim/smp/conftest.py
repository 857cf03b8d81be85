"""Runs each simulated case once per test session (they take seconds each)."""

from __future__ import annotations

import os

import pytest

os.environ["DRAKE_ALLOW_NETWORK"] = "meshcat"


class CaseRuns:
    """Cache of (result, prepared, system, runner, track) per scenario file."""

    def __init__(self) -> None:
        self._runs: dict[str, tuple] = {}

    def get(self, name: str):
        if name not in self._runs:
            from tamp.sim.smp.runner import SimRunner
            from tamp.sim.smp.scenario import load_scenario, scenario_path
            from tamp.sim.smp.simulate import prepare
            from tamp.sim.smp.station import build_station

            from .helpers import Track

            scenario = load_scenario(scenario_path(name))
            prepared = prepare(scenario)
            system = build_station(scenario, prepared.policy)
            runner = SimRunner(system)
            track = Track()

            def record(t: float) -> None:
                track.times.append(t)
                track.poses.append(runner.object_poses())

            result = runner.run(on_chunk=record)
            self._runs[name] = (result, prepared, system, runner, track)
        return self._runs[name]


@pytest.fixture(scope="session")
def case_runs() -> CaseRuns:
    return CaseRuns()
