"""JSON Schemas of the YAML formats (`tamp schema`, `tamp.commands.schema.FORMATS`): each is a
valid draft 2020-12 schema, every packaged file validates against its format's schema, every
packaged YAML file belongs to one format, and a schema refuses what its loader refuses
(unknown keys, wrong types, values out of bounds)."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import pytest

jsonschema = pytest.importorskip("jsonschema")

from tamp.commands.schema import FORMATS  # noqa: E402
from tamp.errors import InputError  # noqa: E402
from tamp.fileio import load_yaml  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "tamp"


def _validator(name: str):
    schema = FORMATS[name].schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _cases():
    return [
        pytest.param(name, path, id=f"{name}:{path.name}")
        for name, fmt in FORMATS.items()
        for path in fmt.example_files()
    ]


@pytest.mark.parametrize("name", list(FORMATS))
def test_each_schema_is_valid_and_has_examples(name):
    _validator(name)
    assert FORMATS[name].example_files(), f"{name}: no packaged file matches its globs"


@pytest.mark.parametrize(("name", "path"), _cases())
def test_every_packaged_file_validates(name, path):
    data, _ = load_yaml(path, kind=name)
    errors = sorted(_validator(name).iter_errors(data), key=str)
    assert not errors, f"{path}: " + "; ".join(
        f"{'.'.join(map(str, e.absolute_path))}: {e.message}" for e in errors[:5]
    )


def test_every_packaged_yaml_file_has_one_format():
    owners: dict[Path, list[str]] = {}
    for name, fmt in FORMATS.items():
        for path in fmt.example_files():
            owners.setdefault(path, []).append(name)
    found = sorted((PACKAGE / "scenarios").rglob("*.yaml")) + sorted(
        (PACKAGE / "world" / "domains").glob("*.yaml")
    )
    unclaimed = [str(p.relative_to(ROOT)) for p in found if p not in owners]
    twice = {str(p.relative_to(ROOT)): n for p, n in owners.items() if len(n) > 1}
    assert not unclaimed, f"no format claims {unclaimed}: add it to FORMATS"
    assert not twice, f"claimed by two formats: {twice}"


@pytest.mark.parametrize(("name", "path"), _cases())
def test_schemas_refuse_an_unknown_key(name, path):
    data, _ = load_yaml(path, kind=name)
    bad = copy.deepcopy(data)
    bad["no_such_key"] = 1
    assert not _validator(name).is_valid(bad)


def _first_file(name: str) -> dict:
    return load_yaml(FORMATS[name].example_files()[0], kind=name)[0]


@pytest.mark.parametrize(
    ("name", "edit"),
    [
        ("demonstration", lambda d: d.update(area_radius=0)),
        ("demonstration", lambda d: d["steps"][0].update(to=[1, 2])),
        ("domain", lambda d: d["actions"][0].update(success_rate=1.5)),
        ("domain", lambda d: d["actions"][0]["params"].update(x="robot")),
        ("lots-task", lambda d: d["initial"].update(C={})),
        ("lots-interference", lambda d: d["events"][0].update(kind="throw")),
        ("sim-smp", lambda d: d.setdefault("plant", {}).update(time_step=1.0)),
        ("sim-smp", lambda d: d.setdefault("planner", {}).update(cost="fastest")),
        ("sim-lots", lambda d: d["objects"][0].update(workspace="C")),
        ("refine-program", lambda d: d["robots"][0].update(model="pr2")),
        ("refine-program", lambda d: d["communication"].update(category="IV")),
        ("refine-architecture", lambda d: d["categories"].pop("II")),
        ("refine-scene", lambda d: d.update(version=2)),
    ],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_schemas_refuse_what_the_loaders_refuse(name, edit, tmp_path):
    """The same edit makes the schema and the loader refuse the file."""
    import importlib

    import yaml

    original = _first_file(name)
    src = FORMATS[name].example_files()[0]
    for key in ("demonstration", "architecture"):  # files named relative to the packaged one
        if key in original and (src.parent / original[key]).exists():
            original[key] = str((src.parent / original[key]).resolve())
    data = copy.deepcopy(original)
    edit(data)
    assert not _validator(name).is_valid(data), f"{name}: the schema accepts the edit"
    path = tmp_path / src.name  # files it names resolve to the packaged ones from here
    module, func = FORMATS[name].loader.rsplit(".", 1)
    loader = getattr(importlib.import_module(module), func)
    args = [path]
    if name == "lots-interference":
        from tamp.lots.task import load_task

        args.append(load_task(src.parent / (src.stem.split("_")[0] + ".yaml")))
    path.write_text(yaml.safe_dump(original), encoding="utf-8")
    loader(*args)  # the unedited copy loads from here
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(InputError):
        loader(*args)


def _tamp(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tamp.commands.main", "schema", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )


def test_tamp_schema_prints_lists_and_refuses(tmp_path):
    out = _tamp("refine-scene")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["$schema"].endswith("2020-12/schema") and doc["title"].startswith("tamp ")
    listing = _tamp()
    assert listing.returncode == 0 and listing.stdout.split()[0] == "demonstration"
    assert {line.split()[0] for line in listing.stdout.splitlines()} == set(FORMATS)
    target = tmp_path / "schemas"  # --out is a folder, as everywhere
    assert _tamp("domain", "--out", str(target)).returncode == 0
    assert (
        json.loads((target / "domain.json").read_text())["properties"]["actions"]["type"] == "array"
    )
    assert _tamp("--out", str(target)).returncode == 0
    assert {p.stem for p in target.glob("*.json")} == set(FORMATS)
    (tmp_path / "file").write_text("x")
    refused = _tamp("domain", "--out", str(tmp_path / "file"))
    assert refused.returncode == 2 and "--out" in refused.stderr
    bad = _tamp("nope")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "unknown format" in bad.stderr
