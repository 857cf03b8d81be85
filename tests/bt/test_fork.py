"""`PaBtExecutor.fork` and `live_key`: what the verification explorer relies on.

A fork shares the finished goal subtrees and the untouched goal conditions with the executor
it came from. It must run exactly like a deep copy, and it must leave the lender as it was.
"""

from __future__ import annotations

import copy

import pytest

from tamp.bt import PaBtExecutor, SymbolicWorld
from tamp.demo import load_demonstration
from tamp.rg import plan
from tamp.world.events import Fail
from tamp.world.outcomes import ScriptedOutcomes
from tests.demo.generate import write_demo


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return load_demonstration(write_demo(tmp_path_factory.mktemp("d") / "d.yaml", 12, "multi", 4))


def _midway(demo, ticks: int) -> tuple[PaBtExecutor, SymbolicWorld]:
    c_goal = plan(demo).c_goal
    ex = PaBtExecutor(c_goal, demo.domain(), free_areas=list(demo.free_areas))
    world = SymbolicWorld(demo.initial_world())
    for _ in range(ticks):
        world.step()
        ex.tick(world)
    return ex, world


@pytest.mark.parametrize("ticks", [0, 7, 25])
def test_a_fork_runs_like_a_deep_copy_and_leaves_its_lender_alone(demo, ticks) -> None:
    ex, world = _midway(demo, ticks)
    before = ex.state_key()
    runs = []
    for twin in (ex.fork(), copy.deepcopy(ex)):
        w = copy.deepcopy(world)
        w.outcomes = ScriptedOutcomes([Fail("Pick", None, 1)])  # one retry on the way
        assert twin.run(w, step=w.step).value == "SUCCESS"
        runs.append(([str(a) for a in twin.executed], w.observe()))
    assert runs[0] == runs[1]
    assert ex.state_key() == before  # the lender's tree was not touched
    again, w = ex.fork(), copy.deepcopy(world)  # and it still forks and runs
    assert again.run(w, step=w.step).value == "SUCCESS"


def test_a_deep_copy_of_a_fork_is_a_whole_tree(demo) -> None:
    ex, world = _midway(demo, 25)
    fork = ex.fork()
    world.step()
    fork.tick(world)
    whole = copy.deepcopy(fork)
    for node in whole.root.walk():
        for child in node.children:
            assert child.parent is node
    assert whole.to_dot()  # exportable: every parent link is inside the copy


def test_live_keys_forget_finished_goals(demo) -> None:
    """Two runs that differ only in an earlier goal (one Pick failed there) have equal live
    keys once the root has passed that goal, and different whole-tree keys."""
    keys = []
    for failures in ([], [Fail("Pick", None, 1)]):
        c_goal = plan(demo).c_goal
        ex = PaBtExecutor(c_goal, demo.domain(), free_areas=list(demo.free_areas))
        world = SymbolicWorld(demo.initial_world(), outcomes=ScriptedOutcomes(failures))
        while ex.goals_done() < 3:
            world.step()
            ex.tick(world)
        keys.append((ex.live_key(), ex.state_key(), world.observe()))
    (live_a, whole_a, state_a), (live_b, whole_b, state_b) = keys
    assert state_a == state_b
    assert live_a == live_b
    assert whole_a != whole_b
