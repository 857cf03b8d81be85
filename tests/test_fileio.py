"""Strict YAML loading: what every file of the project is refused for, before any field."""

from __future__ import annotations

import time

import pytest

from tamp import fileio
from tamp.demo import load_demonstration
from tamp.errors import InputError
from tamp.fileio import MAX_ALIASES, load_yaml, parse_yaml_text

LOADERS = {"libyaml": fileio._LOADER, "pure-python": fileio._StrictLoader}


@pytest.fixture(autouse=True, params=sorted(LOADERS))
def loader(request, monkeypatch):
    """Every refusal holds for the C-scanner loader and for the pure-Python fallback."""
    monkeypatch.setattr(fileio, "_LOADER", LOADERS[request.param])
    return request.param


def _write(tmp_path, text: str):
    p = tmp_path / "f.yaml"
    p.write_text(text)
    return p


def test_version_true_is_not_version_1(tmp_path):
    with pytest.raises(InputError, match="unsupported version True") as err:
        load_yaml(_write(tmp_path, "version: true\n"), kind="demonstration")
    assert err.value.field == "version"


def test_duplicate_keys_are_refused_with_their_line(tmp_path):
    text = "version: 1\nprops:\n  p1: a\n  p1: b\n"
    with pytest.raises(InputError, match=r"duplicate key 'p1' \(line 4\)"):
        load_yaml(_write(tmp_path, text), kind="LTL task")


def _bomb(levels: int) -> str:
    lines = ["version: 1", "a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, levels):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    return "\n".join(lines) + "\n"


def test_too_many_aliases_are_refused(tmp_path):
    with pytest.raises(InputError, match=f"more than {MAX_ALIASES} YAML aliases"):
        load_yaml(_write(tmp_path, _bomb(200)), kind="demonstration")


def test_a_billion_laughs_is_refused_by_field_checks_not_expanded(tmp_path):
    text = _bomb(9) + "frame: {robot_position: *a8}\narea_radius: 0.1\n"
    t0 = time.perf_counter()
    with pytest.raises(InputError) as err:
        load_demonstration(_write(tmp_path, text.replace("a0: &a0", "a0: &a0")))
    assert time.perf_counter() - t0 < 5  # bounded work (10^9 leaves if expanded)
    assert len(str(err.value)) < 300


def test_deep_nesting_is_refused(tmp_path):
    with pytest.raises(InputError, match="nested deeper"):
        load_yaml(_write(tmp_path, "version: 1\nx: " + "[" * 500 + "]" * 500 + "\n"), kind="x")


@pytest.mark.parametrize("value", ["1e999", ".inf", "-.nan", "1e308"])
def test_numbers_must_be_finite_and_sane(tmp_path, value):
    text = (
        "version: 1\nframe: {robot_position: [0, 0, 0]}\narea_radius: 0.15\n"
        f"objects: [{{id: O0, position: [{value}, 0, 0]}}]\n"
        "steps: [{object: O0, to: [1, 0, 0]}]\n"
    )
    with pytest.raises(InputError) as err:
        load_demonstration(_write(tmp_path, text))
    assert err.value.field == "objects[0].position[0]"


def test_messages_quote_only_a_prefix_of_a_huge_value(tmp_path):
    huge = "x" * 1_000_000
    text = f"version: 1\nframe: {{robot_position: [0, 0, 0]}}\narea_radius: {huge}\n"
    with pytest.raises(InputError) as err:
        load_demonstration(_write(tmp_path, text))
    assert len(str(err.value)) < 300


def test_the_c_scanner_is_used_where_libyaml_exists_and_parses_the_same():
    import yaml

    assert (LOADERS["libyaml"] is not fileio._StrictLoader) == yaml.__with_libyaml__
    from pathlib import Path

    import tamp

    files = sorted(Path(tamp.__file__).parent.joinpath("scenarios").rglob("*.yaml"))
    assert len(files) > 10
    for f in files:
        text = f.read_text()
        assert parse_yaml_text(text) == parse_yaml_text(text, pure_python=True), f


def test_nesting_far_beyond_the_limit_is_refused_not_crashed(tmp_path):
    # libyaml's own composer recurses in C and crashes the process on this file
    n = 200_000
    with pytest.raises(InputError, match="nested deeper"):
        load_yaml(_write(tmp_path, "version: 1\nx: " + "[" * n + "]" * n + "\n"), kind="x")
