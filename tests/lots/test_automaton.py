"""The Spot wrapper: state-based Büchi acceptance, executable letters, views, determinism."""

from __future__ import annotations

import subprocess
import sys

import pydot
import pytest

from tamp.errors import InputError
from tamp.lots.automaton import EMPTY, Automaton

GF4 = "GF p1 & GF p2 & GF p3 & GF p4"
P4 = ["p1", "p2", "p3", "p4"]


def L(*props):
    return frozenset(props)


def test_gf_conjunction_is_state_based_buchi():
    a = Automaton(GF4, P4)
    assert a.spot_aut.prop_state_acc().is_true()  # state-based acceptance kept (not 'BA' bug)
    assert a.spot_aut.acc().is_buchi()
    assert a.num_states == 5
    assert a.accepting == {a.initial}
    assert set(a.ap) == set(P4)


def test_executable_letters_and_successors():
    a = Automaton("F(p1 & F(p2 & F p3))", ["p1", "p2", "p3"])
    assert a.letters == (EMPTY, L("p1"), L("p2"), L("p3"))
    q = a.initial
    for p in ("p1", "p2", "p3"):
        (q,) = a.successors(q, L(p))
    assert q in a.accepting
    # out of order does not progress: p2 first keeps the initial state
    assert a.successors(a.initial, L("p2")) == (a.initial,)


def test_spot_checks_lassos_over_the_same_dictionary():
    a = Automaton(GF4, P4)
    assert a.accepts_lasso([], [L("p4"), L("p3"), L("p2"), L("p1")])
    assert not a.accepts_lasso([], [L("p1"), L("p2"), L("p3")])  # p4 never again
    assert not a.accepts_lasso([L("p1")], [EMPTY])


@pytest.mark.filterwarnings("ignore")  # pydot uses deprecated pyparsing names
def test_networkx_and_dot_views_agree():
    a = Automaton(GF4, P4)
    g = a.to_networkx()
    assert g.number_of_nodes() == a.num_states
    assert g.number_of_edges() == len(a.edges)
    assert [n for n, d in g.nodes(data=True) if d["accepting"]] == sorted(a.accepting)
    assert all("label" in d for _, _, d in g.edges(data=True))
    (dot,) = pydot.graph_from_dot_data(a.to_dot())
    edges = [e for e in dot.get_edges() if e.get_source() != "init"]
    assert len(edges) == len(a.edges)
    labels = {e.get_label().strip('"') for e in edges}
    assert labels == {e.label for e in a.edges}


def test_order_depends_on_formula_text_only():
    """Spot interns propositions process-wide; the wrapper keeps the run order stable."""
    code = (
        "import sys\n"
        "from tamp.lots.automaton import Automaton\n"
        "from tamp.lots.planner import initial_lasso\n"
        "from tamp.lots.task import Proposition, Task\n"
        "if sys.argv[1] == 'warm':\n"
        "    Automaton('GF p1 & GF p2 & GF p3', ['p1', 'p2', 'p3'])\n"
        "props = tuple(Proposition(f'p{i}', f'c{i}') for i in (1, 2, 3))\n"
        "task = Task('GF p3 & GF p2 & GF p1', props, {'c1': 1, 'c2': 1, 'c3': 1})\n"
        "steps, _, _ = initial_lasso(Automaton(task.formula, task.props), task)\n"
        "print(' '.join(s.prop for s in steps))\n"
    )
    runs = {
        subprocess.run(
            [sys.executable, "-c", code, arg], capture_output=True, text=True, check=True
        ).stdout.strip()
        for arg in ("cold", "warm")
    }
    assert runs == {"p1 p2 p3"}


@pytest.mark.parametrize(
    "formula, props, field_msg",
    [
        ("F(p1 &", ["p1"], "does not parse"),
        ("F q", ["p1"], "unknown proposition"),
    ],
)
def test_bad_formulas_are_input_errors(formula, props, field_msg):
    with pytest.raises(InputError) as err:
        Automaton(formula, props, file="task.yaml")
    assert err.value.field == "formula"
    assert field_msg in str(err.value)
