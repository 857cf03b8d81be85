"""The registry of grasp networks (`tamp.grasp.networks`): every entry builds and ships its
weights, the command lines offer exactly its names, and reading it loads no torch."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from tamp.commands.main import COMMANDS, build_parser
from tamp.grasp.models import build_model
from tamp.grasp.networks import DEFAULT_NETWORK, INPUT_CHANNELS, NETWORKS, network
from tamp.grasp.predict import GraspPredictor
from tamp.sim.core.models import models_dir

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", list(NETWORKS))
def test_every_network_builds_for_its_input(name):
    net = NETWORKS[name]
    assert net.name == name and net.title and net.citation
    assert net.input in INPUT_CHANNELS and net.input_channels == INPUT_CHANNELS[net.input]
    torch.manual_seed(0)
    model = build_model(name, net.input).eval()
    assert type(model) is net.model_class()
    with torch.no_grad():
        out = model(torch.zeros(1, net.input_channels, 32, 32))
    assert out.shape == (1, 4, 32, 32)


@pytest.mark.parametrize("name", list(NETWORKS))
def test_every_network_ships_weights_that_describe_it(name):
    net = NETWORKS[name]
    path = models_dir() / net.weights
    assert path.is_file() and path.parent.name == "weights"
    meta = GraspPredictor.load(path).meta
    assert meta["model"] == name and meta["input"] == net.input
    assert ("fusion" in meta["kwargs"]) == net.fusion


def test_unknown_names_are_refused_naming_the_known_ones():
    assert DEFAULT_NETWORK == "hrgnet"  # the paper's network
    with pytest.raises(ValueError, match="unknown model 'yolo'.*hrgnet"):
        network("yolo")


def _choices(parser: argparse.ArgumentParser, path: list[str], flag: str) -> list[str]:
    """The choices of option ``flag`` of the subcommand reached by ``path``."""
    for word in path:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    action = next(a for a in parser._actions if flag in a.option_strings)
    return list(action.choices)


def test_command_lines_offer_the_registered_networks():
    parser = build_parser("tamp", COMMANDS, "tamp.commands")
    assert _choices(parser, ["grasp", "train"], "--model") == list(NETWORKS)
    assert _choices(parser, ["simulate", "lots"], "--grasp") == list(NETWORKS)


def test_registry_scenario_loader_and_help_load_no_torch():
    code = (
        "import sys\n"
        "import tamp.grasp.networks, tamp.sim.lots.scenario\n"
        "from tamp.commands.main import main\n"
        "try:\n"
        "    main(['--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        "sys.exit('torch' in sys.modules)\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=False
    )
    assert proc.returncode == 0, proc.stderr or "torch was imported"
