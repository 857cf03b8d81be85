"""`tamp lots` prints exactly what it printed before the LTL layer moved (golden outputs).

The files under ``golden/`` were written by ``tamp lots`` before `tamp.ltl` existed (text,
``--json`` and ``--dot``) for every packaged task, alone and with each packaged interference
script, with both tree-update variants; they were rewritten once when runs were first judged
on their word (a ``run's word`` line, the ``word`` keys) and the robot lost the return action
by default (Example 1 with its interference no longer takes the screwdriver back), and
Example 1's when its task file took the paper's round order (hammer, screw, screwdriver,
screw: the formula's conjuncts written reversed for Spot). Any change
in the automaton (state numbers, edge order, labels), the plan or the robot's actions shows
up here.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tamp.commands.main import main

GOLDEN = Path(__file__).parent / "golden"

RUNS = {
    "example1": ["example1.yaml"],
    "example1_interference": ["example1.yaml", "--interference", "example1_interference.yaml"],
    "example1_interference_random3": [
        "example1.yaml",
        "--interference",
        "example1_interference.yaml",
        "--tree",
        "random",
        "--seed",
        "3",
    ],
    "model_building": ["model_building.yaml"],
    "model_building_fig8": ["model_building.yaml", "--interference", "model_building_fig8.yaml"],
    "model_building_fig9": ["model_building.yaml", "--interference", "model_building_fig9.yaml"],
    "tower": ["tower.yaml"],
    "tower_interference": ["tower.yaml", "--interference", "tower_interference.yaml"],
    "tower_interference_random1": [
        "tower.yaml",
        "--interference",
        "tower_interference.yaml",
        "--tree",
        "random",
        "--seed",
        "1",
    ],
}


@pytest.mark.parametrize("name", sorted(RUNS))
def test_text_and_json_are_unchanged(capsys, name):
    assert main(["lots", *RUNS[name]]) == 0
    assert capsys.readouterr().out == (GOLDEN / f"{name}.txt").read_text()
    assert main(["lots", *RUNS[name], "--json"]) == 0
    assert capsys.readouterr().out == (GOLDEN / f"{name}.json").read_text()


@pytest.mark.parametrize("name", ["example1", "model_building", "tower"])
def test_automaton_dot_is_unchanged(capsys, tmp_path, name):
    dot = tmp_path / "aut.dot"
    assert main(["lots", f"{name}.yaml", "--dot", str(dot)]) == 0
    capsys.readouterr()
    assert dot.read_text() == (GOLDEN / f"{name}.dot").read_text()
