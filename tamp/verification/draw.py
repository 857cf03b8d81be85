"""Drawing a trace on the automaton it is checked against (Graphviz DOT; ``tamp-verify --svg``).

The picture shows what the checker does: starting in the initial state, every letter
moves the set of reachable states along the edges whose label the letter satisfies.
Edges taken into states that can still reach acceptance are green; an edge taken into a
dead state (no accepting continuation) is red, and the step where no live state remains is
the end of the shortest bad prefix. Dead states are grey, accepting states double circles.
A lasso is unrolled for two turns of its cycle.
"""

from __future__ import annotations

from tamp import ltl
from tamp.ltl.automata import edges, live_states
from tamp.ltl.formula import Formula, as_formula
from tamp.ltl.letters import aps, label, letter_bdd, meets
from tamp.verification.words import Word


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')


def trace_dot(formula: str | Formula, word: Word, *, finite: bool = False, title: str = "") -> str:
    """DOT text of the automaton of ``formula`` with ``word``'s walk highlighted."""
    f = as_formula(formula)
    aut = ltl.translate(f, ltl.FINITE if finite else ltl.BUCHI)
    live = live_states(aut, finite=finite)
    letters = list(word.prefix)
    if word.cycle is not None:
        letters += list(word.cycle) * 2
    init = aut.get_init_state_number()
    cur = {init} & live
    green: set[tuple[int, int, str]] = set()
    red: set[tuple[int, int, str]] = set()
    visited = set(cur)
    failed: tuple[list[int], frozenset[str]] | None = None
    for letter in letters:
        b = letter_bdd(aut, letter)
        nxt = set()
        for s in cur:
            for src, dst, cond in edges(aut, s):
                if not meets(cond, b):
                    continue
                key = (src, dst, label(aut, cond))
                if dst in live:
                    green.add(key)
                    nxt.add(dst)
                else:
                    red.add(key)
        visited |= nxt
        if not nxt:
            failed = (sorted(cur), letter)
            break
        cur = nxt
    lines = [
        "digraph trace {",
        "  rankdir=LR;",
        f'  label="{_esc(title or str(f))}"; labelloc=t;',
        '  node [fontname="Helvetica"]; edge [fontname="Helvetica", fontsize=10];',
        '  start [shape=point, label=""];',
    ]
    for s in range(aut.num_states()):
        shape = "doublecircle" if aut.state_is_accepting(s) else "circle"
        if s not in live:
            style = 'style=filled, fillcolor="#dddddd", fontcolor="#777777"'
        elif s in visited:
            style = 'style=filled, fillcolor="#c8f0c8"'
        else:
            style = ""
        lines.append(f'  q{s} [shape={shape}, label="q{s}"{", " + style if style else ""}];')
    lines.append(f"  start -> q{init};")
    for src, dst, cond in edges(aut):
        text = label(aut, cond)
        key = (src, dst, text)
        attrs = f'label="{_esc(text)}"'
        if key in red:
            attrs += ', color="#d62728", fontcolor="#d62728", penwidth=2.5'
        elif key in green:
            attrs += ', color="#2ca02c", penwidth=2.5'
        else:
            attrs += ', color="#999999", fontcolor="#999999"'
        lines.append(f"  q{src} -> q{dst} [{attrs}];")
    if failed is not None:  # the letter that leaves every accepting continuation
        states, letter = failed
        text = " & ".join(a if a in letter else f"!{a}" for a in aps(aut)) or "1"
        lines.append(
            '  dead [shape=box, style="filled,dashed", fillcolor="#f8d0d0", '
            'label="no accepting\\ncontinuation"];'
        )
        for s in states:
            lines.append(
                f'  q{s} -> dead [label="{_esc(text)}", color="#d62728", '
                'fontcolor="#d62728", style=dashed, penwidth=2.5];'
            )
    lines.append("}")
    return "\n".join(lines) + "\n"


def to_svg(dot: str) -> str:
    """Render DOT to SVG with Graphviz ``dot`` (`tamp.pictures.render`, the one renderer)."""
    from tamp.pictures import render

    return render(dot, "svg").decode()
