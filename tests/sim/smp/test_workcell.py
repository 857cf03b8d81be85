"""The SMP-MRO cell keeps the `Workcell` contract: its declarations, ``load`` (a file, a
packaged case, the ``--appear`` / ``--fail`` flags), run options checked before any work,
and a `SimResult` that is a `RunResult` (common keys once, the cell's report lines). That
importing it imports no Drake is checked for every workcell in ``tests/sim/core``."""

from __future__ import annotations

import json

import pytest

from tamp.errors import InputError
from tamp.sim.core.workcell import RunResult, Workcell, get, split_options
from tamp.sim.smp import WORKCELL
from tamp.world.events import Appear, AtTime, Fail

from .helpers import write_one_bottle


def test_the_cell_declares_the_contract():
    assert get("smp-mro") is WORKCELL and isinstance(WORKCELL, Workcell)
    assert (WORKCELL.folder, WORKCELL.key) == ("sim", "demonstration")
    assert WORKCELL.main.spelling == "scenario" and WORKCELL.main.folder == "sim"
    stages = {o.dest: o.stage for o in WORKCELL.options}
    assert stages == {
        "case": "load",
        "appear": "load",
        "fail": "load",
        "detector": "load",
        "verify_budget": "run",
        "rate": "run",
    }
    assert WORKCELL.replay.format(scenario="case3", seed=4) == (
        "tamp simulate smp-mro case3 --seed 4"
    )
    load, run = split_options(WORKCELL, {"case": 2, "rate": 0.5})
    assert load == {"case": 2} and run == {"rate": 0.5}


def test_load_takes_a_file_or_a_packaged_case():
    assert WORKCELL.load(None).name == "case1"  # the default case
    assert WORKCELL.load(None, case=3).name == "case3"
    assert WORKCELL.load("case2", case=3).name == "case2"  # SCENARIO wins over --case


def test_load_applies_the_flags(tmp_path):
    path = write_one_bottle(tmp_path, "fail: ['Pick(O0)']\n")
    s = WORKCELL.load(str(path), appear=["Y@L0@t=2"], fail=["Pick(O0)x2"])
    assert s.object("Y").appear == Appear("Y", "L0", AtTime(2.0))
    assert s.failures == (Fail("Pick", ("O0",), 2),)


@pytest.mark.parametrize(
    ("flags", "field", "words"),
    [
        ({"appear": ["Y@L9"]}, "--appear", "unknown area"),
        ({"appear": ["Y"]}, "--appear", "OBJ@PLACE"),
        ({"fail": ["Fly(O0)"]}, "--fail", "unknown action"),
        ({"fail": ["Place(O0, L0)"]}, "--fail", "only Pick"),
    ],
)
def test_bad_flags_name_the_flag(tmp_path, flags, field, words):
    with pytest.raises(InputError) as info:
        WORKCELL.load(str(write_one_bottle(tmp_path)), **flags)
    assert info.value.field == field and words in info.value.reason


@pytest.mark.parametrize("rate", [-1.0, float("nan")])
def test_a_bad_rate_is_refused_before_any_work(tmp_path, rate):
    s = WORKCELL.load(str(write_one_bottle(tmp_path)))
    with pytest.raises(InputError) as info:
        WORKCELL.run(s, rate=rate)
    assert info.value.field == "--rate"


def test_the_result_is_a_run_result_with_its_own_keys_and_lines():
    from tamp.sim.smp.runner import ObjectPose, SimResult

    r = SimResult(
        scenario="one_bottle",
        status="FAILURE",
        reason="tree failed",
        cause="grasp_slipped",
        sim_time=12.0,
        task_time=12.0,
        wall_time=2.0,
        cpu_time=1.5,
        final_poses={"O0": ObjectPose(1.0, 0.5, 0.1, 0.0)},
        goals={"O0@L0": False},
        failures=[(3.0, "Pick(O0)", "grasp_slipped", "dropped")],
        grasp="friction",
        perception="truth",
        order=["G0"],
        verified={"order": True, "tree": True},
    )
    assert isinstance(r, RunResult) and r.workcell == "smp-mro" and not r.ok
    data = r.to_json()  # raises on a key defined twice
    json.dumps(data)
    assert data["order"] == ["G0"] and data["verified"] == {"order": True, "tree": True}
    assert data["realtime_factor"] == 6.0 and data["cpu_realtime_factor"] == 8.0
    assert data["ok"] is False and data["cause"] == "grasp_slipped"
    lines = r.report_lines()
    assert lines[0] == "scenario one_bottle: order G0  (verified: order, tree)"
    assert "  O0@L0: NOT inside" in lines
    assert "skill failure: t=3.00 s Pick(O0): grasp_slipped (dropped)" in lines
    assert lines[-2] == "cause: grasp_slipped" and lines[-1].startswith("FAILURE: tree failed;")
