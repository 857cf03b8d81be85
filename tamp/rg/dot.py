"""DOT export of the reachability graph with the chosen order highlighted (pydot)."""

from __future__ import annotations

import networkx as nx
import pydot

from tamp.demo.model import Demonstration


def _label(demo: Demonstration, places: dict[str, str]) -> str:
    parts = []
    for obj in demo.objects:
        where = places[obj]
        parts.append(f"{obj}∈{'P' + obj[1:] if where == 'P' else where}")
    return "\\n".join(parts)


def rg_to_dot(demo: Demonstration, rg: nx.DiGraph, order: list[str] | None = None) -> pydot.Dot:
    """One node per RG state (object places), edges labelled by goal; chosen path in bold."""
    dot = pydot.Dot("RG", graph_type="digraph", rankdir="TB")
    dot.set_node_defaults(shape="box", style="rounded", fontname="Helvetica", fontsize="10")
    dot.set_edge_defaults(fontname="Helvetica", fontsize="9")
    names = {
        node: f"s{i}" for i, node in enumerate(sorted(rg.nodes, key=lambda s: (len(s), sorted(s))))
    }
    chosen_nodes = {frozenset()}
    chosen_edges = set()
    if order:
        done: frozenset[str] = frozenset()
        for g in order:
            nxt = done | {g}
            chosen_edges.add((done, nxt))
            chosen_nodes.add(nxt)
            done = nxt
    for node, data in rg.nodes(data=True):
        attrs = {"label": f'"{_label(demo, data["places"])}"'}
        if node in chosen_nodes:
            attrs.update(color="firebrick", penwidth="2")
        # obj_dict given (its default) so that the str-valued **attrs cannot bind to it
        dot.add_node(pydot.Node(names[node], obj_dict=None, **attrs))
    for u, v, data in rg.edges(data=True):
        attrs = {"label": data["goal"], "style": "dashed"}
        if (u, v) in chosen_edges:
            attrs.update(style="bold", color="firebrick", penwidth="2.5")
        dot.add_edge(pydot.Edge(names[u], names[v], **attrs))
    return dot
