"""Exports of a (grown) tree: DOT via pydot with status colours, and BehaviorTree.CPP v4 XML.

DOT: control nodes are boxes labelled with the usual symbols (→ Sequence, →* Sequence with
memory, ? Fallback, R→ ReactiveSequence, R? ReactiveFallback, P? PriorityFallback with its
priorities), conditions are ellipses, actions are boxes with rounded corners; the fill
colour is the last status (green SUCCESS, red FAILURE, orange RUNNING, white idle).

XML: the BehaviorTree.CPP v4 format (``BTCPP_format="4"``) that Groot2 opens. Built-in
control nodes keep their names (SequenceWithMemory, Sequence, Fallback, ReactiveSequence,
ReactiveFallback); PriorityFallback is declared as a custom Control node with a
``priorities`` port ("0.95;0.5"); conditions and actions are written as
``<IsObjectAt obj="O1" area="L1"/>`` / ``<Place o="O1" l="L1"/>`` and declared in
``TreeNodesModel`` with their ports.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

from tamp.bt.nodes import (
    ActionNode,
    Condition,
    Fallback,
    Node,
    PriorityFallback,
    ReactiveFallback,
    ReactiveSequence,
    Sequence,
)
from tamp.world.interface import Status
from tamp.world.predicates import DEFAULT_REACH, Predicate

COLOURS = {
    Status.SUCCESS: "#8fd18f",
    Status.FAILURE: "#f08080",
    Status.RUNNING: "#ffc266",
    None: "#ffffff",
}


def _symbol(node: Node) -> str:
    if isinstance(node, Sequence):
        return "→*" if node.memory else "→"
    if isinstance(node, ReactiveSequence):
        return "R→"
    if isinstance(node, ReactiveFallback):
        return "R?"
    if isinstance(node, PriorityFallback):
        return "P? " + " ".join(f"{p:g}" for p in node.priorities)
    if isinstance(node, Fallback):
        return "?"
    return node.describe()


def _numbered(root: Node) -> dict[int, int]:
    """Stable ids in depth-first order (node uids differ between processes)."""
    return {id(n): k for k, n in enumerate(root.walk())}


def to_pydot(root: Node, *, name: str = "bt"):
    """The tree as a ``pydot.Dot`` graph (top-down, children in tick order)."""
    import pydot

    graph = pydot.Dot(name, graph_type="digraph", rankdir="TB", ordering="out")
    graph.set_node_defaults(fontname="Helvetica", fontsize="10", style="filled")
    ids = _numbered(root)
    for n in root.walk():
        nid = f"n{ids[id(n)]}"
        colour = COLOURS.get(n.status, "#ffffff")
        if isinstance(n, Condition):
            shape, style = "ellipse", "filled"
        elif isinstance(n, ActionNode):
            shape, style = "box", "filled,rounded"
        else:
            shape, style = "box", "filled"
        label = _symbol(n).replace('"', "'")
        graph.add_node(
            pydot.Node(nid, label=f'"{label}"', shape=shape, style=style, fillcolor=colour)
        )
        if n.parent is not None:
            graph.add_edge(pydot.Edge(f"n{ids[id(n.parent)]}", nid))
    return graph


def to_dot(root: Node) -> str:
    return to_pydot(root).to_string()


def write_dot(root: Node, path: str | Path) -> Path:
    p = Path(path)
    p.write_text(to_dot(root), encoding="utf-8")
    return p


def render_png(root: Node, path: str | Path) -> Path:
    """Render with Graphviz ``dot`` (installed system-wide) to a PNG file."""
    p = Path(path)
    to_pydot(root).write(str(p), format="png")  # what pydot's generated write_png calls
    return p


# -- BehaviorTree.CPP v4 -------------------------------------------------------------------
def _pred_ports(pred: Predicate) -> dict[str, str]:
    out = {}
    for f in dataclasses.fields(pred):
        value = getattr(pred, f.name)
        if f.name == "d" and value == DEFAULT_REACH:
            continue
        out[f.name] = f"{value:g}" if isinstance(value, float) else str(value)
    return out


def _element(node: Node, models: dict[str, tuple[str, tuple[str, ...]]]) -> ET.Element:
    if isinstance(node, Condition):
        ports = _pred_ports(node.pred)
        models.setdefault(node.pred.name, ("Condition", tuple(ports)))
        el = ET.Element(node.pred.name, {"name": str(node.pred), **ports})
        return el
    if isinstance(node, ActionNode):
        a = node.action
        ports = dict(zip(a.template.param_names, a.args, strict=True))
        models.setdefault(a.name, ("Action", tuple(a.template.param_names)))
        return ET.Element(a.name, {"name": str(a), **ports})
    if isinstance(node, Sequence):
        el = ET.Element("SequenceWithMemory" if node.memory else "Sequence")
    elif isinstance(node, ReactiveSequence):
        el = ET.Element("ReactiveSequence")
    elif isinstance(node, ReactiveFallback):
        el = ET.Element("ReactiveFallback")
    elif isinstance(node, PriorityFallback):
        models.setdefault("PriorityFallback", ("Control", ("priorities",)))
        el = ET.Element(
            "PriorityFallback", {"priorities": ";".join(f"{p:g}" for p in node.priorities)}
        )
    elif isinstance(node, Fallback):
        el = ET.Element("Fallback")
    else:  # pragma: no cover - every kind is handled above
        raise TypeError(f"cannot export {node!r}")
    for c in node.children:
        el.append(_element(c, models))
    return el


def to_btcpp_xml(root: Node, *, tree_id: str = "MainTree") -> str:
    """BehaviorTree.CPP v4 XML of the tree, with a TreeNodesModel for Groot."""
    models: dict[str, tuple[str, tuple[str, ...]]] = {}
    doc = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": tree_id})
    bt = ET.SubElement(doc, "BehaviorTree", {"ID": tree_id})
    bt.append(_element(root, models))
    model = ET.SubElement(doc, "TreeNodesModel")
    for node_id, (kind, ports) in sorted(models.items()):
        el = ET.SubElement(model, kind, {"ID": node_id})
        for p in ports:
            ET.SubElement(el, "input_port", {"name": p})
    ET.indent(doc, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(doc, encoding="unicode")


def write_btcpp_xml(root: Node, path: str | Path) -> Path:
    p = Path(path)
    p.write_text(to_btcpp_xml(root) + "\n", encoding="utf-8")
    return p


def from_btcpp_xml(text: str, domain) -> Node:
    """Read back a tree written by `to_btcpp_xml` (the node kinds of this package only)."""
    from tamp.world.predicates import PREDICATES, IsRobotCloseTo

    doc = ET.fromstring(text)
    bt = doc.find("BehaviorTree")
    if bt is None or len(bt) != 1:
        raise ValueError("expected one <BehaviorTree> with one root node")

    def build(el: ET.Element) -> Node:
        tag, attrs = el.tag, dict(el.attrib)
        attrs.pop("name", None)
        children = [build(c) for c in el]
        if tag in ("Sequence", "SequenceWithMemory"):
            return Sequence(children, memory=tag == "SequenceWithMemory")
        if tag == "Fallback":
            return Fallback(children)
        if tag == "ReactiveSequence":
            return ReactiveSequence(children)
        if tag == "ReactiveFallback":
            return ReactiveFallback(children)
        if tag == "PriorityFallback":
            pri = [float(p) for p in attrs.get("priorities", "").split(";") if p]
            return PriorityFallback(children, pri)
        if tag in PREDICATES:
            cls, _ = PREDICATES[tag]
            if cls is IsRobotCloseTo:
                return Condition(IsRobotCloseTo(attrs["ref"], float(attrs.get("d", DEFAULT_REACH))))
            names = [f.name for f in dataclasses.fields(cls)]
            return Condition(cls(*(attrs[n] for n in names)))
        if tag in domain.templates:
            t = domain.templates[tag]
            return ActionNode(domain.action(tag, *(attrs[p] for p in t.param_names)))
        raise ValueError(f"unknown node {tag!r}")

    return build(bt[0])
