"""The behavior-tree and world packages import without cycles (also under TYPE_CHECKING)."""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parents[2]


def _imports(package: str) -> nx.DiGraph:
    g = nx.DiGraph()
    for path in sorted((ROOT / package.replace(".", "/")).glob("*.py")):
        mod = f"{package}.{path.stem}" if path.stem != "__init__" else package
        g.add_node(mod)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                if name.startswith(package + ".") and mod != package:
                    g.add_edge(mod, name)
    return g


def test_no_import_cycles_between_modules() -> None:
    for package in ("tamp.bt", "tamp.world", "tamp.verification.bt"):
        g = _imports(package)
        assert len(g) > 2
        assert list(nx.simple_cycles(g)) == [], package
    # tree surgery is a method of the executor now; expand.py does not import it back
    assert not _imports("tamp.bt").has_edge("tamp.bt.expand", "tamp.bt.executor")
