"""Letters (sets of true propositions) as BDDs and as Spot word text; lasso words.

A letter is a *full* valuation: propositions of the automaton that the letter does not name
are false. Names the automaton does not use are ignored (the runtime-monitor convention).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TypeAlias

import spot
import spot.impl

# Spot's BDD module: ``import spot`` puts it on ``sys.path`` as ``buddy``; naming it through
# ``spot.impl`` (which imports it) gives the same module object and lets a type checker find it.
from spot.impl import buddy

from tamp.ltl.formula import atom

Letter = frozenset[str]
EMPTY: Letter = frozenset()
#: a BDD (Spot's edge conditions); opaque to every other layer
Bdd: TypeAlias = buddy.bdd
#: Spot's automaton. Spot defines its classes in ``spot.impl`` and extends them in ``spot``
#: under the same name (``Automaton is spot.impl.twa_graph``); a type checker sees the
#: methods only on the ``spot.impl`` class.
Automaton: TypeAlias = spot.impl.twa_graph


def aps(aut: Automaton) -> list[str]:
    """The automaton's propositions, in its own order."""
    return [ap.ap_name() for ap in aut.ap()]


def letter_bdd(aut: Automaton, true_props: Iterable[str]) -> Bdd:
    """The BDD of the full valuation: ``true_props`` true, every other proposition false."""
    d = aut.get_dict()
    true_props = set(true_props)
    b = buddy.bddtrue
    for ap in aut.ap():
        v = d.varnum(ap)
        b = b & (buddy.bdd_ithvar(v) if ap.ap_name() in true_props else buddy.bdd_nithvar(v))
    return b


def bdd_letter(aut: Automaton, cond: Bdd) -> Letter:
    """One full valuation inside ``cond`` (free propositions false: the smallest that fits)."""
    d = aut.get_dict()
    cube = buddy.bdd_satone(cond)
    out = set()
    for ap in aut.ap():
        if (cube & buddy.bdd_nithvar(d.varnum(ap))) == buddy.bddfalse:
            out.add(ap.ap_name())
    return frozenset(out)


def meets(a: Bdd, b: Bdd) -> bool:
    """Some valuation satisfies both (``a & b`` is not false)."""
    return (a & b) != buddy.bddfalse


def label(aut: Automaton, cond: Bdd) -> str:
    """An edge condition as readable formula text (``p1 & !p2``)."""
    return spot.bdd_format_formula(aut.get_dict(), cond)


def letter_text(props: Iterable[str], names: Iterable[str]) -> str:
    """A letter as Spot word syntax over ``names``: ``p1 & !p2`` (``1`` when none)."""
    return _Letters(names).text(props)


class _Letters:
    """Word-syntax text of letters over fixed names (quoted once, each letter written once)."""

    def __init__(self, names: Iterable[str]):
        self.quoted = [(n, atom(n)) for n in sorted(names)]
        self.memo: dict[Letter, str] = {}

    def text(self, props: Iterable[str]) -> str:
        key = frozenset(props)
        out = self.memo.get(key)
        if out is None:
            parts = [q if n in key else f"!{q}" for n, q in self.quoted]
            out = self.memo[key] = " & ".join(parts) if parts else "1"
        return out


def word_text(prefix: Sequence[Iterable[str]], cycle: Sequence[Iterable[str]], names) -> str:
    """Spot's ω-word syntax for ``prefix · cycle^ω`` (full valuations over ``names``)."""
    w = _Letters(names)
    pre = "; ".join(w.text(x) for x in prefix)
    cyc = "cycle{" + "; ".join(w.text(x) for x in cycle) + "}"
    return f"{pre}; {cyc}" if pre else cyc


def word_automaton(
    aut: Automaton, prefix: Sequence[Iterable[str]], cycle: Sequence[Iterable[str]]
) -> Automaton:
    """The automaton of the lasso over ``aut``'s propositions and BDD dictionary."""
    if not cycle:
        raise ValueError("a lasso needs a non-empty cycle")
    return spot.parse_word(word_text(prefix, cycle, aps(aut)), aut.get_dict()).as_automaton()
