"""`tamp.ltl.translate`: options, the cache, the size and time guard, the forked translation."""

from __future__ import annotations

import time

import pytest

from tamp import ltl
from tamp.errors import InputError
from tamp.ltl.automata import Stepper
from tamp.ltl.translate import Limits, Options, cache_info, clear_cache, translate

GF4 = "GF p1 & GF p2 & GF p3 & GF p4"
GF40 = " & ".join(f"GF p{i}" for i in range(1, 41))
#: 11 F-conjuncts: passes the size check (11 <= 16) but takes ~4.7 s at 'high' (measured)
F11 = " & ".join(f"F p{i}" for i in range(11))
#: forces every translation into the forked child
FORK = Limits(inline_length=0, inline_temporal=0)


def test_buchi_keeps_state_based_acceptance():
    aut = translate(GF4)
    assert aut.prop_state_acc().is_true()  # not the 'BA' bug of this Spot build
    assert aut.acc().is_buchi()
    assert aut.num_states() == 5


def test_cache_is_keyed_on_text_and_options():
    clear_cache()
    a = translate("F(a & F b)")
    assert cache_info().misses == 1 and cache_info().hits == 0
    assert translate("F(a & F b)") is a
    assert cache_info().hits == 1
    low = translate("F(a & F b)", Options(level="low", pref="any"))
    assert low is not a and cache_info().misses == 2
    assert translate(ltl.parse("F(a & F b)")) is a  # a formula object by its printed text
    clear_cache()
    assert cache_info().size == 0 and translate("F(a & F b)") is not a


def test_translating_leaves_the_callers_formula_alone():
    """Spot's Python translate rewrites the object it gets (GFa & GFb prints as G(Fa & Fb))."""
    f = ltl.parse(GF4)
    clear_cache()
    translate(f)
    assert str(f) == "GFp1 & GFp2 & GFp3 & GFp4"


def test_ltlf_automaton_reads_finite_traces():
    aut = translate("F(a & X[!] b)", ltl.FINITE)
    st = Stepper(aut, finite=True)

    def accepts(*letters):
        cur = st.initial()
        for x in letters:
            cur = st.step(cur, x)
        return any(aut.state_is_accepting(s) for s in cur)

    assert accepts({"a"}, {"b"})
    assert not accepts({"a"})  # strong next: a last position has no successor
    assert not accepts({"b"}, {"a"})


@pytest.mark.parametrize(
    "text, options",
    [
        (GF4, Options()),
        ("GF p3 & GF p2 & GF p1", Options(fresh=True)),
        ("F(p1 & F(p2 & F p3)) & G !bad", Options()),
        ("!(F g0 & F g1 & (!g1 U g0))", Options(level="low", pref="any")),
        ("F(a & X[!] b) & G !c", Options(finite=True)),
    ],
)
def test_forked_translation_is_the_same_automaton(text, options):
    clear_cache()
    inline = translate(text, options).to_str("hoa")
    clear_cache()
    forked = translate(text, options, limits=FORK)
    assert forked.to_str("hoa") == inline
    assert forked.prop_state_acc().is_true() or options.finite


def test_size_guard_refuses_40_gf_conjuncts_at_once():
    t = time.perf_counter()
    with pytest.raises(InputError) as err:
        translate(GF40, file="task.yaml")
    assert time.perf_counter() - t < 0.5
    msg = str(err.value)
    assert err.value.file == "task.yaml" and err.value.field == "formula"
    assert "'GF p1 & GF p2 & GF p3" in msg and "GF p40" not in msg  # a prefix only
    assert "40 temporal conjuncts (limit 16" in msg


def test_size_guard_counts_propositions():
    text = " | ".join(f"a{i}" for i in range(70))
    with pytest.raises(InputError, match="70 propositions \\(limit 64\\)"):
        translate(f"G({text})")


def test_time_guard_stops_a_slow_translation_and_caches_nothing():
    clear_cache()
    t = time.perf_counter()
    with pytest.raises(InputError) as err:
        translate(F11, limits=Limits(seconds=0.3))
    took = time.perf_counter() - t
    assert took < 2.0
    assert "takes longer than the limit of 0.3 s to translate" in str(err.value)
    assert "'F p0 & F p1" in str(err.value)
    assert cache_info().size == 0


def test_a_negated_big_conjunction_translates_fast_at_low_level():
    f = ltl.negate(ltl.parse(" & ".join(f"F g{i}" for i in range(30))))
    t = time.perf_counter()
    aut = translate(f, ltl.NEGATION)
    assert time.perf_counter() - t < 1.0
    assert aut.num_states() == 31


def test_forked_automata_share_the_default_dictionary_like_inline_ones():
    clear_cache()
    inline = translate("G(a -> F b)")
    forked = translate(GF4, limits=FORK)
    assert forked.get_dict() == inline.get_dict()
