"""The layering of docs/architecture.md, checked on every import statement of the source tree.

"The arrows go one way: world ← ltl, demo, rg, bt, lots, refine, grasp ← verification ←
sim ← campaign ← commands." Function-level imports count too (a lazy import is still a
dependency). Drake is imported only under `tamp/sim/` and by the grasp data renderer,
Spot only under `tamp/ltl/`, Meshcat only in `tamp/sim/core/recording.py`, Ray only under
`tamp/campaign/` (an optional extra: everything imports without it).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Rank of each layer: a module may import only layers of lower or equal rank.
RANK = {
    "tamp.errors": 0,
    "tamp.fileio": 0.5,
    "tamp.pictures": 0.5,
    "tamp.extras": 0.5,
    "tamp.scenarios": 0.5,
    "tamp.perturbation": 0.6,
    "tamp.schema": 0.6,
    "tamp.world": 1,
    "tamp.ltl": 2,
    "tamp.demo": 2,
    "tamp.rg": 3,
    "tamp.bt": 3,
    "tamp.lots": 3,
    "tamp.refine": 3,
    "tamp.grasp": 3,
    "tamp.verification": 4,
    "tamp.sim.core": 5,  # what the workcells share ranks below them
    "tamp.sim.smp": 5.5,
    "tamp.sim.lots": 5.5,
    "tamp.sim.refine": 5.5,
    "tamp.sim": 5.5,  # the package's own __init__
    "tamp.campaign": 6,
    "tamp.serve": 6,  # the live link: planning, execution and a workcell, given to it
    "tamp.commands": 7,
    "tamp": 0,  # the package's own __init__
}

#: Imports that a layer may make of a peer of the same rank (documented dependencies).
PEERS = {("tamp.rg", "tamp.demo"), ("tamp.lots", "tamp.ltl"), ("tamp.demo", "tamp.world")}


def _layer(module: str) -> str | None:
    best = None
    for name in RANK:
        if (module == name or module.startswith(name + ".")) and (
            best is None or len(name) > len(best)
        ):
            best = name
    return best


def _modules():
    for base in ("tamp",):
        for path in sorted((ROOT / base).rglob("*.py")):
            rel = path.relative_to(ROOT).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            yield ".".join(parts), path


def _imports(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module, node.lineno
            for alias in node.names:  # "from tamp import cli" names a module
                yield f"{node.module}.{alias.name}", node.lineno


def test_layers_import_only_downwards():
    bad = []
    for module, path in _modules():
        src = _layer(module)
        for target, line in _imports(path):
            dst = _layer(target)
            if src is None or dst is None or dst == src or src == "tamp":
                continue
            if RANK[dst] > RANK[src] or (RANK[dst] == RANK[src] and (src, dst) not in PEERS):
                bad.append(f"{path.relative_to(ROOT)}:{line}: {src} imports {target}")
    assert not bad, "\n".join(bad)


def _sim_part(module: str) -> str | None:
    """``core`` or the workcell (``smp``, ``lots``, ...) of a ``tamp.sim.<part>...`` module."""
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["tamp", "sim"] else None


def test_a_workcell_never_imports_another_and_core_imports_none():
    """What two workcells share lives in ``tamp.sim.core``: a cell imports core, never another
    cell, and core imports no cell (whatever ranks ``RANK`` gives them)."""
    bad = []
    for module, path in _modules():
        src = _sim_part(module)
        if src is None:
            continue
        for target, line in _imports(path):
            dst = _sim_part(target)
            if dst is None or dst == src or dst == "core":
                continue
            what = "core imports the cell" if src == "core" else "one cell imports another"
            bad.append(f"{path.relative_to(ROOT)}:{line}: {what}: {target}")
    assert not bad, "\n".join(bad)


def test_heavy_libraries_stay_in_their_layer():
    where = {
        "pydrake": ("tamp/sim/", "tamp/grasp/synthetic.py"),
        "spot": ("tamp/ltl/",),
        "buddy": ("tamp/ltl/",),
        "ray": ("tamp/campaign/",),
    }
    bad = []
    for _, path in _modules():
        rel = str(path.relative_to(ROOT))
        for target, line in _imports(path):
            top = target.split(".")[0]
            if top in where and not rel.startswith(where[top]):
                bad.append(f"{rel}:{line}: imports {target}")
            if target.endswith("Meshcat") and rel != "tamp/sim/core/recording.py":
                bad.append(f"{rel}:{line}: imports Meshcat")
    assert not bad, "\n".join(bad)


def test_spot_translate_is_called_in_one_file():
    users = [
        str(p.relative_to(ROOT))
        for _, p in _modules()
        if "spot.translate(" in p.read_text(encoding="utf-8")
    ]
    assert users == ["tamp/ltl/translate.py"]


def test_tamp_imports_without_ray():
    """Ray is the `campaign` extra: with `import ray` failing, the campaign package and every
    command module still import (Ray is imported only when a Ray engine is made), and
    `tamp --help` works."""
    code = (
        "import sys; sys.modules['ray'] = None\n"
        "import importlib, pkgutil, tamp.campaign, tamp.commands\n"
        "for pkg in (tamp.campaign, tamp.commands):\n"
        "    for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + '.'):\n"
        "        importlib.import_module(m.name)\n"
        "from tamp.commands.main import main\n"
        "sys.exit(main(['--help']))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert "campaign" in proc.stdout


def test_the_refinement_loop_imports_no_drake():
    """`tamp.refine` (programs, state machines, the refinement loop and the measuring
    interface it is given) runs without Drake: none of its import statements names pydrake
    or the workcells (`tamp.sim`), and every module imports with pydrake unavailable."""
    bad = []
    for module, path in _modules():
        if module != "tamp.refine" and not module.startswith("tamp.refine."):
            continue
        for target, line in _imports(path):
            if target.split(".")[0] == "pydrake" or target.startswith("tamp.sim"):
                bad.append(f"{path.relative_to(ROOT)}:{line}: imports {target}")
    assert not bad, "\n".join(bad)
    code = (
        "import sys; sys.modules['pydrake'] = None\n"
        "import importlib, pkgutil, tamp.refine\n"
        "for m in pkgutil.walk_packages(tamp.refine.__path__, 'tamp.refine.'):\n"
        "    importlib.import_module(m.name)\n"
        "assert not any(n.startswith('tamp.sim') for n in sys.modules), 'tamp.sim imported'\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
