"""LTL formulas and their automata, on Spot: parsing, translation, letters as BDDs.

Everything Spot-specific the checkers need lives here, so that the rest of the package
talks about formulas, automaton states and letters (sets of true propositions).

Facts this module relies on (FIELD_NOTES, Spot 2.13):
- ``spot.translate(f, 'BA')`` silently loses state-based acceptance in this build, so
  Büchi automata are made with ``spot.translate(f, 'Buchi', 'SBAcc', 'small', 'high')``.
- LTLf (finite traces) goes through ``spot.from_ltlf(f, 'alive')`` and
  ``spot.to_finite(aut, 'alive')``: the result is an automaton whose accepting states are
  the final states of an NFA. In Spot's LTLf, ``X f`` is the *weak* next (true at the last
  position) and ``X[!] f`` the strong next; LTLf traces are non-empty, so the empty trace
  satisfies no formula.
- A translation with many top-level conjuncts can blow up (``F g0 & … & F g11`` has 2^12
  states and its negation takes ~12 s), while every conjunct alone is tiny. The checkers
  therefore check conjunct by conjunct where that is sound: a word satisfies ``c1 & c2``
  iff it satisfies both, and every path of a system satisfies ``c1 & c2`` iff every path
  satisfies each.
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Iterable
from functools import lru_cache

import buddy
import spot

from tamp.errors import InputError

#: ``name <= 3`` style comparisons are not LTL syntax; they become one quoted proposition
#: (``"holding_count<=1"``) whose truth the labelling of a system computes.
_COMPARISON = re.compile(r"(?<![\"\w])([A-Za-z_][\w.]*)\s*(<=|>=|==|!=|<|>)\s*(-?\d+)(?![\w\"])")
COMPARISON_AP = re.compile(r"^([A-Za-z_][\w.]*)(<=|>=|==|!=|<|>)(-?\d+)$")

#: Above this many top-level conjuncts the whole-formula automaton is not built for
#: explanations (it can be exponential in the number of conjuncts); see module docstring.
MAX_CONJUNCTS_FOR_WHOLE = 8


def _quote_comparisons(text: str) -> str:
    return _COMPARISON.sub(lambda m: f'"{m.group(1)}{m.group(2)}{m.group(3)}"', text)


def parse_formula(text: str, *, field: str = "formula", file: str | None = None) -> spot.formula:
    """Parse an LTL formula in Spot's syntax; a syntax error is bad input (exit 2).

    Comparisons ``name OP integer`` (e.g. ``holding_count <= 1``) are accepted and turned
    into one atomic proposition, so properties over counters read naturally.
    """
    if not isinstance(text, str) or not text.strip():
        raise InputError("empty formula", file=file, field=field)
    try:
        return spot.formula(_quote_comparisons(text))
    except SyntaxError as exc:
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        reason = next((ln for ln in lines if not ln.startswith((">>>", "^"))), "syntax error")
        raise InputError(
            f"formula {text!r} does not parse: {reason}", file=file, field=field
        ) from None


def ap_names(f: spot.formula) -> list[str]:
    """The atomic propositions of ``f``, as plain names, sorted."""
    return sorted(ap.ap_name() for ap in spot.atomic_prop_collect(f))


def conjuncts(f: spot.formula) -> list[spot.formula]:
    """Top-level conjuncts of ``f`` (``[f]`` when ``f`` is not a conjunction)."""
    if f.kind() == spot.op_And:
        return [c for c in f]
    return [f]


@lru_cache(maxsize=512)
def _buchi(text: str) -> spot.twa_graph:
    return spot.translate(spot.formula(text), "Buchi", "SBAcc", "small", "high")


def buchi(f: spot.formula) -> spot.twa_graph:
    """State-based Büchi automaton of ``f`` (cached by formula text; do not mutate)."""
    return _buchi(str(f))


@lru_cache(maxsize=512)
def _finite(text: str) -> spot.twa_graph:
    g = spot.from_ltlf(spot.formula(text), "alive")
    return spot.to_finite(spot.translate(g, "Buchi", "SBAcc", "small", "high"), "alive")


def finite_automaton(f: spot.formula) -> spot.twa_graph:
    """NFA of ``f`` read with LTLf semantics: accepting states are final (cached)."""
    return _finite(str(f))


# -- letters --------------------------------------------------------------------------------


def letter_bdd(aut: spot.twa_graph, true_props: Iterable[str]) -> buddy.bdd:
    """The BDD of a *full* valuation of the automaton's propositions.

    Propositions of the automaton not in ``true_props`` are false; names the automaton
    does not use are ignored (runtime-monitor convention).
    """
    d = aut.get_dict()
    true_props = set(true_props)
    b = buddy.bddtrue
    for ap in aut.ap():
        v = d.varnum(ap)
        b = b & (buddy.bdd_ithvar(v) if ap.ap_name() in true_props else buddy.bdd_nithvar(v))
    return b


def bdd_letter(aut: spot.twa_graph, cond: buddy.bdd) -> frozenset[str]:
    """One full valuation inside ``cond``, as the set of its true propositions.

    Propositions left free by ``cond`` are set false (the smallest letter that fits).
    """
    d = aut.get_dict()
    cube = buddy.bdd_satone(cond)
    out = set()
    for ap in aut.ap():
        v = d.varnum(ap)
        if (cube & buddy.bdd_nithvar(v)) == buddy.bddfalse:
            out.add(ap.ap_name())
    return frozenset(out)


def formula_letter_text(props: Iterable[str], aps: Iterable[str]) -> str:
    """A letter as Spot word syntax over ``aps``: ``p1 & !p2`` (``1`` when ``aps`` is empty)."""
    props = set(props)
    parts = []
    for name in sorted(aps):
        atom = str(spot.formula.ap(name))
        parts.append(atom if name in props else f"!{atom}")
    return " & ".join(parts) if parts else "1"


# -- automaton analysis ---------------------------------------------------------------------


def live_states(aut: spot.twa_graph, *, finite: bool) -> set[int]:
    """States from which some continuation is accepted.

    Büchi: states in an SCC that can reach an accepting cycle (Spot's ``is_useful_scc``).
    Finite: states that reach an accepting (final) state, by backward search.
    """
    n = aut.num_states()
    if not finite:
        si = spot.scc_info(aut)
        return {s for s in range(n) if si.is_useful_scc(si.scc_of(s))}
    preds: dict[int, list[int]] = {s: [] for s in range(n)}
    for s in range(n):
        for e in aut.out(s):
            preds[e.dst].append(s)
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
    aut: spot.twa_graph, state: int, *, finite: bool
) -> tuple[list[frozenset[str]], list[frozenset[str]] | None]:
    """A shortest-effort accepted word read from ``state``: (letters, cycle or None).

    Finite: breadth-first shortest path to a final state (cycle None; may be empty when
    ``state`` is final). Büchi: Spot's ``accepting_word`` from a copy started at ``state``.
    """
    if finite:
        parent: dict[int, tuple[int, buddy.bdd] | None] = {state: None}
        queue = deque([state])
        while queue:
            s = queue.popleft()
            if aut.state_is_accepting(s):
                path = []
                while parent[s] is not None:
                    p, cond = parent[s]
                    path.append(bdd_letter(aut, cond))
                    s = p
                return list(reversed(path)), None
            for e in aut.out(s):
                if e.dst not in parent:
                    parent[e.dst] = (s, e.cond)
                    queue.append(e.dst)
        raise ValueError("no accepting state reachable")
    copy = spot.make_twa_graph(aut, spot.twa_prop_set.all())
    copy.set_init_state(state)
    word = copy.accepting_word()
    if word is None:
        raise ValueError("no accepting run from this state")
    word.simplify()
    return [bdd_letter(aut, b) for b in word.prefix], [bdd_letter(aut, b) for b in word.cycle]


class Stepper:
    """Reads letters on an automaton, keeping the set of reachable *live* states.

    Successor sets are memoised per (state, letter), so a long trace over a small automaton
    costs one BDD test per automaton edge and distinct letter.
    """

    def __init__(self, aut: spot.twa_graph, *, finite: bool):
        self.aut = aut
        self.finite = finite
        self.live = live_states(aut, finite=finite)
        self._bdds: dict[frozenset[str], buddy.bdd] = {}
        self._succ: dict[tuple[int, frozenset[str]], frozenset[int]] = {}
        self._aps = frozenset(ap.ap_name() for ap in aut.ap())
        self.visited = 0

    def key(self, letter: Iterable[str]) -> frozenset[str]:
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
                    e.dst
                    for e in self.aut.out(s)
                    if e.dst in self.live and (e.cond & b) != buddy.bddfalse
                )
                self._succ[(s, key)] = succ
            out |= succ
        self.visited += len(out)
        return frozenset(out)
