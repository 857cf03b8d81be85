"""Kripke structures (``spot.make_kripke_graph``) and their runs accepted by an automaton.

Used by the model checker: a system satisfies ``f`` on all paths iff its Kripke structure has
no run accepted by the automaton of ``!f``; Spot's ``intersecting_run`` returns one as a
lasso of states.
"""

from __future__ import annotations

from collections.abc import Sequence

import spot
from spot.impl import buddy  # the module ``import buddy`` names (see tamp.ltl.letters)

from tamp.ltl.formula import Formula
from tamp.ltl.letters import Automaton, Bdd, Letter


def kripke(
    labels: Sequence[Letter],
    succ: Sequence[Sequence[int]],
    aps: Sequence[str],
    aut: Automaton,
    *,
    init: int = 0,
    stutter: frozenset[int] | set[int] | None = None,
) -> spot.kripke_graph:
    """The Kripke structure of states ``labels`` / ``succ`` over ``aps``, in ``aut``'s dict.

    A state without successors gets a self-loop (stutter extension), except the states
    not in ``stutter`` when ``stutter`` is given.
    """
    bdict = aut.get_dict()
    k = spot.make_kripke_graph(bdict)
    varnums = {}
    for name in aps:
        f = Formula.ap(name)
        k.register_ap(f)
        varnums[name] = bdict.varnum(f)
    cache: dict[Letter, Bdd] = {}
    keep = frozenset(aps)
    for label in labels:
        key = label & keep
        b = cache.get(key)
        if b is None:
            b = buddy.bddtrue
            for name, v in varnums.items():
                b = b & (buddy.bdd_ithvar(v) if name in key else buddy.bdd_nithvar(v))
            cache[key] = b
        k.new_state(b)
    for s, out in enumerate(succ):
        if not out and (stutter is None or s in stutter):
            k.new_edge(s, s)
        for d in dict.fromkeys(out):
            k.new_edge(s, d)
    k.set_init_state(init)
    return k


def intersecting_lasso(k: spot.kripke_graph, aut: Automaton) -> tuple[list[int], list[int]] | None:
    """A run of ``k`` accepted by ``aut`` as (prefix, cycle) state numbers, shortest form."""
    run = k.intersecting_run(aut)
    if run is None:
        return None
    prefix = [k.state_number(st.s) for st in run.prefix]
    cycle = [k.state_number(st.s) for st in run.cycle]
    while prefix and prefix[-1] == cycle[-1]:  # shortest equivalent lasso
        prefix.pop()
        cycle = cycle[-1:] + cycle[:-1]
    return prefix, cycle
