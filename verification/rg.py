"""SMP-MRO plans (Nakamura & Sekiyama, IEEE Access, §IV-B): the chosen goal order, and the
whole reachability graph.

Encoding (docs/architecture.md, "The verification gate"): one proposition ``g_k`` per goal ``G_k``,
true once the goal has been reached (labels are cumulative: an RG node is the *set* of
achieved goals, and a node is labelled with all of them). The demonstration's
constraints become ``!g_j U g_i`` for every ``G_i ≤ G_j`` (G_j is not reached before G_i)
and ``F g_i`` for every goal. An order ``[G_a, G_b, …]`` is the lasso
``{} ; {g_a} ; {g_a, g_b} ; … ; cycle{all reached}``: the robot stays done, as the RG's
final node does (the Kripke structure repeats dead ends).
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Sequence
from functools import lru_cache

import networkx as nx

from tamp.errors import InputError
from tamp.ltl.formula import Formula
from verification.kripke import TransitionSystem, model_check
from verification.traces import MAX_CONJUNCTS_FOR_WHOLE, check_trace, known_violations
from verification.verdict import Report, Verdict
from verification.words import Word


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


def order_word(order: Sequence[str]) -> Word:
    """The lasso of cumulative "goal reached" letters for an execution order."""
    letters = [frozenset()]
    for g in order:
        letters.append(letters[-1] | {goal_prop(g)})
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


def order_violations(
    goal_ids: Sequence[str], constraints, order: Sequence[str]
) -> list[tuple[str, int | None]]:
    """The conjuncts of `constraint_parts` that the order's lasso violates, in that order,
    with the end of each one's shortest bad prefix (None: no bad prefix), by one scan.

    This decides each conjunct exactly, because the lasso of an order is monotone: letter t
    holds the first t goals of the order, and the last letter repeats forever. So
    ``F g_i`` holds iff G_i is in the order, and ``!g_j U g_i`` iff G_i is in the order and
    G_j is not reached before it (a goal is reached at one letter only). A violated ``U``
    conjunct has its shortest bad prefix at the letter where g_j turns true (no
    continuation can make g_i true before it any more); a missing goal's ``F g_i`` has
    none (every prefix could still be extended). O(|order| + |C| + |G|), no automaton.
    """
    at = {g: k + 1 for k, g in enumerate(order)}  # the letter where goal g turns true
    bad: list[tuple[str, int | None]] = []
    for i, j in sorted(constraints):
        if i not in at or (j in at and at[j] < at[i]):
            bad.append((f"(!{goal_prop(j)} U {goal_prop(i)})", at.get(j)))
    bad.extend((f"F {goal_prop(g)}", None) for g in goal_ids if g not in at)
    return bad


def check_order(demo, order: Sequence[str], *, source: str = "--order") -> Verdict:
    """Verdict of the order trace against the constraint encoding of ``demo``.

    Small encodings (at most `MAX_CONJUNCTS_FOR_WHOLE` conjuncts) are checked on the
    automaton of the whole formula, as any trace. Larger ones are decided by
    `order_violations` (one linear scan, exact for this encoding, see there) and never
    build the conjunction; only a violated order then reads an automaton, that of the
    conjunct with the shortest bad prefix, for its counterexample.
    """
    ids = demo.goal_ids
    check_order_ids(ids, order, source)
    subject = f"order {', '.join(order) if order else '(empty)'}"
    steps = ["start"] + [f"reach {g}" for g in order] + ["done (stays)"]
    parts = constraint_parts(ids, demo.constraints)
    if len(parts) > MAX_CONJUNCTS_FOR_WHOLE:
        violated = order_violations(ids, demo.constraints, order)
        ref = reference_order(ids, demo.constraints) if violated else None
        return known_violations(
            " & ".join(parts),
            sorted(goal_prop(g) for g in ids),
            lambda: order_word(order),
            violated,
            explored=len(order) + 2,  # the prefix letters and the repeated last one
            subject=subject,
            steps=steps,
            accepting_word=order_word(ref) if ref is not None else None,
        )
    f = constraint_formula(ids, demo.constraints)
    ref = reference_order(ids, demo.constraints)
    return check_trace(
        f,
        order_word(order),
        finite=False,
        accepting_word=order_word(ref) if ref is not None else None,
        subject=subject,
        steps=steps,
    )


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


def check_graph(demo, rg: nx.DiGraph | None = None) -> Verdict:
    """Every path of the RG (``build_rg(demo)`` unless given) satisfies the encoding."""
    if rg is None:
        from tamp.rg import build_rg

        rg = build_rg(demo)
    ids = demo.goal_ids
    f = constraint_formula(ids, demo.constraints)
    ts = rg_system(rg)
    ref = reference_order(ids, demo.constraints)
    return model_check(
        ts,
        f,
        subject=f"RG ({ts.num_states} states, {ts.num_edges} edges)",
        accepting_word=order_word(ref) if ref is not None else None,
    )


#: The gate model-checks the whole RG up to this many states (≈0.5 s per 4k states); beyond,
#: only the chosen order is checked (``tamp-verify plan`` always checks the whole graph).
GRAPH_LIMIT = 10_000
#: ... and up to this many (state, goal) label entries: each state is labelled with every
#: goal reached there, so one object's chain of 5,000 goals (5,001 states) has 12.5 M of
#: them and its whole-RG check would take minutes and gigabytes; 2^12 states of 12 goals
#: have 49 k.
GRAPH_LABEL_LIMIT = 250_000


def check_plan(
    result,
    *,
    graph: bool = True,
    rg: nx.DiGraph | None = None,
    graph_limit: int | None = GRAPH_LIMIT,
) -> Report:
    """The RG planner's result (``tamp.rg.PlanResult``): its order, and the whole RG.

    The whole-graph check is skipped (with a note in the report) when the RG has more than
    ``graph_limit`` states or was too large for the planner to count.
    """
    demo = result.demo
    verdicts = [check_order(demo, list(result.order), source="order")]
    notes: list[str] = []
    if graph:
        states = getattr(getattr(result, "rg", None), "states", None) if rg is None else len(rg)
        if rg is None and states is None:
            notes.append("whole-RG check skipped: the RG is too large to enumerate")
        elif graph_limit is not None and states is not None and states > graph_limit:
            notes.append(
                f"whole-RG check skipped: {states} states > {graph_limit} (use tamp-verify plan)"
            )
        elif (
            graph_limit is not None
            and states is not None
            and states * len(demo.goals) > GRAPH_LABEL_LIMIT
        ):
            notes.append(
                f"whole-RG check skipped: {states} states × {len(demo.goals)} goals > "
                f"{GRAPH_LABEL_LIMIT} labels (use tamp-verify plan)"
            )
        else:
            if rg is None and hasattr(result, "graph"):
                rg = result.graph()  # the plan's own enumeration: the RG is built once
            verdicts.append(check_graph(demo, rg))
    return Report(verdicts, notes=notes)
