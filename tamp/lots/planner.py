"""Planning on the automaton with the W^B counts carried along (Zhou et al. Alg. 2 and 3).

* :func:`initial_lasso` — Dijkstra over the automaton from ``q_0`` for the cheapest accepting
  lasso ``prefix · cycle^ω`` whose letters are executable; one *round* of the task is the
  prefix followed by one traversal of the cycle, and its W^B counts are ``s^B_final``.
* :meth:`Planner.plan_from` — Alg. 2 line 1, ``Dijkstra(q_s, s^B_s, B)``: the cheapest run from
  the pair ``(q, s^B)`` to an accepting state with ``s^B = s^B_final`` (A* with an admissible
  count heuristic; W^B stays inside Lemma 1's box). Steps are deliveries (one proposition
  true), the empty letter, or removing an object from W^B (empty letter).
* :class:`Table` — the table ``T`` (W^B state → action), built from a plan (Alg. 2 lines 2-8).
* :class:`Tree` — the search tree ``TR`` of pairs ``(q, s^B)`` and its update (Alg. 3),
  random (seedable) or breadth-first; both expand until a pair with the observed W^B state
  that can still complete the task is found, or the reachable pairs are exhausted (verdict:
  the state cannot lead to completion, Alg. 1 line 23).

Pairs, tables and plans are the stable API that ``tamp.verification`` reads: ``Plan.prefix`` /
``Plan.cycle`` (letters = frozensets of true propositions), ``Table.as_mapping()`` and
:func:`follow_table`.
"""

from __future__ import annotations

import heapq
import itertools
import random
from collections import deque
from collections.abc import Collection, Iterator
from dataclasses import dataclass, field

from tamp.lots.automaton import EMPTY, Automaton, Letter
from tamp.lots.lots import Counts, Lots
from tamp.lots.task import Task

Pair = tuple[int, Counts]
#: a node of `Planner.plan_from`'s search: a pair and the W^A stock left (None: not tracked)
Node = tuple[int, Counts, Counts | None]


@dataclass(frozen=True)
class Step:
    """One step of a run: ``(q, b) --letter--> (q_next, b_next)``.

    ``kind``: ``move`` (deliver one object for proposition ``prop``), ``remove`` (take one
    object of class ``cls`` out of W^B — back to W^A when the rest of the run needs it, else
    into the waste basket; letter ∅) or ``idle`` (letter ∅, nothing moves; only the automaton
    state changes).
    """

    kind: str
    q: int
    b: Counts
    q_next: int
    b_next: Counts
    prop: str | None = None
    cls: int | None = None

    @property
    def letter(self) -> Letter:
        if self.kind != "move":
            return EMPTY
        assert self.prop is not None, "a move names the proposition it delivers"
        return frozenset({self.prop})


@dataclass
class Plan:
    """A run from ``start`` to a goal pair, and the accepting cycle that continues it.

    ``prefix`` lists the letters of ``steps``; ``prefix · cycle^ω`` is accepted by the task
    automaton (what ``tamp.verification`` checks).
    """

    start: Pair
    steps: list[Step]
    cycle: list[Letter]
    cost: float

    @property
    def prefix(self) -> list[Letter]:
        return [s.letter for s in self.steps]

    @property
    def end(self) -> Pair:
        return (self.steps[-1].q_next, self.steps[-1].b_next) if self.steps else self.start


# ---------------------------------------------------------------------------- initial lasso
def initial_lasso(aut: Automaton, task: Task) -> tuple[list[Step], list[Letter], Counts]:
    """Cheapest executable accepting lasso from ``q_0`` (Alg. 1 line 3 / Alg. 2 line 1).

    Dijkstra on ``(phase, q, b, q_F)``: phase 0 walks to an accepting state ``q_F``; a free
    switch starts phase 1, which must return to ``q_F`` with at least one letter. ``b`` is
    W^B, from ``s^B_0`` (objects already there at the start), bounded by the objects that
    exist; a step delivers, reads ∅, or takes one object out of W^B (∅, at
    ``remove_cost``). With Zhou et al.'s action set (Def. 3, the default) that object goes
    into the waste basket and is gone: the node also carries what is left in W^A, and a
    delivery needs an object there. With our return action (``task.returns``) it goes back to
    W^A — so an object of a needed class that starts in W^B is removed and delivered again
    when the formula needs its delivery event. Ties: fewer steps, then letter order. Returns
    (round steps = prefix then one cycle, the cycle letters, s^B_final).
    """
    classes = task.classes
    idx = {c: i for i, c in enumerate(classes)}
    prop_class = {p.name: idx[p.cls] for p in task.propositions}
    cost_of = {p.name: p.cost for p in task.propositions}
    avail = tuple(task.initial_a.get(c, 0) + task.initial_b.get(c, 0) for c in classes)
    b0 = tuple(task.initial_b.get(c, 0) for c in classes)
    box = Lots(classes, prop_class, avail)
    # W^A's stock, tracked only without the return action (a discarded object is gone)
    stock0 = None if task.returns else tuple(task.initial_a.get(c, 0) for c in classes)
    start = (0, aut.initial, b0, -1, False, stock0)
    tie = itertools.count()
    heap = [((0.0, 0), next(tie), start)]
    best: dict = {start: (0.0, 0)}
    parent: dict = {start: None}
    while heap:
        key, _, node = heapq.heappop(heap)
        if best.get(node) != key:
            continue
        phase, q, b, qf, moved, stock = node
        if phase == 1 and moved and q == qf:
            return _lasso_from(parent, node, box)
        succ: list = []
        if phase == 0 and q in aut.live_accepting:
            succ.append(((1, q, b, q, False, stock), 0.0, None))
        for letter in aut.letters:
            nb = box.deliver(b, letter)
            if nb is None:
                continue
            ns = stock
            if letter and stock is not None:
                i = prop_class[next(iter(letter))]
                if stock[i] == 0:
                    continue
                ns = stock[:i] + (stock[i] - 1,) + stock[i + 1 :]
            c = cost_of[next(iter(letter))] if letter else 0.0
            for nq in aut.successors(q, letter):
                succ.append(((phase, nq, nb, qf, moved or phase == 1, ns), c, letter))
        for i in range(len(b)):  # take one object out of W^B (letter ∅; the int marks it)
            nb = box.remove(b, i)
            if nb is not None:
                for nq in aut.successors(q, EMPTY):
                    nxt = (phase, nq, nb, qf, moved or phase == 1, stock)
                    succ.append((nxt, task.remove_cost, i))
        for nxt, c, letter in succ:
            nkey = (key[0] + c, key[1] + (letter is not None))
            if nxt not in best or nkey < best[nxt]:
                best[nxt] = nkey
                parent[nxt] = (node, letter)
                heapq.heappush(heap, (nkey, next(tie), nxt))
    why = (
        ""
        if task.returns
        else (
            "; Zhou et al.'s actions only deliver from W^A to W^B (or discard into the waste "
            "basket), so no object can be delivered twice — the return action W^B→W^A "
            "(task field 'actions: {return: true}' or --return-action) is our extension"
        )
    )
    raise_infeasible(
        f"the formula {task.formula!r} has no accepting run that moves one object at a time "
        f"with the objects available ({dict(zip(classes, avail, strict=True))}){why}"
    )
    raise AssertionError  # unreachable


def round_goals(aut: Automaton, task: Task, final: Counts) -> tuple[Counts, ...]:
    """Every W^B state that ends one round of some accepting way of the task, ``final`` first.

    A round of a way, from an empty W^B: a prefix of deliveries (and ∅) to an accepting state
    ``q_F`` on an accepting cycle, then one traversal of *any* non-empty cycle back to ``q_F``
    (a recurring choice, ``GF(p | q)``, gives one way per class); its end is W^B after both.
    Objects are those that exist (W^A and W^B at the start); delivering a class again when
    all its objects are already in W^B takes one out first (∅, then the delivery), so a way
    that delivers an object twice (``F(p & F(q & F p))`` with one cup) ends with it in W^B
    once. ``F p | F q`` (classes x, y) has two ends, ``x^1 y^0`` and ``x^0 y^1``. Kept, for
    each accepting state ``q_F``: the minimal ends of its *plain* rounds (each object
    delivered once), and the ends of its redelivering rounds that are minimal among all its
    ends — a round of the same kind through the same ``q_F`` that leaves more in W^B is
    surplus, not another way; a round through another ``q_F`` is another way even with a
    larger end (``F(p & F q) | GF p`` keeps cup, and cup with mug: once ``p`` is delivered
    for the first way only the mug completes it), and a plain round stays a way beside a
    redelivering one with a smaller end (``(F p0 & F p2) | F(p1 & F p2)`` with one mug keeps
    cup with mug beside mug alone). Plus ``final`` (the planned round).

    Search: ``(q, b, q_F, redelivered?)`` (``q_F`` = -1 in the prefix), by levels of ``Σ b``
    (W^B only grows along a round); a state above a known end of its ``q_F`` (of every ``q_F``
    in the prefix) is not expanded. At most ``4·|Q|·(|Q_F| + 1)·∏(m_i + 1)`` states, with
    ``m_i = min(n_i, K + 1)`` and ``K = 2·|Q|·(|Q_F| + 1)`` the number of control states
    ``(q, q_F, redelivered?)``: a kept end delivers no class more than K times, so counts
    beyond that (a person pouring 10^7 objects into W^A) cost nothing. Why: on a path that
    delivers class ``i`` more than K times, two of those deliveries start from the same control
    state; cutting the segment between them leaves a path to the same ``q_F`` whose W^B is
    smaller (a return it then cannot make, its class no longer all in W^B, becomes ∅ and a
    delivery, still below the cut path's W^B), so the longer path's end is above a kept one.
    A class capped this way has more objects than any kept end delivers, so its return
    action (all of the class in W^B) never applies.
    """
    classes = task.classes
    idx = {c: i for i, c in enumerate(classes)}
    props = [(frozenset({p.name}), idx[p.cls]) for p in task.propositions]
    avail = tuple(task.initial_a.get(c, 0) + task.initial_b.get(c, 0) for c in classes)
    live = aut.live_accepting
    control = 2 * aut.num_states * (len(live) + 1)
    cap = tuple(min(n, control + 1) for n in avail)  # deliveries a kept end can need
    # per q_F: the minimal ends of plain rounds, and of all rounds (plain and redelivering)
    plain: dict[int, list[Counts]] = {qf: [] for qf in live}
    every: dict[int, list[Counts]] = {qf: [] for qf in live}

    def above(b: Counts, gs: list[Counts], strict: bool) -> bool:
        return any(
            all(x >= y for x, y in zip(b, g, strict=True)) and (b != g or not strict) for g in gs
        )

    def pruned(b: Counts, qf: int, sat: bool) -> bool:
        """No new end can follow: b is above a known end of its q_F (of every q_F while in
        the prefix) — a plain end for a plain round, any end for a redelivering one."""
        known = every if sat else plain
        if qf >= 0:
            return above(b, known[qf], strict=True)
        return all(above(b, gs, strict=True) for gs in known.values())

    def steps(q: int, b: Counts, sat: bool) -> Iterator[tuple[int, Counts, bool]]:
        for nq in aut.successors(q, EMPTY):
            yield nq, b, sat
        for letter, i in props:
            if b[i] < cap[i]:
                nb = b[:i] + (b[i] + 1,) + b[i + 1 :]
                for nq in aut.successors(q, letter):
                    yield nq, nb, sat
            elif b[i] == avail[i] and avail[i] and task.returns:  # all of the class in W^B:
                # one back to W^A, delivered again
                for mid in aut.successors(q, EMPTY):
                    for nq in aut.successors(mid, letter):
                        yield nq, b, True

    start = (aut.initial, (0,) * len(classes), -1, False)  # qf -1: still in the prefix
    seen: set[tuple[int, Counts, int, bool]] = {start}
    level = [start]
    while level:
        nxt_level: list[tuple[int, Counts, int, bool]] = []
        stack = list(level)
        while stack:
            q, b, qf, sat = stack.pop()
            if pruned(b, qf, sat):
                continue
            if qf >= 0 and q == qf and not above(b, (every if sat else plain)[qf], False):
                if not sat:
                    plain[qf].append(b)
                every[qf].append(b)
            succ = [(nq, nb, qf, s) for nq, nb, s in steps(q, b, sat)]
            if qf < 0 and q in live:  # the cycle starts here (its first step)
                succ += [(nq, nb, q, s) for nq, nb, s in steps(q, b, sat)]
            for node in succ:
                if node not in seen:
                    seen.add(node)
                    (stack if node[1] == b else nxt_level).append(node)
        level = nxt_level
    rest = {g for gs in every.values() for g in gs} - {final}
    return (final, *sorted(rest))


def cheapest_cycle(aut: Automaton, cost_of: dict[str, float], qf: int) -> list[Letter]:
    """Cheapest non-empty accepting cycle ``q_F → q_F`` (letters only; the ω-continuation)."""
    tie = itertools.count()
    heap: list = []
    best: dict[int, tuple[float, int]] = {}
    parent: dict[int, tuple[int, Letter] | None] = {}
    for letter in aut.letters:
        c = cost_of[next(iter(letter))] if letter else 0.0
        for nq in aut.successors(qf, letter):
            key = (c, 1)
            if nq not in best or key < best[nq]:
                best[nq], parent[nq] = key, (-1, letter)
                heapq.heappush(heap, (key, next(tie), nq))
    done: set[int] = set()
    while heap:
        key, _, q = heapq.heappop(heap)
        if q in done or best[q] != key:
            continue
        done.add(q)
        if q == qf:
            letters: list[Letter] = []
            node = q
            while True:
                link = parent[node]
                assert link is not None  # every state pushed has its parent link
                prev, letter = link
                letters.append(letter)
                if prev == -1:
                    break
                node = prev
            letters.reverse()
            return letters
        for letter in aut.letters:
            c = cost_of[next(iter(letter))] if letter else 0.0
            for nq in aut.successors(q, letter):
                nk = (key[0] + c, key[1] + 1)
                if nq != qf and nq in done:
                    continue
                if nq not in best or nk < best[nq]:
                    best[nq], parent[nq] = nk, (q, letter)
                    heapq.heappush(heap, (nk, next(tie), nq))
    raise ValueError(f"automaton state {qf} is not on an accepting cycle")


def raise_infeasible(reason: str) -> None:
    from tamp.errors import InfeasibleError

    raise InfeasibleError(reason)


def _lasso_from(parent: dict, node: tuple, box: Lots) -> tuple[list[Step], list[Letter], Counts]:
    chain = []
    while parent[node] is not None:
        prev, letter = parent[node]
        chain.append((prev, letter, node))
        node = prev
    chain.reverse()
    steps: list[Step] = []
    cycle: list[Letter] = []
    for prev, letter, nxt in chain:
        if letter is None:  # the phase switch
            continue
        if isinstance(letter, int):  # a removal from W^B
            steps.append(Step("remove", prev[1], prev[2], nxt[1], nxt[2], cls=letter))
            letter = EMPTY
        else:
            steps.append(_step(prev[1], prev[2], letter, nxt[1], nxt[2], box))
        if prev[0] == 1:
            cycle.append(letter)
    final = steps[-1].b_next if steps else chain[-1][2][2]
    return steps, cycle, final


def _step(q: int, b: Counts, letter: Letter, nq: int, nb: Counts, lots: Lots) -> Step:
    if letter:
        (p,) = letter
        return Step("move", q, b, nq, nb, prop=p, cls=lots.prop_class[p])
    return Step("idle", q, b, nq, nb)


# ---------------------------------------------------------------------------- planner
class Planner:
    """Alg. 2's Dijkstra from any pair ``(q, s^B)``; remembers pairs proven dead."""

    def __init__(self, aut: Automaton, lots: Lots, task: Task):
        self.aut = aut
        self.lots = lots
        self.remove_cost = task.remove_cost
        self.cost_of = {p.name: p.cost for p in task.propositions}
        self._min_cost = [
            min((p.cost for p in task.propositions if lots.prop_class[p.name] == i), default=0.0)
            for i in range(len(lots.classes))
        ]
        self.dead: set[Node] = set()  # nodes proven dead with every object available
        # ... with fewer (per W^B bound, stock, relaxation)
        self._dead_capped: dict[tuple[Counts, Counts | None, bool], set[Node]] = {}
        self._cycles: dict[int, list[Letter]] = {}
        self.expanded = 0  # pairs expanded by plan_from (for the benchmark)
        # per automaton state: (cost, proposition or None, class index or -1, successor)
        self._trans: list[list[tuple[float, str | None, int, int]]] = []
        for q in range(aut.num_states):
            out: list[tuple[float, str | None, int, int]] = [
                (0.0, None, -1, nq) for nq in aut.successors(q, EMPTY)
            ]
            for p in (pp.name for pp in task.propositions):
                for nq in aut.successors(q, frozenset({p})):
                    out.append((self.cost_of[p], p, lots.prop_class[p], nq))
            self._trans.append(out)
        self._empty = [aut.successors(q, EMPTY) for q in range(aut.num_states)]
        #: the round's accepting cycle (the initial lasso's), and the states that accept it
        #: forever: a relaxed goal (`plan_from`) may end in one of them
        self.round_cycle: list[Letter] = []
        self._cycle_ok: frozenset[int] | None = None

    def cycle_ok(self) -> frozenset[int]:
        """Automaton states from which ``round_cycle^ω`` is accepted (computed once)."""
        if self._cycle_ok is None:
            from tamp.ltl.automata import accepts_lasso

            self._cycle_ok = frozenset(
                q
                for q in range(self.aut.num_states)
                if self.round_cycle
                and accepts_lasso(self.aut.spot_aut, [], self.round_cycle, start=q)[0]
            )
        return self._cycle_ok

    def heuristic(self, b: Counts, goals: tuple[Counts, ...] | None = None) -> float:
        """Admissible: every object missing for the nearest goal (default: every round end)
        needs one delivery of at least its cheapest cost."""
        return min(
            sum((n - x) * c for x, n, c in zip(b, gl, self._min_cost, strict=True) if n > x)
            for gl in (self.lots.goals if goals is None else goals)
        )

    def moves(self, q: int, b: Counts) -> Iterator[Step]:
        """Executable steps from a pair (deliveries, ∅, removals to the waste basket)."""
        lots, aut = self.lots, self.aut
        for letter in aut.letters:
            nb = lots.deliver(b, letter)
            if nb is None:
                continue
            for nq in aut.successors(q, letter):
                yield _step(q, b, letter, nq, nb, lots)
        empty = aut.successors(q, EMPTY)
        for i in range(len(b)):
            nb = lots.remove(b, i)
            if nb is None:
                continue
            for nq in empty:
                yield Step("remove", q, b, nq, nb, cls=i)

    def step_cost(self, s: Step) -> float:
        if s.kind == "move":
            assert s.prop is not None, "a move names the proposition it delivers"
            return self.cost_of[s.prop]
        return self.remove_cost if s.kind == "remove" else 0.0

    def is_goal(self, q: int, b: Counts) -> bool:
        """A live accepting state with W^B at the end of a round of some way."""
        return q in self.aut.live_accepting and self.lots.is_goal(b)

    def successor_pairs(self, q: int, b: Counts) -> Iterator[Pair]:
        """The pairs one step away (what the tree update adds, Alg. 3 lines 3-6)."""
        final = self.lots.bound
        for _, p, ci, nq in self._trans[q]:
            if p is None:
                yield (nq, b)
            elif b[ci] < final[ci]:
                yield (nq, b[:ci] + (b[ci] + 1,) + b[ci + 1 :])
        for ci, x in enumerate(b):
            if x:
                nb = b[:ci] + (x - 1,) + b[ci + 1 :]
                for nq in self._empty[q]:
                    yield (nq, nb)

    def letter_between(self, a: Pair, b: Pair) -> Letter:
        """The executable letter of one step ``a → b`` (a delivery gives ``{p}``, else ∅)."""
        (q, x), (nq, y) = a, b
        for p, ci in self.lots.prop_class.items():
            if y == x[:ci] + (x[ci] + 1,) + x[ci + 1 :] and nq in self.aut.successors(
                q, frozenset({p})
            ):
                return frozenset({p})
        if nq in self.aut.successors(q, EMPTY):
            return EMPTY
        raise ValueError(f"no executable step from {a} to {b}")

    def plan_from(
        self,
        q: int,
        b: Counts,
        cap: Counts | None = None,
        stock: Counts | None = None,
        *,
        relaxed: bool = False,
    ) -> Plan | None:
        """Cheapest run from ``(q, b)`` to a live accepting ``q_F`` with W^B at the end of a
        round of some accepting way (``s^B_final`` or another way's, `Lots.goals`), or None.

        ``cap``: the objects of each class that exist (W^A, W^B and the hand): W^B never
        holds more, so a way whose class was taken away is not planned. ``stock``: the
        objects in W^A, given with Zhou et al.'s action set (no return W^B→W^A): an object
        taken out of W^B is discarded, so the run delivers at most ``stock[i]`` objects of
        class ``i`` (a search node then carries what is left; a stock of at least
        ``|Q|·|S^B|`` cannot run out along a cheapest run and is not tracked). A* on pairs
        (key: cost + h, then the deeper node, then fewer steps); an exhausted search marks
        every node it closed as dead for that ``cap`` and ``stock`` (none of them can
        complete the task), so later calls prune them. ``relaxed``: a goal may also be a
        state from which the round's cycle (``round_cycle``) repeated forever is accepted
        — a person delivered part of a recurring task early (``GF``), so the round ends with
        W^B complete before the automaton is back in ``q_F``; the plan's cycle is then the
        round's.
        """
        lots = self.lots
        bound = lots.bound if cap is None else tuple(map(min, lots.bound, cap))
        goals = tuple(gl for gl in lots.goals if all(map(int.__le__, gl, bound)))
        if stock is not None:
            plenty = self.aut.num_states * lots.num_wb_states()
            stock = tuple(-1 if n >= plenty else n for n in stock)  # -1: not tracked
            if all(n < 0 for n in stock):
                stock = None
        if cap is None and stock is None and not relaxed:
            dead = self.dead
        else:
            dead = self._dead_capped.setdefault((bound, stock, relaxed), set())
        if not goals or not lots.in_box(b) or (q, b, stock) in dead:
            return None
        goal_set = frozenset(goals)
        # one goal: the heuristic changes by one class's cheapest cost per step (exact sums)
        single = goals == (bound,)
        hfun = self.heuristic
        final, live = bound, self.aut.live_accepting
        if relaxed:
            live = live | self.cycle_ok()
        trans, empty, min_cost, rc = self._trans, self._empty, self._min_cost, self.remove_cost
        start = (q, b, stock)
        tie = itertools.count()
        g: dict = {start: (0.0, 0)}
        parent: dict = {}
        h0 = hfun(b, goals)
        heap = [(h0, 0.0, 0, next(tie), start, h0)]
        closed: set = set()
        push = heapq.heappush
        while heap:
            _, negc, nsteps, _, node, h = heapq.heappop(heap)
            cost = -negc
            if node in closed or g[node] != (cost, nsteps):
                continue
            closed.add(node)
            self.expanded += 1
            nq_, nb_, st = node
            if nq_ in live and nb_ in goal_set:
                return self._plan(start, node, parent, cost)
            ns = nsteps + 1
            succ = []
            for c, p, ci, nq in trans[nq_]:
                if p is None:
                    succ.append(((nq, nb_, st), c, h, None, -1))
                elif nb_[ci] < final[ci]:
                    nst = st
                    if st is not None and st[ci] >= 0:
                        if st[ci] == 0:
                            continue
                        nst = st[:ci] + (st[ci] - 1,) + st[ci + 1 :]
                    nb = nb_[:ci] + (nb_[ci] + 1,) + nb_[ci + 1 :]
                    nh = h - min_cost[ci] if single else hfun(nb, goals)
                    succ.append(((nq, nb, nst), c, nh, p, ci))
            for ci, x in enumerate(nb_):
                if x:
                    nb = nb_[:ci] + (x - 1,) + nb_[ci + 1 :]
                    nh = h + min_cost[ci] if single else hfun(nb, goals)
                    for nq in empty[nq_]:
                        succ.append(((nq, nb, st), rc, nh, None, ci))
            for nxt, c, nh, p, ci in succ:
                if nxt in dead or nxt in closed:
                    continue
                nk = (cost + c, ns)
                old = g.get(nxt)
                if old is None or nk < old:
                    g[nxt] = nk
                    parent[nxt] = (node, p, ci)
                    push(heap, (nk[0] + nh, -nk[0], ns, next(tie), nxt, nh))
        dead |= closed
        return None

    def _plan(self, start: tuple, node: tuple, parent: dict, cost: float) -> Plan:
        steps: list[Step] = []
        while node != start:
            prev, p, ci = parent[node]
            if p is not None:
                steps.append(Step("move", prev[0], prev[1], node[0], node[1], prop=p, cls=ci))
            elif ci >= 0:
                steps.append(Step("remove", prev[0], prev[1], node[0], node[1], cls=ci))
            else:
                steps.append(Step("idle", prev[0], prev[1], node[0], node[1]))
            node = prev
        steps.reverse()
        end_q = steps[-1].q_next if steps else start[0]
        cycle = self.cycle_from(end_q) if end_q in self.aut.live_accepting else self.round_cycle
        return Plan((start[0], start[1]), steps, list(cycle), cost)

    def cycle_from(self, qf: int) -> list[Letter]:
        """Cheapest non-empty accepting cycle ``q_F → q_F`` (`cheapest_cycle`, cached)."""
        if qf not in self._cycles:
            self._cycles[qf] = cheapest_cycle(self.aut, self.cost_of, qf)
        return self._cycles[qf]


# ---------------------------------------------------------------------------- table T
@dataclass(frozen=True)
class Entry:
    """``T[s^B]``: the action to take in W^B state ``b`` and the automaton state it pairs with.

    ``kind``: ``move`` (proposition ``prop`` delivers class ``cls``), ``remove`` (one object of
    class ``cls`` out of W^B) or ``done`` (the round of the task is complete). ``index`` is the
    entry's position in the planned run.
    """

    kind: str
    q: int
    b: Counts
    index: int
    prop: str | None = None
    cls: int | None = None
    q_next: int | None = None
    b_next: Counts | None = None

    def label(self, lots: Lots) -> str:
        if self.kind == "move":
            return self.prop or ""
        if self.kind == "remove":
            assert self.cls is not None, "a remove names the class it takes out"
            return f"remove:{lots.classes[self.cls]}"
        return "done"

    @property
    def letter(self) -> Letter:
        if self.kind != "move":
            return EMPTY
        assert self.prop is not None, "a move names the proposition it delivers"
        return frozenset({self.prop})


@dataclass
class Table:
    """The knowledge base ``T``: W^B counts → :class:`Entry` (a plain dict on tuples).

    ``run`` keeps the entries in plan order. A run may pass the same W^B state twice (take an
    object out of W^B, deliver it again later, for the automaton's order); the dict keeps the
    first visit, and the controller follows ``run`` while W^B is where the plan expects it.
    """

    lots: Lots
    entries: dict[Counts, Entry] = field(default_factory=dict)
    run: list[Entry] = field(default_factory=list)

    @classmethod
    def from_plan(cls, plan: Plan, lots: Lots) -> Table:
        """Alg. 2 lines 2-8: ``(s^B_i, a_i)`` for each non-idle step, then ``done`` at the end.

        Idle steps (letter ∅ with nothing moving) only advance the automaton; the next action
        taken from the same W^B state is recorded with the automaton state it is taken in.
        """
        t = cls(lots)
        for s in plan.steps:
            if s.kind == "idle":
                continue
            e = Entry(s.kind, s.q, s.b, len(t.run), s.prop, s.cls, s.q_next, s.b_next)
            t.run.append(e)
            t.entries.setdefault(s.b, e)
        q_end, b_end = plan.end
        e = Entry("done", q_end, b_end, len(t.run))
        t.run.append(e)
        t.entries.setdefault(b_end, e)
        return t

    def get(self, b: Counts) -> Entry | None:
        """The table hit of Alg. 1 line 12: one dict lookup."""
        return self.entries.get(b)

    def next_after(self, e: Entry, b: Counts) -> Entry | None:
        """The plan's next entry after ``e`` when W^B is ``b`` as the plan expects, else None."""
        i = e.index + 1
        if i < len(self.run) and self.run[i].b == b:
            return self.run[i]
        return None

    def __contains__(self, b: Counts) -> bool:
        return b in self.entries

    def __len__(self) -> int:
        return len(self.entries)

    def as_mapping(self) -> dict[Counts, str]:
        """W^B state → proposition name, ``remove:<class>`` or ``done`` (for verification)."""
        return {b: e.label(self.lots) for b, e in self.entries.items()}

    def rows(self) -> list[dict]:
        """JSON-ready rows in plan order: W^B counts by class, automaton state, action."""
        return [
            {"w_b": self.lots.named(e.b), "q": e.q, "action": e.label(self.lots)} for e in self.run
        ]


def follow_table(table: Table, b: Counts) -> list[Letter]:
    """Follow ``T`` from W^B state ``b`` with no interference: the letters the robot produces.

    Starts at ``T[b]`` and walks the planned run (each action leads to the W^B state of the
    next entry); deliveries give ``{p}``, removals from W^B give ∅; stops at ``done``. Raises
    ``KeyError`` when ``b`` is not in the table.
    """
    e = table.entries[b]
    letters: list[Letter] = []
    while e.kind != "done":
        letters.append(e.letter)
        e = table.run[e.index + 1]
    return letters


# ---------------------------------------------------------------------------- tree TR
class Tree:
    """The search tree ``TR`` of pairs ``(q, s^B)`` (Alg. 1 line 2, Alg. 2 line 7, Alg. 3).

    Children of a pair: every executable letter (``(δ(q, σ), δ_t(s^B, a(σ)))``) and, because
    dis_2 can take objects away, every single removal from W^B (letter ∅). ``mode``: ``random``
    (Alg. 3 as written: pick a random unexpanded node; seedable) or ``bfs`` (deterministic).
    """

    def __init__(self, planner: Planner, root: Pair, *, mode: str = "bfs", seed: int = 0):
        if mode not in ("bfs", "random"):
            raise ValueError(f"unknown tree mode {mode!r}")
        self.planner = planner
        self.mode = mode
        self.rng = random.Random(seed)
        self.parent: dict[Pair, Pair | None] = {root: None}
        self.by_b: dict[Counts, list[int]] = {root[1]: [root[0]]}
        self._frontier: deque[Pair] | list[Pair] = deque([root]) if mode == "bfs" else [root]
        self.expansions = 0

    def __len__(self) -> int:
        return len(self.parent)

    def __contains__(self, pair: Pair) -> bool:
        return pair in self.parent

    def __deepcopy__(self, memo: dict) -> Tree:
        """Copy the pairs, frontier and random state; share the planner (and its automaton)."""
        new = Tree.__new__(Tree)
        memo[id(self)] = new
        new.planner, new.mode, new.expansions = self.planner, self.mode, self.expansions
        new.rng = random.Random()
        new.rng.setstate(self.rng.getstate())
        new.parent = dict(self.parent)
        new.by_b = {b: list(qs) for b, qs in self.by_b.items()}
        new._frontier = type(self._frontier)(self._frontier)
        return new

    def add(self, pair: Pair, parent: Pair | None) -> bool:
        if pair in self.parent:
            return False
        self.parent[pair] = parent
        self.by_b.setdefault(pair[1], []).append(pair[0])
        self._frontier.append(pair)
        return True

    def add_plan(self, plan: Plan) -> None:
        """Alg. 2 line 7: record the pairs ``(q_i, s^B_i)`` of a planned run."""
        prev = plan.start
        if prev not in self.parent:
            self.add(prev, None)
        for s in plan.steps:
            nxt = (s.q_next, s.b_next)
            self.add(nxt, prev)
            prev = nxt

    def letters_to(self, pair: Pair) -> list[Letter]:
        """Letters of the tree path from the root to ``pair``: a word reaching its ``q``."""
        path = [pair]
        up = self.parent[pair]
        while up is not None:
            path.append(up)
            up = self.parent[up]
        path.reverse()
        return [self.planner.letter_between(a, b) for a, b in zip(path, path[1:], strict=False)]

    def _pop(self) -> Pair:
        if self.mode == "bfs":
            return self._frontier.popleft()  # type: ignore[union-attr]
        f = self._frontier
        i = self.rng.randrange(len(f))
        f[i], f[-1] = f[-1], f[i]
        return f.pop()

    def _best(
        self,
        b: Counts,
        cap: Counts | None = None,
        stock: Counts | None = None,
        allowed: Collection[int] | None = None,
        *,
        relaxed: bool = False,
    ) -> tuple[int, Plan] | None:
        best: tuple[int, Plan] | None = None
        qs = self.by_b.get(b, ()) if allowed is None else allowed
        for q in sorted(qs):
            plan = self.planner.plan_from(q, b, cap, stock, relaxed=relaxed)
            if plan is not None and (best is None or plan.cost < best[1].cost):
                best = (q, plan)
        return best

    def update(
        self,
        b: Counts,
        cap: Counts | None = None,
        stock: Counts | None = None,
        *,
        allowed: Collection[int] | None = None,
    ) -> tuple[int, Plan] | None:
        """Alg. 3: grow TR until it holds a pair ``(q, b)`` that can complete the task.

        Returns that automaton state and its plan (the cheapest among the pairs with ``b``
        found so far, to the end of a round of any accepting way, with at most ``cap``
        objects per class, delivering at most ``stock`` from W^A when given), or None once
        every reachable pair has been generated without
        one — the W^B state cannot lead to completion (Alg. 1 line 23: wait).

        ``allowed``: the automaton states the run's word can be in (`tamp.lots.word`). Given,
        the pairs ``(q, b)`` for those states are added and planned from directly — a pair
        with another ``q`` would stand for a history that did not happen.
        """
        if not self.planner.lots.in_box(b):
            return None
        if allowed is not None:
            for q in sorted(allowed):
                self.add((q, b), None)
            strict = self._best(b, cap, stock, allowed)
            loose = self._best(b, cap, stock, allowed, relaxed=True)
            if strict is None or (loose is not None and loose[1].cost < strict[1].cost):
                return loose
            return strict
        found = self._best(b, cap, stock)
        while found is None and self._frontier:
            node = self._pop()
            self.expansions += 1
            hit = False
            for child in self.planner.successor_pairs(*node):
                if self.add(child, node) and child[1] == b:
                    hit = True
            if hit:
                found = self._best(b, cap, stock)
        return found
