"""DOT (pydot) and BehaviorTree.CPP v4 XML exports of the grown Case 3 tree."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pydot
import pytest

from tamp import scenarios
from tamp.bt import Appear
from tamp.bt.export import COLOURS, from_btcpp_xml, to_btcpp_xml, to_dot
from tamp.bt.nodes import ActionNode, Condition, PriorityFallback
from tamp.bt.run import execute_plan
from tamp.demo import load_demonstration
from tamp.rg import plan
from tamp.world import Point, default_domain
from tamp.world.interface import Status

pytestmark = pytest.mark.filterwarnings("ignore:'setParseAction' deprecated")


@pytest.fixture(scope="module")
def grown():
    demo = load_demonstration(scenarios.path("case3.yaml"))
    report = execute_plan(demo, plan(demo).c_goal, events=[Appear("Oa", Point(2.2, 0.8, 0.1))])
    assert report.reached
    return report.executor.root


def _shape(node) -> tuple:
    if isinstance(node, Condition):
        return ("C", str(node.pred))
    if isinstance(node, ActionNode):
        return ("A", str(node.action))
    extra = tuple(node.priorities) if isinstance(node, PriorityFallback) else ()
    return (node.describe().split("[")[0], extra, tuple(_shape(c) for c in node.children))


def test_dot_has_every_node_edge_and_status_colour(grown) -> None:
    (graph,) = pydot.graph_from_dot_data(to_dot(grown))
    nodes = [n for n in graph.get_nodes() if n.get_name() not in ("node", "graph", "edge")]
    assert len(nodes) == grown.size()
    assert len(graph.get_edges()) == grown.size() - 1
    fills = {n.get_attributes()["fillcolor"].strip('"') for n in nodes}
    assert COLOURS[Status.SUCCESS] in fills and COLOURS[Status.FAILURE] in fills
    labels = {n.get_attributes()["label"].strip('"') for n in nodes}
    assert "Place(O1, free2)" in labels and "IsAreaFree(L1)" in labels


def test_btcpp_xml_is_v4_with_a_node_model(grown) -> None:
    doc = ET.fromstring(to_btcpp_xml(grown))
    assert doc.tag == "root" and doc.get("BTCPP_format") == "4"
    tree = doc.find("BehaviorTree")
    assert tree.get("ID") == doc.get("main_tree_to_execute")
    assert tree[0].tag == "SequenceWithMemory"
    assert sum(1 for _ in tree.iter()) - 1 == grown.size()
    model = {el.get("ID"): el.tag for el in doc.find("TreeNodesModel")}
    assert model["PriorityFallback"] == "Control"
    assert model["Pick"] == "Action" and model["IsAreaFree"] == "Condition"
    place = next(el for el in tree.iter("Place") if el.get("l") == "free2")
    assert place.get("o") == "O1"


def test_btcpp_xml_round_trip_gives_the_same_tree(grown) -> None:
    back = from_btcpp_xml(to_btcpp_xml(grown), default_domain())
    assert _shape(back) == _shape(grown)
