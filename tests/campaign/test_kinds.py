"""Which kind a SCENARIO is: packaged names through the one resolver, user files by key."""

from __future__ import annotations

import pytest

from tamp import scenarios
from tamp.campaign.kinds import get_kind, kinds, resolve_scenario
from tamp.errors import InputError


@pytest.mark.parametrize(
    ("name", "kind", "path"),
    [
        ("case3.yaml", "smp-mro", "sim/case3.yaml"),
        ("case1", "smp-mro", "sim/case1.yaml"),
        ("tower.yaml", "lots", "lots/tower.yaml"),
        ("task4", "refine", "refine/task4.yaml"),
    ],
)
def test_packaged_names(name, kind, path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # from any directory
    k, p = resolve_scenario(name, None)
    assert k.name == kind and p == scenarios.ROOT / path
    assert resolve_scenario(name, kind) == (k, p)


def test_user_files_by_their_key(tmp_path):
    for text, kind in (
        ("version: 1\ndemonstration: case1.yaml\n", "smp-mro"),
        ("version: 1\nformula: F p1\n", "lots"),
        ("version: 1\nrobots: []\n", "refine"),
    ):
        f = tmp_path / f"{kind}.yaml"
        f.write_text(text)
        assert resolve_scenario(str(f), None) == (kinds()[kind], f)
    odd = tmp_path / "odd.yaml"
    odd.write_text("version: 1\nname: x\n")
    with pytest.raises(InputError, match="give --kind") as e:
        resolve_scenario(str(odd), None)
    assert e.value.field == "--kind" and e.value.file == str(odd)
    assert resolve_scenario(str(odd), "lots") == (kinds()["lots"], odd)  # --kind decides


def test_unknown_and_ambiguous(fake_kind, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match="no such file") as e:
        resolve_scenario("no_such_case", None)
    assert e.value.field == "SCENARIO"
    with pytest.raises(InputError, match="unknown kind"):
        get_kind("nonsense")
    # the test kind shares the sim folder: case3.yaml is packaged for both
    with pytest.raises(InputError, match="smp-mro, test-fake: give --kind"):
        resolve_scenario("case3.yaml", None)


def test_every_kind_is_a_registered_workcell():
    from tamp.sim.core.workcell import CELL_PACKAGES, Workcell

    assert tuple(kinds()) == tuple(CELL_PACKAGES) == ("smp-mro", "lots", "refine")
    for name, kind in kinds().items():
        assert isinstance(kind, Workcell) and kind.name == name
        assert "{seed}" in kind.replay and "{scenario}" in kind.replay
