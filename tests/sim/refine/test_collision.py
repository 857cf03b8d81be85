"""Step 2's safety check with a real collision in the plant: a parallelized program that
makes a robot hit the table is executed once, the collision is read from SceneGraph's
contacts, the parallelization is reverted, and the output says so."""

from __future__ import annotations

import json

import pytest

from tamp.commands.main import main as tamp_main
from tamp.refine.architecture import load_architecture
from tamp.refine.loader import load_program
from tamp.refine.steps import parallelize
from tamp.scenarios import path
from tamp.sim.refine.simulate import simulate

PROGRAM = "table_collision"


def _arch():
    return load_architecture(path("refine/fast_probe_architecture.yaml"))


@pytest.mark.slow  # two short Drake runs
def test_the_parallelized_program_collides_and_the_original_does_not():
    program = load_program(PROGRAM)
    original = simulate(program, _arch())
    assert original.finished and original.collisions == {}
    parallel, done = parallelize(program, original.timeline.durations())
    assert [p.describe() for p in done] == ["R2: raise_arm runs in parallel with approach"]
    run = simulate(parallel, _arch(), max_sim_time=6.0)
    hits = {k: t for k, t in run.collisions.items() if k[1] == "table.table"}
    assert hits, run.collisions
    (robot_body, _), t = min(hits.items(), key=lambda kv: kv[1])
    assert robot_body.startswith("R2.")  # R2's gripper or lever met the table's edge
    assert 0.0 < t < 4.0  # before the arm was up (the raise takes 6.5 s)


@pytest.mark.slow  # every phase of the short program simulated
def test_refine_reverts_it_and_says_so(capsys):
    assert tamp_main(["refine", PROGRAM, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["parallelized"] == [] or "R2" not in " ".join(doc["parallelized"])
    ((revert,),) = [doc["reverted"]]
    assert revert["parallelization"] == "R2: raise_arm runs in parallel with approach"
    assert any(other == "table.table" and 0 < t < 4.0 for _, other, t in revert["collisions"])
    assert [p["name"] for p in doc["phases"]] == [
        "original",
        "parallelized",
        "speed-adjusted",
        "rate-refined",
    ]
    # the program ran again without it: the reverted phase is the original's, sequential
    r2 = [b for b in doc["phases"][1]["timeline"] if b["event"].startswith("R2.")]
    raise_arm, approach = sorted(r2, key=lambda b: b["start"])
    assert approach["start"] >= raise_arm["end"]
    assert all(p["collisions"] == [] for p in doc["phases"])
