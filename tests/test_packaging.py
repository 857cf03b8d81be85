"""pyproject.toml against the source tree: every package listed, every pin in its range."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE_DIRS = {"tamp": "tamp"}


def _config() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_folder_with_files_is_a_listed_package():
    """A folder missing from the list is missing from the wheel (code or data alike)."""
    setuptools = _config()["tool"]["setuptools"]
    assert "package-dir" not in setuptools  # one import root, found by its own name
    patterns = setuptools["package-data"]["*"]
    found = set()
    for name, folder in PACKAGE_DIRS.items():
        for path in (ROOT / folder).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts:
                rel = path.parent.relative_to(ROOT / folder).parts
                found.add(".".join((name, *rel)))
                assert path.suffix == ".py" or any(path.match(p) for p in patterns), (
                    f"{path.relative_to(ROOT)} is not matched by [tool.setuptools.package-data]"
                )
    listed = set(setuptools["packages"])
    assert found - listed == set(), "add these to [tool.setuptools] packages in pyproject.toml"
    assert listed - found == set(), "these packages of pyproject.toml do not exist"
    # importlib.resources.files needs it
    assert (ROOT / "tamp" / "models" / "__init__.py").is_file()


def test_pins_lie_in_the_declared_ranges():
    """constraints.txt pins every dependency, inside the range pyproject.toml declares."""
    from packaging.requirements import Requirement

    project = _config()["project"]
    declared = [Requirement(r) for r in project["dependencies"]]
    for extra in project["optional-dependencies"].values():
        declared += [Requirement(r) for r in extra]
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            req = Requirement(line)
            (spec,) = req.specifier
            assert spec.operator == "==", line
            pins[req.name.lower().replace("_", "-")] = spec.version
    for req in declared:
        name = req.name.lower().replace("_", "-")
        if name == project["name"]:  # an extra made of other extras (all, dev)
            assert req.extras <= set(project["optional-dependencies"]), req
            continue
        assert name in pins, f"constraints.txt does not pin {req.name}"
        assert req.specifier.contains(pins[name]), f"{req.name}=={pins[name]} not in {req}"
    assert pins["drake"] == "1.51.1" and pins["torch"] == "2.13.0"
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]


def test_the_citation_file_cites_the_software_and_the_three_papers():
    """CITATION.cff (Citation File Format 1.2): the software at pyproject's version, and the
    papers whose methods it implements, with the DOI where the paper gives one."""
    import yaml

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    project = _config()["project"]
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["version"] == project["version"] and cff["license"] == project["license"]
    titles = {r["title"].split()[0]: r for r in cff["references"]}
    assert set(titles) == {"Robot", "Local", "Refining"}
    assert titles["Local"]["doi"] == "10.1109/TASE.2023.3304842"
    assert titles["Refining"]["journal"] == "Journal of Robotics and Mechatronics"
    for ref in cff["references"]:
        assert ref["type"] == "article" and ref["authors"] and ref["journal"]
