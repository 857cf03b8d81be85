"""`tamp simulate smp-mro --json` gives the recorded outputs (golden/*.json), timing aside.

The files were written by the simulation before the scenario files moved to the shared
event vocabulary (`tamp.world.events`) and the Drake code to ``tamp/sim/{core,smp}``: the
refactoring changed nothing a run does. Wall and CPU times (and their real-time factors)
are left out; everything else, sim times and final plant poses included, must match.

Changed on purpose once (nothing a run does changed, only how it is reported): a
``MoveTo`` the tree halted once its goal held is ``"status": "HALTED"`` with ``"detail":
"goal reached: IsRobotCloseTo(x)"`` (was ``CANCELLED``, ``""``), and every output has a
``warnings`` list (empty here: no appearance met an occupied place). ``ok`` now comes from
`SimResult.to_json` (``status == "SUCCESS"``), the same value as before.

Added later (nothing a run does changed; every other value was compared equal before
the files were rewritten): ``cause`` (None on success), ``task_time``, ``failures`` (the
lost grasp's ``injected_failure``), ``grasp`` (weld), ``perception`` (truth), ``seed`` (0)
and ``perturbation`` (nothing drawn: the packaged cases have no section; its
``detector`` key, null here, came with the noisy-detector perturbation). ``disturbed``
(objects left knocked over, on top of another or moved unpicked: none in these runs) came
with the judge reading every object, not only the goal objects.

Changed on purpose (2026-11-28, what runs do): every arm move starts the fingers'
reference where it was (a friction grasp's squeeze no longer vanishes at the start of each
move), and a base that starts inside an object's margin goes straight to its goal when
that move only backs away (no detour past the goal). Case 2 and Case 3 then end 0.1 and
0.2 s sooner with the same actions, verdicts and final positions (a bottle's yaw on its
place differs); Case 1 and the failed grasp are unchanged.

Every workcell's run document now starts with the common keys of
`tamp.sim.core.workcell.RunResult`: ``schema`` and ``workcell`` are new (checked, not
recorded); every other key and value is as recorded.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tamp.commands.main import main

pytestmark = pytest.mark.slow

GOLDEN = Path(__file__).resolve().parent / "golden"
TIMING = ("wall_time", "realtime_factor", "cpu_time", "cpu_realtime_factor")
RUNS = {
    "case1": ["--case", "1"],
    "case2": ["--case", "2"],
    "case3": ["--case", "3"],
    "case1_failed_grasp": ["case1_failed_grasp"],
}


@pytest.mark.parametrize("name", sorted(RUNS))
def test_simulated_output_is_unchanged(name, capsys):
    code = main(["simulate", "smp-mro", *RUNS[name], "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["ok"] is True and out["status"] == "SUCCESS"
    for key in TIMING:
        assert out.pop(key) > 0
    assert (out.pop("schema"), out.pop("workcell")) == (1, "smp-mro")  # the common keys' own
    expected = json.loads((GOLDEN / f"{name}.json").read_text())
    assert out == expected
