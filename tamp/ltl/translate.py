"""LTL → automaton, the one place that calls Spot's translator: options, cache and guard.

Facts of Spot 2.13 (pip ``spottl``) that this module relies on:

- ``'BA'`` silently loses state-based acceptance in this build (its option parser drops the
  flag), so Büchi automata are made with ``'Buchi', 'SBAcc'`` plus the preference and the
  optimisation level (``'small', 'high'`` by default).
- LTLf (finite traces) goes through ``spot.from_ltlf(f, 'alive')``, the Büchi translation and
  ``spot.to_finite(aut, 'alive')``: accepting states are the final states of an NFA. In
  Spot's LTLf ``X f`` is the weak next and ``X[!] f`` the strong one; traces are non-empty.
- The order of ``&`` operands, and so the order in which a degeneralised automaton of
  ``GF p1 & GF p2 & …`` serves its conjuncts, depends on what the process created before
  (atomic propositions are interned process-wide). ``Options.fresh`` translates a copy whose
  propositions are brand-new names created in order of first appearance in the text, in a
  fresh BDD dictionary, and relabels back: the automaton is then a function of the text only.
- The negation of a big conjunction is a small disjunction, but the ``'high'``
  simplifications take seconds to minutes on it (``!(F g0 & … & F g11)``: ~1 ms at
  ``'low'``, ~12 s at ``'high'``): callers that translate negations ask for ``level='low'``.

Translations are cached on (formula text, options); a cached automaton is shared, so callers
must not modify it (copy it with `tamp.ltl.automata.copy` first).

Guard. The automaton of k temporal conjuncts can need 2^k states and Spot's C++ cannot be
interrupted from Python, so a formula is refused (`InputError`, exit 2, naming a prefix of the
formula and the limit) when a cheap size check fails (`Limits.max_aps`,
`Limits.max_temporal_conjuncts`), and a formula above the small "inline" size is translated
in a forked child that has `Limits.seconds` to send back its HOA text (killed otherwise),
unless Spot's syntactic simplifier (< 2 ms) makes it that small: an unsatisfiable
``G !a & F a & F g0 & … & F g9`` is ``0`` and translates in-process, whatever the
machine's load (in a child it took 0.1 s idle and over 1 s on a loaded machine).
Measured on this machine: GF × 13 takes 4.7 s at ``'high'``, ``F p0 & … & F p10`` 4.7 s;
forking costs ~7 ms, so small formulas (all packaged tasks) translate in-process. Where
``os.fork`` does not exist (Windows) every translation runs in-process, with the size check
only. The child's automaton is parsed back from HOA (same states, edges and labels: tested).
"""

from __future__ import annotations

import itertools
import os
import re
import select
import signal
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import spot

from tamp.errors import InputError
from tamp.ltl.formula import Formula, ap_names, short, temporal_conjuncts, temporal_operators
from tamp.ltl.letters import Automaton


@dataclass(frozen=True)
class Options:
    """How to translate (part of the cache key).

    ``level``: Spot's optimisation level (``high``, ``medium``, ``low``); ``pref``: ``small``
    or ``any``; ``finite``: LTLf semantics (an NFA, accepting = final); ``fresh``: fresh
    proposition names and BDD dictionary (the automaton depends on the formula text only).
    """

    level: str = "high"
    pref: str = "small"
    finite: bool = False
    fresh: bool = False


@dataclass(frozen=True)
class Limits:
    """The guard: size limits checked before translating, and a wall-time limit.

    Formulas with at most ``inline_temporal`` temporal operators and ``inline_length``
    length are translated in-process (measured < 0.1 s); others in a forked child killed
    after ``seconds``.
    """

    max_aps: int = 64
    max_temporal_conjuncts: int = 16
    seconds: float = 5.0
    inline_temporal: int = 8
    inline_length: int = 40


LIMITS = Limits()
BUCHI = Options()
#: the negation of a property (model checking): Spot's low level, see module docstring
NEGATION = Options(level="low", pref="any")
FINITE = Options(finite=True)


@dataclass
class CacheInfo:
    """Translation cache counters (hits, misses) and the current number of entries."""

    hits: int = 0
    misses: int = 0
    size: int = 0


_CACHE: OrderedDict[tuple[str, Options], Automaton] = OrderedDict()
_CACHE_MAX = 512
_INFO = CacheInfo()


def cache_info() -> CacheInfo:
    """Hits, misses and size of the translation cache."""
    return CacheInfo(_INFO.hits, _INFO.misses, len(_CACHE))


def clear_cache() -> None:
    """Forget every cached automaton (benchmarks measure cold translations this way)."""
    _CACHE.clear()
    _INFO.hits = _INFO.misses = 0


def translate(
    f: str | Formula,
    options: Options = BUCHI,
    *,
    limits: Limits = LIMITS,
    file: str | None = None,
    field: str = "formula",
) -> Automaton:
    """The state-based Büchi automaton (or, ``options.finite``, the NFA) of ``f``; cached.

    The cache key is the formula's printed form, or with ``options.fresh`` the text as
    written (its order of first appearance fixes the proposition order). A formula that exceeds
    ``limits`` is an `InputError` (``file``/``field`` name where it came from).
    """
    formula = Formula(f) if isinstance(f, str) else f
    # fresh names follow the text as written; otherwise the formula's printed form is the key
    text = f if isinstance(f, str) and options.fresh else str(formula)
    key = (text, options)
    aut = _CACHE.get(key)
    if aut is not None:
        _INFO.hits += 1
        _CACHE.move_to_end(key)
        return aut
    _INFO.misses += 1
    written = f if isinstance(f, str) else text  # what errors quote
    _check_size(formula, written, options, limits, file, field)
    job = _job(text, formula, options)
    if _inline(formula, limits) or _inline(_simplified(text), limits) or not hasattr(os, "fork"):
        aut = job()
    else:
        aut = _in_child(job, written, options, limits, file, field)
    _CACHE[key] = aut
    if len(_CACHE) > _CACHE_MAX:
        _CACHE.popitem(last=False)
    return aut


# -- guard ----------------------------------------------------------------------------------


def _check_size(
    f: Formula, text: str, options: Options, limits: Limits, file: str | None, field: str
) -> None:
    n_aps = len(ap_names(f))
    if n_aps > limits.max_aps:
        raise InputError(
            f"{short(text)!r} is too large to translate: {n_aps} propositions "
            f"(limit {limits.max_aps})",
            file=file,
            field=field,
        )
    k = temporal_conjuncts(f)
    if k > limits.max_temporal_conjuncts:
        raise InputError(
            f"{short(text)!r} is too large to translate: {k} temporal conjuncts "
            f"(limit {limits.max_temporal_conjuncts}; the automaton can need 2^{k} states)",
            file=file,
            field=field,
        )


def _simplified(text: str) -> Formula:
    """Spot's syntactic simplification of the formula (on its own copy; < 2 ms on GF x 13):
    ``G !a & F a & F g0 & ...`` is ``0``."""
    return spot.simplify(Formula(text))


def _inline(f: Formula, limits: Limits) -> bool:
    small = spot.length(f) <= limits.inline_length
    return small and temporal_operators(f) <= limits.inline_temporal


def _in_child(
    job: Callable[[], Automaton],
    text: str,
    options: Options,
    limits: Limits,
    file: str | None,
    field: str,
) -> Automaton:
    """Run ``job`` in a forked child; its automaton comes back as HOA text within the limit."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # child: translate, write the HOA text, leave without cleanup
        code = 1
        try:
            os.close(r)
            # to_str is added by the ``spot`` extension of twa, which a type checker cannot see
            data = job().to_str("hoa").encode()  # pyright: ignore[reportAttributeAccessIssue]
            view = memoryview(data)
            while view:
                view = view[os.write(w, view) :]
            code = 0
        finally:
            os._exit(code)
    os.close(w)
    chunks: list[bytes] = []
    deadline = time.monotonic() + limits.seconds
    try:
        while True:
            left = deadline - time.monotonic()
            ready = select.select([r], [], [], max(0.0, left))[0] if left > 0 else []
            if not ready:
                os.kill(pid, signal.SIGKILL)
                raise InputError(
                    f"{short(text)!r} takes longer than the limit of "
                    f"{limits.seconds:g} s to translate",
                    file=file,
                    field=field,
                )
            chunk = os.read(r, 1 << 16)
            if not chunk:
                break
            chunks.append(chunk)
    finally:
        os.close(r)
        _, status = os.waitpid(pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"translating {short(text)!r} failed in the child process")
    hoa = b"".join(chunks).decode()
    if not options.fresh:  # Spot's default BDD dictionary, like an in-process translation
        return spot.automaton(hoa)
    parser = spot.automaton_stream_parser(hoa, "<translation>", spot.automaton_parser_options())
    return parser.parse(spot.make_bdd_dict()).aut


# -- the translation itself -------------------------------------------------------------------

_FRESH = itertools.count()
_IDENT = re.compile(r"\b[a-z_][a-z0-9_]*\b")


def _job(text: str, f: Formula, options: Options) -> Callable[[], Automaton]:
    """The translation as a closure (run in-process or in the child).

    Spot's Python ``translate`` rewrites the formula object it is given (it then prints
    differently), so it always gets a new object parsed from ``text``, never the caller's.
    """
    if not options.fresh:
        return lambda: _spot(Formula(text), options, None)
    return lambda: _fresh(text, f, options)


def _spot(f: Formula, options: Options, bdict) -> Automaton:
    g = spot.from_ltlf(f, "alive") if options.finite else f
    kw = {} if bdict is None else {"dict": bdict}
    aut = spot.translate(g, "Buchi", "SBAcc", options.pref, options.level, **kw)
    return spot.to_finite(aut, "alive") if options.finite else aut


def _fresh(text: str, f: Formula, options: Options) -> Automaton:
    """Translate a copy with fresh proposition names in text order, then relabel back."""
    aps = set(ap_names(f))
    order: list[str] = []
    for m in _IDENT.finditer(text):
        if m.group(0) in aps and m.group(0) not in order:
            order.append(m.group(0))
    if set(order) != aps:  # a name the plain-identifier scan cannot see: keep it as is
        return _spot(Formula(text), options, spot.make_bdd_dict())
    tag = next(_FRESH)
    fresh = {name: f"ltlap{tag}x{i}" for i, name in enumerate(order)}
    renamed = _IDENT.sub(lambda m: fresh.get(m.group(0), m.group(0)), text)
    for name in order:  # create the fresh atoms in text order
        Formula.ap(fresh[name])
    aut = _spot(Formula(renamed), options, spot.make_bdd_dict())
    back = spot.relabeling_map()
    for name, new in fresh.items():
        back[Formula.ap(new)] = Formula.ap(name)
    spot.relabel_here(aut, back)
    return aut
