"""One grammar for every command: each option has help text, every JSON document says its
schema, the packaged scenarios are listed, and the completion script is made from the
parsers (so it lists every subcommand)."""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess

import pytest

from tamp.commands.completion import parsers, script
from tamp.commands.main import COMMANDS
from tamp.commands.main import main as tamp_main
from tamp.commands.verify import main as verify_main


def _options(parser: argparse.ArgumentParser, path: str):
    """(command path, option) for every argument of ``parser`` and its subcommands."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _options(sub, f"{path} {name}")
        elif not isinstance(action, argparse._HelpAction | argparse._VersionAction):
            yield path, action


def test_every_option_of_every_command_has_help_text():
    missing = [
        f"{path} {(action.option_strings or [action.dest])[0]}"
        for prog, parser in parsers().items()
        for path, action in _options(parser, prog)
        if not action.help or action.help == argparse.SUPPRESS
    ]
    assert not missing, "options without help text: " + ", ".join(missing)


def _json(run, capsys, *argv: str) -> dict:
    run(list(argv))
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    "run, argv",
    [
        (tamp_main, ["plan", "case2.yaml", "--json"]),
        (tamp_main, ["plan", "case1.yaml", "--execute", "--json"]),
        (tamp_main, ["lots", "tower.yaml", "--json"]),
        (tamp_main, ["scenarios", "--json"]),
        (tamp_main, ["plan", "no_such_demo.yaml", "--json"]),  # an error document
        (tamp_main, ["simulate", "lots", "tower", "--seed", "-1", "--json"]),  # refused early
        (verify_main, ["trace", "--formula", "F p", "--word", "cycle{p}", "--json"]),
        (verify_main, ["plan", "case2.yaml", "--order", "G2,G3,G0,G1", "--json"]),
        (verify_main, ["lots", "tower.yaml", "--json"]),
    ],
)
def test_every_json_document_says_its_schema(run, argv, capsys):
    assert _json(run, capsys, *argv)["schema"] == 1


def test_scenarios_lists_the_packaged_files_by_kind(capsys):
    doc = _json(tamp_main, capsys, "scenarios", "--json")
    kinds = {(f["name"], f["kind"]) for f in doc["scenarios"]}
    assert {("case1", "demonstration"), ("case1", "sim-smp"), ("tower", "lots-task")} <= kinds
    assert {("tower", "sim-lots"), ("task4", "refine-program")} <= kinds  # the name and
    # the command's kind say which file: `tamp plan case1`, `tamp simulate smp-mro case1`
    tower = next(f for f in doc["scenarios"] if f["name"] == "tower")
    assert tower["path"] == "tamp/scenarios/lots/tower.yaml"
    assert tower["description"].startswith("Zhou et al.")
    assert "domain" not in {k for _, k in kinds}  # a robot's domain file is not a scenario
    assert tamp_main(["scenarios", "lots-task"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines and all(line.split()[1] == "lots-task" for line in lines)
    assert any(line.startswith("tower ") for line in lines)
    assert tamp_main(["scenarios", "nonsense"]) == 2
    assert "KIND" in capsys.readouterr().err


def test_completion_lists_every_subcommand():
    for shell in ("bash", "zsh"):
        text = script(shell)
        for command in COMMANDS:
            assert f" {command}" in text, (shell, command)
        for check in ("trace", "plan", "bt", "lots"):
            assert f"'tamp-verify {check}'" in text
        assert "smp-mro lots refine" in text  # the workcells after `tamp simulate`


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_the_bash_script_completes_subcommands_options_and_choices():
    def complete(*words: str) -> list[str]:
        probe = (
            'COMP_WORDS=("$@"); COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); COMPREPLY=(); '
            '_tamp_complete; printf "%s\\n" "${COMPREPLY[@]}"'
        )
        out = subprocess.run(
            ["bash", "-c", f"{script('bash')}\n{probe}", "bash", *words],
            capture_output=True,
            text=True,
            check=True,
        )
        return out.stdout.split()

    assert complete("tamp", "sim") == ["simulate"]
    assert complete("tamp", "simulate", "l") == ["lots"]
    assert "--cell" in complete("tamp", "simulate", "lots", "tower", "--c")
    assert complete("tamp", "campaign", "x", "--kind", "") == ["smp-mro", "lots", "refine"]


def test_completion_command_prints_the_script(capsys):
    assert tamp_main(["completion", "bash"]) == 0
    assert "complete -o filenames -F _tamp_complete tamp" in capsys.readouterr().out
    assert tamp_main(["completion", "fish"]) == 2
