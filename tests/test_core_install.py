"""The light core: `tamp plan`, `tamp lots` and `tamp-verify` import neither Drake nor torch,
and a command whose extra is missing says which extra to install (exit 2).

`make test-core` runs this file in fresh environments holding only the core (Python 3.12 and
3.13), where the missing-extra cases happen for real; in the full environment they are
provoked with a module that is not installed.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys

import pytest

from tamp.commands.main import main, run
from tamp.extras import DISTRIBUTION, EXTRAS, extra_of, from_import_error

HAS_DRAKE = importlib.util.find_spec("pydrake") is not None

PROBE = """
import json, sys
from tamp.commands.main import main, run
from tamp.commands.verify import main as verify
codes = [main(["plan", "case3", "--execute"]), main(["lots", "tower"]),
         verify(["bt", "case1.yaml"]), verify(["lots", "tower"])]
heavy = sorted(m for m in ("pydrake", "torch", "ray", "websockets") if m in sys.modules)
print(json.dumps({"codes": codes, "heavy": heavy}))
"""


def test_the_symbolic_commands_import_neither_drake_nor_torch():
    out = subprocess.run(
        [sys.executable, "-c", PROBE], capture_output=True, text=True, check=True, timeout=300
    ).stdout
    doc = json.loads(out.strip().splitlines()[-1])
    assert doc == {"codes": [0, 0, 0, 0], "heavy": []}


def test_every_extra_names_its_install_line():
    names = {e.name for e in EXTRAS}
    assert names == {"sim", "grasp", "campaign", "serve"}
    assert extra_of("pydrake.systems.framework").name == "sim"
    assert extra_of("torch").name == "grasp" and extra_of("yaml") is None
    err = from_import_error(ModuleNotFoundError("x", name="ray.util"), "tamp campaign")
    assert err is not None and err.exit_code == 2
    assert f"pip install '{DISTRIBUTION}[campaign]'" in str(err)
    assert str(err).startswith("tamp campaign needs Ray ('ray' is not installed)")


def _parser_raising(exc: BaseException):
    """A `tamp`-like parser with one command ``grasp`` whose work raises ``exc``."""
    import argparse

    def parser():
        p = argparse.ArgumentParser(prog="tamp")
        sub = p.add_subparsers(dest="command", required=True)
        cmd = sub.add_parser("grasp")
        cmd.add_argument("--json", action="store_true")

        def func(args):
            raise exc

        cmd.set_defaults(func=func)
        return p

    return parser


def test_a_command_missing_its_extra_exits_2_naming_it(capsys):
    """What every command does when an optional library is absent (here: torch, provoked)."""
    no_torch = ModuleNotFoundError("No module named 'torch'", name="torch")
    assert run(["grasp"], _parser_raising(no_torch)) == 2
    err = capsys.readouterr().err
    assert "tamp: error: tamp grasp needs torch ('torch' is not installed)" in err
    assert f"pip install '{DISTRIBUTION}[grasp]'" in err
    assert run(["grasp", "--json"], _parser_raising(no_torch)) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["exit"] == 2 and "[grasp]" in doc["error"]


def test_an_unknown_missing_module_is_an_internal_error(capsys):
    other = ModuleNotFoundError("No module named 'no_such_xyz'", name="no_such_xyz")
    assert run(["grasp"], _parser_raising(other)) == 3
    assert "internal error: ModuleNotFoundError" in capsys.readouterr().err


@pytest.mark.skipif(HAS_DRAKE, reason="Drake is installed (the core-only run checks this)")
def test_without_drake_simulate_and_refine_name_the_sim_extra(capsys):
    for argv in (["simulate", "smp-mro", "--case", "1"], ["refine", "task4"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "('pydrake' is not installed)" in err
        assert f"pip install '{DISTRIBUTION}[sim]'" in err
