"""Reading automata: edges, copies started elsewhere, lasso acceptance, live states.

Lasso acceptance is Spot's product emptiness ``L(A) ∩ {w} ≠ ∅`` with the word automaton of
``spot.parse_word`` over the automaton's own BDD dictionary.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Iterator, Sequence

import spot

from tamp.ltl.letters import (
    Automaton,
    Bdd,
    Letter,
    bdd_letter,
    letter_bdd,
    meets,
    word_automaton,
)


def edges(aut: Automaton, state: int | None = None) -> Iterator[tuple[int, int, Bdd]]:
    """``(src, dst, cond)`` of every edge (of ``state`` only when given), in Spot's order."""
    states = range(aut.num_states()) if state is None else (state,)
    for s in states:
        for e in aut.out(s):
            yield e.src, e.dst, e.cond


def accepting_states(aut: Automaton) -> frozenset[int]:
    return frozenset(s for s in range(aut.num_states()) if aut.state_is_accepting(s))


def copy(aut: Automaton) -> Automaton:
    """A modifiable copy sharing the BDD dictionary (cached automata must not be modified)."""
    return spot.make_twa_graph(aut, spot.twa_prop_set.all())


def started_at(aut: Automaton, state: int) -> Automaton:
    """A copy of ``aut`` whose initial state is ``state``."""
    out = copy(aut)
    out.set_init_state(state)
    return out


def register_aps(aut: Automaton, names: Iterable[str]) -> None:
    """Add propositions to ``aut``'s alphabet (a modifiable automaton: see `copy`)."""
    for name in names:
        aut.register_ap(name)


def accepts_lasso(
    aut: Automaton,
    prefix: Sequence[Iterable[str]],
    cycle: Sequence[Iterable[str]],
    *,
    start: int | None = None,
) -> tuple[bool, int]:
    """Is ``prefix · cycle^ω`` accepted (from ``start``, default the initial state)?

    Returns the verdict and the number of product states explored.
    """
    a = aut if start is None else started_at(aut, start)
    prod = spot.product(a, word_automaton(a, prefix, cycle))
    return (not prod.is_empty()), prod.num_states()


def live_states(aut: Automaton, *, finite: bool) -> set[int]:
    """States from which some continuation is accepted.

    Büchi: reachable states in an SCC that can reach an accepting cycle (Spot's
    ``is_useful_scc``; asking it about an unreachable state crashes Spot 2.13).
    Finite: states that reach an accepting (final) state, by backward search.
    """
    n = aut.num_states()
    if not finite:  # states not reachable from the initial one have no SCC (scc_of: -1)
        si = spot.scc_info(aut)
        return {s for s in range(n) if si.reachable_state(s) and si.is_useful_scc(si.scc_of(s))}
    preds: dict[int, list[int]] = {s: [] for s in range(n)}
    for src, dst, _ in edges(aut):
        preds[dst].append(src)
    live = {s for s in range(n) if aut.state_is_accepting(s)}
    queue = deque(live)
    while queue:
        s = queue.popleft()
        for p in preds[s]:
            if p not in live:
                live.add(p)
                queue.append(p)
    return live


def accepting_continuation(
    aut: Automaton, state: int, *, finite: bool
) -> tuple[list[Letter], list[Letter] | None]:
    """An accepted word read from ``state``: (letters, cycle or None).

    Finite: breadth-first shortest path to a final state (cycle None; may be empty when
    ``state`` is final). Büchi: Spot's ``accepting_word`` from a copy started at ``state``.
    """
    if finite:
        parent: dict[int, tuple[int, Bdd] | None] = {state: None}
        queue = deque([state])
        while queue:
            s = queue.popleft()
            if aut.state_is_accepting(s):
                path = []
                step = parent[s]
                while step is not None:
                    s, cond = step
                    path.append(bdd_letter(aut, cond))
                    step = parent[s]
                return list(reversed(path)), None
            for _, dst, cond in edges(aut, s):
                if dst not in parent:
                    parent[dst] = (s, cond)
                    queue.append(dst)
        raise ValueError("no accepting state reachable")
    word = started_at(aut, state).accepting_word()
    if word is None:
        raise ValueError("no accepting run from this state")
    word.simplify()
    return [bdd_letter(aut, b) for b in word.prefix], [bdd_letter(aut, b) for b in word.cycle]


class Stepper:
    """Reads letters on an automaton, keeping the set of reachable *live* states.

    Successor sets are memoised per (state, letter), so a long trace over a small automaton
    costs one BDD test per automaton edge and distinct letter.
    """

    def __init__(self, aut: Automaton, *, finite: bool):
        self.aut = aut
        self.finite = finite
        self.live = live_states(aut, finite=finite)
        self._bdds: dict[Letter, Bdd] = {}
        self._succ: dict[tuple[int, Letter], frozenset[int]] = {}
        self._aps = frozenset(ap.ap_name() for ap in aut.ap())
        self.visited = 0

    def key(self, letter: Iterable[str]) -> Letter:
        return frozenset(letter) & self._aps

    def initial(self) -> frozenset[int]:
        s = self.aut.get_init_state_number()
        return frozenset({s} & self.live)

    def step(self, states: frozenset[int], letter: Iterable[str]) -> frozenset[int]:
        key = self.key(letter)
        b = self._bdds.get(key)
        if b is None:
            b = self._bdds[key] = letter_bdd(self.aut, key)
        out: set[int] = set()
        for s in states:
            succ = self._succ.get((s, key))
            if succ is None:
                succ = frozenset(
                    dst
                    for _, dst, cond in edges(self.aut, s)
                    if dst in self.live and meets(cond, b)
                )
                self._succ[(s, key)] = succ
            out |= succ
        self.visited += len(out)
        return frozenset(out)
