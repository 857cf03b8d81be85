"""SMP-MRO plans (Nakamura & Sekiyama, IEEE Access, §IV-B): the chosen goal order, and the
whole reachability graph.

Encoding (docs/architecture.md, "The verification gate"): one proposition ``g_k`` per goal ``G_k``,
true once the goal has been reached (labels are cumulative: an RG node is the *set* of
achieved goals, and a node is labelled with all of them). The demonstration's
constraints become ``!g_j U g_i`` for every ``G_i ≤ G_j`` (G_j is not reached before G_i)
and ``F g_i`` for every goal. An order ``[G_a, G_b, …]`` is the lasso
``{} ; {g_a} ; {g_a, g_b} ; … ; cycle{all reached}``: the robot stays done, as the RG's
final node does (the Kripke structure repeats dead ends).

How it is checked. These are the project's own formulas over *monotone* runs (a goal, once
reached, stays reached), so each conjunct is decided directly on the run, without an
automaton (docs/verification.md, "Orders and reachability graphs"):

- on an order (`check_order`): by one scan, O(|order| + |C| + |G|);
- on a graph whose edges never lose a goal, such as every RG (`check_graph`): by one
  breadth-first search, O(states + edges · in-degree in C + stuck states · |G| / 64),
  with goal sets as bit masks. Graphs that can lose a goal fall back to the explicit
  method (`check_graph_explicit`: Spot's product of the graph with the automaton of the
  negated conjunction), which is also the oracle of the property tests.

The automaton size guard of `tamp.ltl.translate` thus never sees these encodings: it is for
formulas a user writes. A violation's counterexample names the broken constraint (with the
demonstration's reason for it) or the goal never reached.
"""

from __future__ import annotations

import itertools
import re
from collections import Counter, deque
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from functools import lru_cache

import networkx as nx

from tamp.errors import InputError
from tamp.ltl.formula import Formula, as_formula
from tamp.rg.graph import set_bits
from tamp.verification.kripke import TransitionSystem, model_check
from tamp.verification.verdict import Counterexample, Report, Verdict
from tamp.verification.words import Word

#: Up to this many goals a counterexample's letters carry every goal proposition; beyond,
#: only those of the conjuncts it names (a run of 5,000 cumulative letters would otherwise
#: hold 12.5 M propositions).
FULL_LETTERS_UP_TO = 64
#: Violated conjuncts whose propositions the counterexample's letters keep (large plans).
SHOWN_VIOLATIONS = 8


@lru_cache(maxsize=4096)
def goal_prop(gid: str) -> str:
    """Proposition "goal ``gid`` reached": ``G3`` → ``g3`` (other ids: ``reached_<id>``)."""
    return gid.lower() if re.fullmatch(r"G\d+", gid) else f"reached_{gid}"


def constraint_parts(goal_ids: Sequence[str], constraints) -> list[str]:
    """The conjuncts of `constraint_formula`, as text, in a fixed order."""
    return [f"(!{goal_prop(j)} U {goal_prop(i)})" for i, j in sorted(constraints)] + [
        f"F {goal_prop(g)}" for g in goal_ids
    ]


def constraint_formula(goal_ids: Sequence[str], constraints) -> Formula:
    """``∧ (!g_j U g_i)`` over ``G_i ≤ G_j`` in C, ``∧ F g_i`` over the goals."""
    parts = constraint_parts(goal_ids, constraints)
    return Formula(" & ".join(parts) if parts else "1")


def order_word(order: Sequence[str], keep: Collection[str] | None = None) -> Word:
    """The lasso of cumulative "goal reached" letters for an execution order (only the
    propositions in ``keep``, when given)."""
    letters = [frozenset()]
    for g in order:
        p = goal_prop(g)
        letters.append(letters[-1] | {p} if keep is None or p in keep else letters[-1])
    return Word.lasso(letters, [letters[-1]])


def check_order_ids(goal_ids: Sequence[str], order: Sequence[str], source: str = "--order") -> None:
    known = set(goal_ids)
    for g in order:
        if g not in known:
            raise InputError(f"unknown goal {g!r} (known: {', '.join(goal_ids)})", field=source)
    dup = sorted(g for g, n in Counter(order).items() if n > 1)
    if dup:
        raise InputError(f"goal(s) {', '.join(dup)} listed more than once", field=source)


def reference_order(goal_ids: Sequence[str], constraints) -> list[str] | None:
    """Some order respecting C (demonstrated order as tie-break), or None when C is cyclic."""
    g = nx.DiGraph()
    g.add_nodes_from(goal_ids)
    g.add_edges_from(constraints)
    rank = {gid: k for k, gid in enumerate(goal_ids)}
    try:
        return list(nx.lexicographical_topological_sort(g, key=lambda x: rank[x]))
    except nx.NetworkXUnfeasible:
        return None


# -- the direct check of one monotone run ------------------------------------------------------


@dataclass(frozen=True)
class Broken:
    """One conjunct of the encoding that a run violates, in the user's terms.

    ``position``: the end of the conjunct's shortest bad prefix on the run (the letter where
    G_j turns true before G_i), or None when every prefix could still be extended (a goal is
    never reached: only the run's endless stay at its last state violates it).
    """

    conjunct: str
    props: tuple[str, ...]
    position: int | None
    reason: str


def run_violations(
    goal_ids: Sequence[str], constraints, at: dict[str, int], why: dict | None = None
) -> list[Broken]:
    """The conjuncts of `constraint_parts` (in that order) violated by a monotone run on which
    goal ``g`` turns true at position ``at[g]`` and stays true (goals absent from ``at`` are
    never reached; the run ends by staying forever where it is).

    Exact for such runs: ``F g_i`` holds iff G_i is reached; ``!g_j U g_i`` iff G_i is
    reached and G_j is not reached strictly before it. A violated ``U`` whose G_j is reached
    has its shortest bad prefix at ``at[j]`` (no continuation can make g_i true before
    g_j any more, even one that is not monotone); the others have none. O(|C| + |G|).
    """
    why = why or {}
    out: list[Broken] = []
    for i, j in sorted(constraints):
        if i in at and (j not in at or at[j] >= at[i]):
            continue
        text = f"(!{goal_prop(j)} U {goal_prop(i)})"
        props = (goal_prop(i), goal_prop(j))
        because = f" ({why[(i, j)]})" if (i, j) in why else ""
        if j in at:
            reason = f"{j} is reached at position {at[j]} before {i}, but C has {i} <= {j}{because}"
            out.append(Broken(text, props, at[j], reason))
        else:
            reason = f"{i} is never reached, so {i} <= {j}{because} is never met"
            out.append(Broken(text, props, None, reason))
    out.extend(
        Broken(f"F {goal_prop(g)}", (goal_prop(g),), None, f"{g} is never reached")
        for g in goal_ids
        if g not in at
    )
    return out


def _counterexample(
    broken: list[Broken],
    goal_ids: Sequence[str],
    word_of,
    *,
    steps: list[str],
    accepting_order: Sequence[str] | None,
    prefix: str = "",
) -> Counterexample:
    """The counterexample of a violated run: the conjunct with the shortest bad prefix
    explains it (exact for this encoding: a prefix is bad for the conjunction iff it is
    bad for one conjunct, since reaching every goal at once next satisfies all the others)."""
    first = min(broken, key=lambda b: (b.position is None, b.position or 0))
    if first.position is not None:
        tail = f"no continuation can satisfy the formula after position {first.position}"
    else:
        tail = (
            "every finite prefix can still be extended, but repeating the cycle forever never "
            "satisfies the formula"
        )
    keep: set[str] | None = None
    if len(goal_ids) > FULL_LETTERS_UP_TO:
        keep = {first.props[0], *first.props}
        for b in broken[:SHOWN_VIOLATIONS]:
            keep.update(b.props)
    aps = sorted(keep) if keep is not None else sorted(goal_prop(g) for g in goal_ids)
    return Counterexample(
        word_of(keep),
        f"{prefix}{first.reason}: {tail}",
        first.position,
        order_word(accepting_order, keep) if accepting_order is not None else None,
        violated=[str(as_formula(b.conjunct)) for b in broken],
        steps=steps,
        aps=aps,
    )


def _subject(order: Sequence[str]) -> str:
    if len(order) <= 12:
        return f"order {', '.join(order) if order else '(empty)'}"
    return f"order of {len(order)} goals ({', '.join(order[:3])}, …, {order[-1]})"


def check_order(demo, order: Sequence[str], *, source: str = "--order") -> Verdict:
    """Verdict of the order trace against the constraint encoding of ``demo``, decided by
    `run_violations` in one scan (no automaton; any number of goals and constraints)."""
    ids = demo.goal_ids
    check_order_ids(ids, order, source)
    at = {g: k + 1 for k, g in enumerate(order)}  # the letter where goal g turns true
    formula = " & ".join(constraint_parts(ids, demo.constraints)) or "1"
    explored = len(order) + 2  # the prefix letters and the repeated last one
    broken = run_violations(ids, demo.constraints, at, demo.constraint_reasons)
    if not broken:
        return Verdict(_subject(order), formula, "infinite", True, explored)
    ce = _counterexample(
        broken,
        ids,
        lambda keep: order_word(order, keep),
        steps=["start"] + [f"reach {g}" for g in order] + ["done (stays)"],
        accepting_order=reference_order(ids, demo.constraints),
    )
    return Verdict(_subject(order), formula, "infinite", False, explored, ce)


# -- graphs of goal sets --------------------------------------------------------------------


@dataclass
class GoalGraph:
    """An explicit graph whose states are sets of reached goals, as bit masks over ``ids``
    (bit k: ``ids[k]`` reached); ``init`` is the start state."""

    ids: tuple[str, ...]
    masks: list[int]
    succ: list[list[int]]
    init: int = 0

    @staticmethod
    def of_rg(reachability) -> GoalGraph | None:
        """The enumeration of a `tamp.rg.graph.ReachabilityGraph` (None past its limit)."""
        enumeration = reachability.enumeration()
        if enumeration is None:
            return None
        masks, edges = enumeration
        succ: list[list[int]] = [[] for _ in masks]
        for at, to, _ in edges:
            succ[at].append(to)
        return GoalGraph(tuple(reachability.index.ids), list(masks), succ, 0)

    @staticmethod
    def of_networkx(ids: Sequence[str], rg: nx.DiGraph) -> GoalGraph:
        """A graph whose nodes are frozensets of goal ids, the root being the empty set."""
        root = frozenset()
        if root not in rg:
            raise ValueError("the RG has no root node (the empty set of achieved goals)")
        bit = {g: 1 << k for k, g in enumerate(ids)}
        nodes = list(rg.nodes)
        index = {n: k for k, n in enumerate(nodes)}
        masks = [sum(bit[g] for g in n) for n in nodes]
        succ = [[index[m] for m in rg.successors(n)] for n in nodes]
        return GoalGraph(tuple(ids), masks, succ, index[root])

    def name(self, state: int) -> str:
        """``{G0, G1}``; a large set is abbreviated to its first goals and its size."""
        mask = self.masks[state]
        count = mask.bit_count()
        names = [self.ids[k] for k in itertools.islice(set_bits(mask), 8 if count <= 8 else 3)]
        if count <= 8:
            return "{" + ", ".join(names) + "}"
        return "{" + ", ".join(names) + f", … ({count} goals)" + "}"


@dataclass(frozen=True)
class _Witness:
    """A reachable state where the encoding breaks: by a constraint (a bad prefix ends
    there) or by the run staying there forever with goals missing."""

    state: int
    stuck: bool


def _search(gg: GoalGraph, preds: list[list[int]]) -> tuple[int, list[int], _Witness | None]:
    """Breadth-first search from ``gg.init``: (states reached, BFS parents, first witness),
    or parents ``[]`` when some edge loses a goal (not monotone: no direct check)."""
    masks, succ = gg.masks, gg.succ
    full = (1 << len(gg.ids)) - 1
    parent = [-1] * len(masks)
    seen = [False] * len(masks)
    seen[gg.init] = True
    queue = deque([gg.init])
    reached = 0
    broken: _Witness | None = None
    stuck: _Witness | None = None
    stutter: list[tuple[int, int]] = []  # edges keeping the goal set: cycles can only use them

    def breaks(mask: int, new: int) -> bool:
        return any(not mask >> i & 1 for j in set_bits(new) for i in preds[j])

    if breaks(masks[gg.init], masks[gg.init]):
        broken = _Witness(gg.init, False)
    while queue:
        u = queue.popleft()
        reached += 1
        mu = masks[u]
        if not succ[u] and mu != full and stuck is None:
            stuck = _Witness(u, True)
        for v in succ[u]:
            mv = masks[v]
            if mu & ~mv:
                return reached, [], None
            if mv == mu:
                stutter.append((u, v))
            if not seen[v]:
                seen[v] = True
                parent[v] = u
                queue.append(v)
                if broken is None and breaks(mv, mv & ~mu):
                    broken = _Witness(v, False)
    if broken is not None:
        return reached, parent, broken
    if stuck is None and stutter:  # a cycle of equal goal sets missing a goal also sticks
        loops = nx.DiGraph(stutter)
        for scc in nx.strongly_connected_components(loops):
            s = next(iter(scc))
            if masks[s] != full and (len(scc) > 1 or loops.has_edge(s, s)):
                stuck = _Witness(s, True)
                break
    return reached, parent, stuck


def _lasso(gg: GoalGraph, parent: list[int], w: _Witness) -> tuple[list[int], list[int]]:
    """(prefix, cycle) of a run from the start through the witness: the cycle, repeated
    forever, is the witness itself (a dead end stutters) or a cycle of equal goal sets
    through it, or, for a broken constraint, where any way on from the witness ends."""
    path = [w.state]
    while parent[path[-1]] != -1:
        path.append(parent[path[-1]])
    path.reverse()
    if w.stuck:
        return path[:-1], _cycle_through(gg, w.state) or [w.state]
    seen = set(path)
    while gg.succ[path[-1]]:
        nxt = gg.succ[path[-1]][0]
        if nxt in seen:
            k = path.index(nxt)
            return path[:k], path[k:]
        seen.add(nxt)
        path.append(nxt)
    return path[:-1], [path[-1]]


def _cycle_through(gg: GoalGraph, s: int) -> list[int] | None:
    """A cycle from ``s`` back to ``s`` over states with its goal set (None: a dead end)."""
    m = gg.masks[s]
    parent = {s: -1}
    queue = deque([s])
    while queue:
        u = queue.popleft()
        for v in gg.succ[u]:
            if gg.masks[v] != m:
                continue
            if v == s:
                cycle = [u]
                while parent[cycle[-1]] != -1:
                    cycle.append(parent[cycle[-1]])
                return cycle[::-1]
            if v not in parent:
                parent[v] = u
                queue.append(v)
    return None


def check_goal_graph(demo, gg: GoalGraph, *, subject: str | None = None) -> Verdict | None:
    """Every path of ``gg`` against the encoding of ``demo``, directly (see the module
    docstring); None when some edge loses a goal (then use `check_graph_explicit`)."""
    ids = list(gg.ids)
    pos = {g: k for k, g in enumerate(ids)}
    preds: list[list[int]] = [[] for _ in ids]
    for i, j in demo.constraints:
        preds[pos[j]].append(pos[i])
    reached, parent, witness = _search(gg, preds)
    if not parent:
        return None
    edges = sum(len(s) for s in gg.succ)
    subject = subject or f"RG ({len(gg.masks)} states, {edges} edges)"
    formula = " & ".join(constraint_parts(ids, demo.constraints)) or "1"
    if witness is None:
        return Verdict(subject, formula, "all paths", True, reached)
    prefix, cycle = _lasso(gg, parent, witness)
    run = prefix + cycle
    # the goals each step adds (the run never loses one): O(run · |G| / 64 + |G|)
    added = [gg.masks[run[0]]] + [gg.masks[b] & ~gg.masks[a] for a, b in itertools.pairwise(run)]
    at = {ids[k]: t for t, new in enumerate(added) for k in set_bits(new)}
    broken = run_violations(ids, demo.constraints, at, demo.constraint_reasons)

    def word_of(keep):
        letters, cur = [], frozenset()
        for new in added:
            props = {goal_prop(ids[k]) for k in set_bits(new)}
            cur = cur | {p for p in props if keep is None or p in keep} if props else cur
            letters.append(cur)
        return Word.lasso(letters[: len(prefix)], letters[len(prefix) :])

    ce = _counterexample(
        broken,
        ids,
        word_of,
        steps=[gg.name(s) for s in run],
        accepting_order=reference_order(ids, demo.constraints),
        prefix=f"a path of {subject} violates the formula: ",
    )
    return Verdict(subject, formula, "all paths", False, reached, ce)


def rg_system(rg: nx.DiGraph) -> TransitionSystem:
    """The RG as a transition system: node = achieved set, labelled with its g_k."""
    ts = TransitionSystem()
    index: dict[frozenset, int] = {}
    root = frozenset()
    if root not in rg:
        raise ValueError("the RG has no root node (the empty set of achieved goals)")
    for n in rg.nodes:
        name = "{" + ", ".join(sorted(n)) + "}"
        index[n] = ts.add_state(frozenset(map(goal_prop, n)), name)
    for a, b in rg.edges:
        ts.add_edge(index[a], index[b])
    ts.init = index[root]
    return ts


def check_graph_explicit(demo, rg: nx.DiGraph) -> Verdict:
    """Every path of ``rg`` against the whole encoding, by the explicit automaton method:
    Spot's product of the RG's Kripke structure with the automaton of the negated
    conjunction (`tamp.verification.kripke.model_check`). Subject to the translation guard of
    `tamp.ltl` (at most 64 goals); the direct check agrees with it wherever it runs."""
    ids = demo.goal_ids
    ts = rg_system(rg)
    ref = reference_order(ids, demo.constraints)
    return model_check(
        ts,
        constraint_formula(ids, demo.constraints),
        subject=f"RG ({ts.num_states} states, {ts.num_edges} edges)",
        accepting_word=order_word(ref) if ref is not None else None,
    )


def check_graph(demo, rg: nx.DiGraph | None = None) -> Verdict:
    """Every path of the RG (the demonstration's own unless given) satisfies the encoding.

    The demonstration's RG is read from its bit-mask enumeration (`tamp.rg.graph`), never
    as networkx sets. A given graph is checked directly when no edge loses a goal, else by
    `check_graph_explicit`.
    """
    if rg is None:
        from tamp.rg.graph import ReachabilityGraph, RGTooLarge

        reachability = ReachabilityGraph(demo)
        gg = GoalGraph.of_rg(reachability)
        if gg is None:
            raise RGTooLarge(f"the RG has more than {reachability.limit} states")
        verdict = check_goal_graph(demo, gg)
        assert verdict is not None  # the RG only adds goals
        return verdict
    verdict = check_goal_graph(demo, GoalGraph.of_networkx(demo.goal_ids, rg))
    return verdict if verdict is not None else check_graph_explicit(demo, rg)


def check_plan(result, *, graph: bool = True, rg: nx.DiGraph | None = None) -> Report:
    """The RG planner's result (``tamp.rg.PlanResult``): its order, and the whole RG.

    Both checks are linear in the plan's size (see the module docstring). The whole RG is
    checked as far as the planner enumerated it: its enumeration budget
    (`tamp.rg.plan`'s ``stats_limit``, 200,000 states by default) bounds the work; past it
    the report notes that only the order was checked.
    """
    demo = result.demo
    verdicts = [check_order(demo, list(result.order), source="order")]
    notes: list[str] = []
    if graph:
        if rg is not None:
            verdicts.append(check_graph(demo, rg))
        else:
            reachability = result.reachability
            gg = GoalGraph.of_rg(reachability)
            if gg is None:
                notes.append(
                    f"whole-RG check skipped: the RG has more than {reachability.limit} "
                    "states (the planner's enumeration budget); the order itself is verified"
                )
            else:
                verdict = check_goal_graph(demo, gg)
                assert verdict is not None  # the RG only adds goals
                verdicts.append(verdict)
    return Report(verdicts, notes=notes)
