"""Property tests (hypothesis): random feasible demonstrations, obstacles in goal areas and
single skill failures always end with every goal reached, a bounded tree, and skills that
never overlap."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.bt import Appear, Fail
from tamp.bt.run import execute
from tamp.world import Area, IsObjectAt, ObjectState, Point, Pose, WorldState
from tamp.world.events import AtTick

RADIUS = 0.15
CELLS = [(0.6 + 0.8 * i, -2.0 + 0.8 * j) for i in range(6) for j in range(6)]


@st.composite
def scenarios(draw):
    n = draw(st.integers(1, 3))
    n_free = draw(st.integers(0, 2))
    cells = draw(st.permutations(range(len(CELLS))))
    starts = [CELLS[c] for c in cells[:n]]
    goals = [CELLS[c] for c in cells[n : 2 * n]]
    frees = [CELLS[c] for c in cells[2 * n : 2 * n + n_free]]
    objects = {f"O{k}": ObjectState(f"O{k}", Pose.at(x, y, 0.1)) for k, (x, y) in enumerate(starts)}
    areas = {f"L{k}": Area(f"L{k}", Point(x, y), RADIUS) for k, (x, y) in enumerate(goals)}
    areas.update(
        {
            f"free{k + 1}": Area(f"free{k + 1}", Point(x, y), RADIUS)
            for k, (x, y) in enumerate(frees)
        }
    )
    state = WorldState(robot=Pose.at(0.0, 0.0), objects=objects, areas=areas)
    order = draw(st.permutations(range(n)))
    c_goal = [IsObjectAt(f"O{k}", f"L{k}") for k in order]
    obstacles = []
    for j in range(draw(st.integers(0, 2))):
        k = draw(st.integers(0, n - 1))
        dx, dy = draw(st.tuples(st.floats(-0.1, 0.1), st.floats(-0.1, 0.1)))
        tick = draw(st.one_of(st.none(), st.integers(0, 40)))
        x, y = goals[k]
        obstacles.append(
            Appear(f"X{j}", Point(x + dx, y + dy, 0.1), None if tick is None else AtTick(tick))
        )
    failures = []
    if draw(st.booleans()):
        name = draw(st.sampled_from(["MoveTo", "Pick", "Place"]))
        failures.append(Fail(name, None, 1))
    skill_ticks = draw(st.integers(0, 3))
    return state, c_goal, [f"free{k + 1}" for k in range(n_free)], obstacles, failures, skill_ticks


@settings(max_examples=60, deadline=None)
@given(scenarios())
def test_random_demonstrations_reach_every_goal(case) -> None:
    state, c_goal, free, obstacles, failures, skill_ticks = case
    report = execute(
        state, c_goal, free_areas=free, events=obstacles, failures=failures,
        skill_ticks=skill_ticks,
    )  # fmt: skip
    assert report.reached, report.reason
    for c in c_goal:
        assert c.holds(report.final)
    assert report.final.held is None
    # bounded growth: a few dozen nodes per goal and per obstacle
    assert report.tree_size <= 1 + 40 * len(c_goal) + 60 * len(obstacles)
    assert report.stats["expansions"] <= 6 * len(c_goal) + 10 * len(obstacles)
    # no skill ever starts while another one runs
    assert report.world.violations == 0
    assert report.stats["implicit_preemptions"] == 0
    attempts = report.attempts
    for prev, nxt in zip(attempts, attempts[1:], strict=False):
        assert prev["ended"] is not None and nxt["started"] >= prev["ended"]


@st.composite
def demonstrations(draw):
    """Random demonstrations built with tamp.demo (objects may move twice, e.g. swaps)."""
    from tamp.demo.build import make_demonstration

    n = draw(st.integers(1, 3))
    cells = draw(st.permutations(range(len(CELLS))))
    starts = {f"O{k}": Point(*CELLS[cells[k]]) for k in range(n)}
    spare = [Point(*CELLS[c]) for c in cells[n : n + 4]]
    steps = []
    for k in range(n):
        steps.append((f"O{k}", spare[k]))
    for k in range(n):
        if draw(st.booleans()):  # second move: into another object's start place
            steps.append((f"O{k}", starts[f"O{(k + 1) % n}"]))
    frees = [Point(*CELLS[c]) for c in cells[n + 4 : n + 4 + draw(st.integers(0, 2))]]
    free_areas = [Area(f"free{i + 1}", p, RADIUS) for i, p in enumerate(frees)]
    demo = make_demonstration(starts, steps, RADIUS, free_areas=free_areas)
    return demo, draw(st.integers(0, 2)), draw(st.booleans())


@settings(max_examples=30, deadline=None)
@given(demonstrations())
def test_random_demonstrations_through_the_rg_layer(case) -> None:
    from tamp.bt.run import execute_plan
    from tamp.rg import plan

    demo, n_obstacles, fail = case
    result = plan(demo)
    last = {}
    for c in result.c_goal:
        last[c.obj] = c
    obstacles = [
        Appear(f"X{j}", Point(g.pos.x + 0.05, g.pos.y, 0.1), None)
        for j, g in enumerate(demo.goals[:n_obstacles])
    ]
    failures = [Fail("Pick", None, 1)] if fail else []
    report = execute_plan(demo, result.c_goal, events=obstacles, failures=failures)
    assert report.reached, report.reason
    assert report.goals_reached == len(result.c_goal)
    for c in last.values():
        assert c.holds(report.final)
    assert report.world.violations == 0
