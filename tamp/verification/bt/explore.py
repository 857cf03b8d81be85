"""Every execution of a grown behavior tree, as an explicit transition system.

SMP-MRO grows its tree at run time (§IV-C, Alg. 2-3), so what must be verified is the
*executor* (`tamp.bt.PaBtExecutor`: tree + growth rules), not one static tree. The
exploration runs copies of the real executor, tick by tick, against the one
`tamp.world.SymbolicWorld` configured for it: every skill takes one tick and then either
succeeds (effects applied, §IV-C1 ``a.eef``) or fails (state unchanged), as chosen by a
`BranchingOutcomes` source. Each tick is replayed from the executor's snapshot
and a copy of the world once per combination of skill outcomes, so the graph holds every
execution the executor can produce. A state is keyed by (executor key,
`SymbolicWorld.fingerprint`, label); equal keys are merged, which makes the graph finite and
the count meaningful.

Two ways, same verdicts (a property test compares them):
- ``reduce=True`` (default, what the gate runs): the executor key is
  `PaBtExecutor.live_key` and each tick continues from `ExecutorSnapshot.fork`. A tree
  grown from per-goal subtrees is then explored goal by goal: once the root's memory
  passes a goal, that goal's subtree can never act again, so executions that differ only
  there (where an earlier skill failed, which ids the growth gave to its nodes) merge at
  the goal boundary, and a copy costs the live subtree, not the grown tree. The states
  grow linearly with the goals (per goal: its executions for each remaining failure
  budget) instead of quadratically, and a state costs about the same at goal 300 as at
  goal 10.
  Why the merge is exact, not an approximation, is written down in docs/verification.md
  ("Why the reduced exploration is exact").
- ``reduce=False``: the key is the whole tree (`PaBtExecutor.state_key`) and each tick
  continues from a full copy (`ExecutorSnapshot.resume`): the explicit exploration, kept as
  the reference the reduced one is tested against.

Choices written down here:
- Failures are bounded: at most ``max_failures`` skill failures per execution (default 1),
  of the skills matching ``failures`` (`tamp.world.events.Fail` entries; None: every
  skill). With unbounded failures no controller reaches its goal on every path (a skill
  can fail forever); the executor's own retry limit still applies inside that budget.
- Interference is `tamp.world.events.Appear` events. An object discovered on reach is seen
  at the tick after the robot arrives (``discover_on_arrival=False``; `tamp plan
  --execute` sees it in the arrival tick).
- The exploration is bounded by ``max_states``; when the bound is hit the states left
  unexpanded are recorded (`TransitionSystem.unexpanded`): a path that stops there is a
  counterexample only when it is already a bad prefix (see `tamp.verification.kripke`), never
  merely because the exploration stopped.
- A long exploration says so: every `PROGRESS_SECONDS` a line on the ``tamp`` logger
  (stderr in the CLIs) with the states explored, the frontier and the bound.
"""

from __future__ import annotations

import copy
import logging
import time
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from tamp.bt.executor import ExecutorSnapshot, PaBtExecutor
from tamp.verification.bt.labels import Labeller
from tamp.verification.kripke import TransitionSystem
from tamp.world.events import Appear, Fail
from tamp.world.interface import Status
from tamp.world.outcomes import BranchingOutcomes
from tamp.world.state import WorldState
from tamp.world.symbolic import SymbolicWorld

#: seconds between two progress lines of a long exploration
PROGRESS_SECONDS = 2.0

log = logging.getLogger("tamp")


#: the default bound on explored states (the gate's budget, ``--verify-budget``)
DEFAULT_MAX_STATES = 200_000


@dataclass
class Exploration:
    """The explored system, whether it is complete, terminal states and ticks replayed."""

    system: TransitionSystem
    complete: bool
    terminal: int
    ticks: int


def branching_world(
    state: WorldState,
    *,
    events: Iterable[Appear] = (),
    failures: Iterable[Fail] | None = None,
    max_failures: int = 1,
) -> SymbolicWorld:
    """The `SymbolicWorld` the exploration starts from (one tick per skill, branching)."""
    return SymbolicWorld(
        state,
        skill_ticks=1,
        outcomes=BranchingOutcomes(failures, max_failures),
        events=events,
        discover_on_arrival=False,
    )


def explore(
    executor: PaBtExecutor,
    state: WorldState,
    aps: Sequence[str],
    *,
    events: Iterable[Appear] = (),
    failures: Iterable[Fail] | None = None,
    max_failures: int = 1,
    max_states: int = DEFAULT_MAX_STATES,
    reduce: bool = True,
) -> Exploration:
    """Breadth-first over every execution of ``executor`` from ``state`` (module doc).

    ``executor`` itself is never ticked; states are labelled with the propositions ``aps``
    (`tamp.verification.bt.labels`). ``reduce``: merge on the live part of the executor (the
    default) or on the whole tree (the explicit reference).
    """
    events = list(events)
    labeller = Labeller(aps, state, appearing=[a.obj for a in events])
    world = branching_world(state, events=events, failures=failures, max_failures=max_failures)
    start = executor.snapshot(history=False)
    ts = TransitionSystem()
    index: dict[tuple, int] = {}
    executor_key = PaBtExecutor.live_key if reduce else PaBtExecutor.state_key
    cont = ExecutorSnapshot.fork if reduce else ExecutorSnapshot.resume

    def add(e: PaBtExecutor, w: SymbolicWorld, how: str) -> tuple[int, bool]:
        label = labeller.label(e, w)
        key = (executor_key(e), w.fingerprint(), label)
        if key in index:
            return index[key], False
        i = ts.add_state(label, how)
        index[key] = i
        return i, True

    root, _ = add(start.executor, world, "start")
    ts.init = root
    queue = deque([(root, start, world, start.executor.result is not None)])
    complete = True
    terminal = 0
    ticks = 0
    began = time.monotonic()
    said = began
    while queue:
        now = time.monotonic()
        if now - said >= PROGRESS_SECONDS:
            said = now
            log.info(
                "verifying the behavior tree: %d states explored, %d to expand "
                "(bound %d states), %.0f s",
                ts.num_states,
                len(queue),
                max_states,
                now - began,
            )
        i, snap, w, done = queue.popleft()
        if done:
            terminal += 1
            continue
        pending: list[list[Status]] = [[]]
        while pending:
            choices = pending.pop()
            work = cont(snap)
            w2 = copy.deepcopy(w)
            outcomes = w2.outcomes
            assert isinstance(outcomes, BranchingOutcomes)
            outcomes.choose(choices)
            w2.step()
            work.tick(w2)
            ticks += 1
            decisions = outcomes.decisions
            for k in range(len(choices), len(decisions)):
                pending.append(decisions[:k] + [Status.FAILURE])
            j, new = add(work, w2, _describe_tick(w2, work, choices))
            ts.add_edge(i, j)
            if new:
                if ts.num_states >= max_states:
                    complete = False
                    ts.unexpanded = {j, *(q[0] for q in queue)}
                    queue.clear()
                    break
                work.forget_history()
                w2.clear_history()
                # ``work`` is not ticked again: it becomes the new state's snapshot as is
                queue.append((j, ExecutorSnapshot(work), w2, work.result is not None))
    return Exploration(ts, complete, terminal, ticks)


def _describe_tick(w: SymbolicWorld, e: PaBtExecutor, choices: Sequence[Status]) -> str:
    parts = [str(ev) for ev in w.tick_events()]
    if Status.FAILURE in choices:
        parts.append("(outcome chosen: failure)")
    if e.result is not None:
        parts.append(f"tree {e.result.value}" + (f" ({e.reason})" if e.reason else ""))
    return "; ".join(parts) if parts else "tick"
