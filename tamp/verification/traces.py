"""Checking one trace against an LTL formula, with a shortest-bad-prefix explanation.

Two semantics:
- infinite words (a lasso ``prefix · cycle^ω``): the verdict is lasso acceptance by the Büchi
  automaton of ``f`` (`tamp.ltl.automata.accepts_lasso`: Spot's product emptiness);
- finite words (LTLf): the NFA of ``f`` read with LTLf semantics is run on the letters.

Every letter is a full valuation over the formula's propositions: a proposition the
letter does not name is false. Propositions the trace names but the formula does not
mention are ignored, as a runtime monitor would.

When the formula is violated, the explanation reads the trace on the automaton while
keeping only *live* states (those with an accepting continuation): the first position at
which no live state remains ends the shortest bad prefix. An accepted word that agrees
with the trace before that position is built from one live state reached there, for
comparison. For formulas with many top-level conjuncts the whole-formula automaton can be
exponential, so the verdict is computed conjunct by conjunct (sound: a word satisfies a
conjunction iff it satisfies every conjunct); the explanation comes from the whole formula
when its automaton translates within `EXPLAIN_LIMITS` (an unsatisfiable conjunction is
explained as unsatisfiable, however many conjuncts it has), else from the violated conjunct
whose bad prefix is shortest, named as such.
"""

from __future__ import annotations

from tamp import ltl
from tamp.errors import InputError
from tamp.ltl.automata import Automaton, Stepper, accepting_continuation, accepts_lasso
from tamp.ltl.formula import Formula, as_formula
from tamp.verification.verdict import Counterexample, Verdict
from tamp.verification.words import Word

#: Above this many top-level conjuncts the whole-formula automaton is not built (it can be
#: exponential in the number of conjuncts while each conjunct alone is tiny): the verdict is
#: then computed conjunct by conjunct, which is sound for a conjunction.
MAX_CONJUNCTS_FOR_WHOLE = 8

#: The guard for the whole-formula automaton of a violated large conjunction (explanation
#: only: the verdict never waits for it).
EXPLAIN_LIMITS = ltl.Limits(seconds=1.0)
_TOO_LARGE: set[tuple[str, bool]] = set()  # (formula, finite) that exceeded EXPLAIN_LIMITS

__all__ = [
    "EXPLAIN_LIMITS",
    "MAX_CONJUNCTS_FOR_WHOLE",
    "as_formula",
    "check_trace",
    "explain",
    "explain_on",
]


def check_trace(
    formula: str | Formula,
    word: Word,
    *,
    finite: bool | None = None,
    accepting_word: Word | None = None,
    subject: str = "trace",
    steps: list[str] | None = None,
) -> Verdict:
    """Verdict of ``word`` against ``formula``.

    ``finite`` selects LTLf semantics; ``None`` means "finite iff the word has no cycle".
    A lasso cannot be read finitely and a finite word has no infinite reading: both are
    `InputError` (exit 2). ``accepting_word`` (optional) replaces the computed comparison
    word, for callers that know a better one (the RG check passes the optimal order).
    ``steps`` labels the positions of ``word`` in the counterexample.
    """
    f = as_formula(formula)
    if finite is None:
        finite = not word.is_lasso
    if finite and word.is_lasso:
        raise InputError("a trace with a cycle is infinite: drop --finite", field="trace")
    if not finite and not word.is_lasso:
        raise InputError(
            "a finite trace has no infinite-word reading: add a cycle{…} or use --finite",
            field="trace",
        )
    parts = ltl.conjuncts(f)
    semantics = "finite" if finite else "infinite"
    whole = len(parts) <= MAX_CONJUNCTS_FOR_WHOLE

    def holds(g: Formula) -> tuple[bool, int]:
        return _holds_finite(g, word) if finite else _holds_lasso(g, word)

    explored = 0
    if whole:  # one product with the (small) whole-formula automaton decides
        ok, explored = holds(f)
        if ok:
            return Verdict(subject, str(f), semantics, True, explored)
    violated = []
    if len(parts) > 1 or not whole:
        for c in parts:
            ok, n = holds(c)
            if not whole:
                explored += n
            if not ok:
                violated.append(c)
    else:
        violated = [f]
    if not violated:
        return Verdict(subject, str(f), semantics, True, explored)
    ce = (
        explain(f, word, finite=finite)
        if whole
        else _explain_conjunction(f, violated, word, finite)
    )
    if accepting_word is not None:
        ce.accepting_word = accepting_word
    ce.violated = [str(c) for c in violated] if len(parts) > 1 else []
    ce.aps = ltl.ap_names(f)
    ce.steps = steps
    return Verdict(subject, str(f), semantics, False, explored, ce)


def _explain_conjunction(f: Formula, violated: list[Formula], word: Word, finite: bool):
    """Explanation of a violated conjunction with more than `MAX_CONJUNCTS_FOR_WHOLE` parts.

    A conjunct alone can misexplain the whole (``G !a & F a & …`` is unsatisfiable, while
    ``F a`` alone only "never happens"; the whole can have a shorter bad prefix than every
    conjunct). So the whole-formula automaton is tried first, under `EXPLAIN_LIMITS`: when
    it translates in time the explanation is exact. Otherwise the explanation is that of the
    violated conjunct with the shortest bad prefix, and says it is about that conjunct alone.
    """
    options = ltl.FINITE if finite else ltl.BUCHI
    key = (str(f), finite)
    aut = None
    if key not in _TOO_LARGE:
        try:
            aut = ltl.translate(f, options, limits=EXPLAIN_LIMITS)
        except InputError:
            _TOO_LARGE.add(key)  # do not wait for it again
    if aut is not None:
        return explain_on(aut, word, finite=finite)
    candidates = [(explain(c, word, finite=finite), c) for c in violated]
    ce, c = min(candidates, key=lambda x: (x[0].position is None, x[0].position or 0))
    ce.accepting_word = None
    ce.reason = (
        f"conjunct {c} alone (the whole formula is too large to explain exactly; a shorter "
        f"bad prefix of the whole is possible): {ce.reason.replace('the formula', 'it')}"
    )
    return ce


def _holds_finite(f: Formula, word: Word) -> tuple[bool, int]:
    aut = ltl.translate(f, ltl.FINITE)
    st = Stepper(aut, finite=True)
    cur = st.initial()
    explored = len(cur)
    for letter in word.prefix:
        if not cur:
            break
        cur = st.step(cur, letter)
    explored += st.visited
    return any(aut.state_is_accepting(s) for s in cur), explored


def _holds_lasso(f: Formula, word: Word) -> tuple[bool, int]:
    assert word.cycle is not None  # called for lassos only
    return accepts_lasso(ltl.translate(f), word.prefix, word.cycle)


def explain(f: Formula, word: Word, *, finite: bool) -> Counterexample:
    """Shortest bad prefix of ``word`` for ``f`` and an accepted word for comparison.

    Assumes ``word`` violates ``f`` (the caller checked).
    """
    aut = ltl.translate(f, ltl.FINITE if finite else ltl.BUCHI)
    return explain_on(aut, word, finite=finite)


def explain_on(aut: Automaton, word: Word, *, finite: bool) -> Counterexample:
    """`explain` on a given automaton (e.g. a task automaton started in some state)."""
    st = Stepper(aut, finite=finite)
    cur = st.initial()
    if not cur:
        what = "no non-empty finite trace" if finite else "no infinite word"
        return Counterexample(word, f"the formula is unsatisfiable: {what} satisfies it")

    def compare(prefix: tuple, states: frozenset[int]) -> Word:
        q = min(states)
        letters, cycle = accepting_continuation(aut, q, finite=finite)
        if finite:
            return Word.finite(list(prefix) + letters)
        assert cycle is not None  # a Büchi continuation always has its cycle
        return Word.lasso(list(prefix) + letters, cycle)

    before = cur
    for i, letter in enumerate(word.prefix):
        cur = st.step(before, letter)
        if not cur:
            return Counterexample(
                word,
                f"after position {i} no continuation can satisfy the formula",
                position=i,
                accepting_word=compare(word.prefix[:i], before),
            )
        before = cur
    if finite:
        if not word.prefix:
            reason = "the empty trace satisfies no LTLf formula (LTLf traces are non-empty)"
        else:
            reason = "the trace ends before the formula is satisfied (it could still be extended)"
        return Counterexample(word, reason, None, compare(word.prefix, cur))
    # Unroll the cycle until the live set dies or repeats (at most |2^Q| · |cycle| steps,
    # in practice a handful of rounds).
    assert word.cycle is not None  # an infinite check reads a lasso
    after_prefix = cur
    seen: set[tuple[frozenset[int], int]] = set()
    i = len(word.prefix)
    k = 0
    unrolled: list = []
    while (cur, k) not in seen:
        seen.add((cur, k))
        letter = word.cycle[k]
        nxt = st.step(cur, letter)
        if not nxt:
            return Counterexample(
                word,
                f"after position {i} (cycle letter {k}) no continuation can satisfy the formula",
                position=i,
                accepting_word=compare(word.prefix + tuple(unrolled), cur),
            )
        unrolled.append(letter)
        cur = nxt
        i += 1
        k = (k + 1) % len(word.cycle)
    return Counterexample(
        word,
        "every finite prefix can still be extended, but repeating the cycle forever never "
        "satisfies the formula",
        None,
        compare(word.prefix, after_prefix),
    )
