"""The scripted person in the Drake workcell (`tamp.sim.lots.person`): the staging shelf, the
hand's trips and what it carries, the robot actions it counts, the CLI's input checks; and
the paper's narratives end to end (slow)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from tamp.lots.person import ScriptedPerson
from tamp.lots.task import Event, load_events, load_task
from tamp.sim.lots.catalogue import CLASSES, HAND_LABEL, PERSON
from tamp.sim.lots.person import (
    GRIP_GAP,
    REACTION,
    STAGING,
    box_gap,
    free_spot,
    on_shelf,
    shelf_spot,
    staged_objects,
)
from tamp.sim.lots.scenario import load_cell_scenario
from tests.sim.lots.helpers import write_scenario

TASK = {
    "version": 1,
    "name": "t",
    "formula": "F p1",
    "propositions": {"p1": {"class": "body"}},
    "initial": {"A": {"body": 1}},
}


def _files(tmp_path, events: list[dict]):
    (tmp_path / "task.yaml").write_text(yaml.safe_dump(TASK))
    (tmp_path / "ev.yaml").write_text(yaml.safe_dump({"version": 1, "events": events}))
    task = load_task(tmp_path / "task.yaml")
    return task, load_events(tmp_path / "ev.yaml", task)


def test_staged_objects_wait_on_the_shelf_one_per_added_object():
    events = [
        Event(after=1, kind="add", cls="body", side="B", count=2),
        Event(after=2, kind="remove", cls="body", side="B"),
        Event(after=3, kind="add", cls="toy_car", side="A"),
    ]
    staged = staged_objects(events, load_cell_scenario("tower"))
    assert [o.id for o in staged] == ["person_body_1", "person_body_2", "person_toy_car_3"]
    assert {o.workspace for o in staged} == {STAGING}
    assert [o.xy for o in staged] == [shelf_spot(0), shelf_spot(1), shelf_spot(2)]
    for o in staged:
        assert on_shelf(*o.xy, 0.0)
        assert o.xy[0] - PERSON.shelf_center[0] == 0.0
    # out of the table (x <= 0.9) and so out of every camera view
    assert all(o.xy[0] - PERSON.shelf_size[0] / 2 > 0.9 for o in staged)
    assert len({o.xy for o in staged}) == 3
    assert HAND_LABEL > 255  # never a body index of the cell


def test_due_returns_each_scripted_event_once_in_its_slot():
    ev = [
        Event(after=0, kind="add", cls="body", side="B"),
        Event(after=1, kind="remove", cls="body", side="B", phase="holding"),
        Event(after=2, kind="move", cls="body", src="B", dst="A"),
    ]
    p = ScriptedPerson(ev)
    assert [(n, ph, e.kind) for n, ph, e in p.due(0, False)] == [(0, "idle", "add")]
    assert p.due(0, False) == []
    assert [(n, ph) for n, ph, _ in p.due(1, False)] == []  # (0, holding), (1, idle): none
    assert [(n, ph, e.kind) for n, ph, e in p.due(1, True)] == [(1, "holding", "remove")]
    assert [(n, e.kind) for n, _, e in p.due(2, False)] == [(2, "move")]
    assert p.unfired() == []


def test_the_person_puts_an_object_down_clear_of_the_others_footprints():
    """Fig. 9 in the cell: the person put the wrench where its origin was farthest from the
    others' origins, and its 16 cm bar lay on the hammer's head (lifting the hammer then made
    the plant non-finite). The spot now keeps the footprints apart."""
    from tamp.sim.lots.scenario import Workspace

    w = Workspace(name="A", center=(0.5, 0.25), size=(0.34, 0.34))
    lying = [  # W^A when the wrench came in that run: class, x, y, yaw
        ("hammer", 0.387, 0.142, 0.105),
        ("scissors", 0.416, 0.261, math.pi),
        ("scissors", 0.57, 0.32, -0.203),
    ]
    others = [CLASSES[c].footprint.corners(x, y, yaw) for c, x, y, yaw in lying]
    f, yaw = CLASSES["wrench"].footprint, -0.022
    x, y = free_spot(w, f, yaw, others)
    assert min(box_gap(f.corners(x, y, yaw), o) for o in others) > 0.004  # clear of all three
    assert box_gap(f.corners(0.535, 0.202, yaw), others[0]) == 0.0  # where it lay: overlapping
    assert free_spot(w, f, yaw, []) == w.center


def test_box_gap():
    unit = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert box_gap(unit, unit + [3.0, 0.0]) == pytest.approx(2.0)
    assert box_gap(unit, unit + [0.5, 0.5]) == 0.0
    diamond = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]]) + [3.0, 0.5]
    assert box_gap(unit, diamond) == pytest.approx(1.0)


def _person_cell(tmp_path, events: list[dict], objects: list[dict]):
    """The cell's plant (no camera, no skills) with the person, its robot inputs fixed to
    ``Place(B)`` #1 SUCCESS: one robot action done."""
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    from tamp.sim.core.messages import SkillCommand, SkillStatus
    from tamp.sim.lots.person import PersonSystem
    from tamp.sim.lots.plant import add_cell_plant
    from tamp.world.interface import Status

    _, ev = _files(tmp_path, events)
    scenario = load_cell_scenario(write_scenario(tmp_path, objects))
    builder = DiagramBuilder()
    cell = add_cell_plant(builder, scenario, staged_objects(ev, scenario))
    plant = cell.plant
    person = builder.AddSystem(
        PersonSystem(plant, scenario, ev, cell.bodies, cell.classes, cell.hand, cell.staged)
    )
    builder.Connect(plant.get_body_poses_output_port(), person.poses_port)
    builder.Connect(plant.get_body_spatial_velocities_output_port(), person.velocities_port)
    builder.Connect(person.desired_state_port, plant.get_desired_state_input_port(cell.hand))
    builder.Connect(person.forces_port, plant.get_applied_spatial_force_input_port())
    diagram = builder.Build()
    sim = Simulator(diagram)
    root = sim.get_mutable_context()
    pc = person.GetMyContextFromRoot(root)
    person.command_port.FixValue(pc, SkillCommand(1, "Place", ("B",)))
    person.status_port.FixValue(pc, SkillStatus(1, Status.SUCCESS))
    plant.get_desired_state_input_port(cell.arm).FixValue(
        plant.GetMyContextFromRoot(root), np.r_[cell.q0[cell.actuator_order], np.zeros(9)]
    )
    return sim, cell, person


def test_the_hand_carries_an_object_between_workspaces_and_parks(tmp_path):
    """A removal of what is not there is skipped; one move (dis_1) after the robot's first
    action: the hand goes over the body, takes it, carries it (the body keeps its pose in
    the hand), puts it down in W^B, parks."""
    sim, cell, person = _person_cell(
        tmp_path,
        [
            {"after": 0, "kind": "remove", "class": "peak", "side": "B"},
            {"after": 1, "kind": "move", "class": "body", "from": "A", "to": "B"},
            {"after": 2, "kind": "add", "class": "peak", "side": "A"},
        ],
        [{"class": "body", "workspace": "A", "xy": [0.02, -0.03], "yaw": 30}],
    )
    plant = cell.plant
    root = sim.get_mutable_context()
    pc, mc = person.GetMyContextFromRoot(root), plant.GetMyContextFromRoot(root)
    hand = plant.GetBodyByName(PERSON.hand_body, cell.hand)
    body = cell.bodies["body_0"]
    start = plant.EvalBodyPoseInWorld(mc, body)
    offsets, took, curtain = [], None, []
    t = 0.0
    while t < 7.0:
        t += 0.1
        sim.AdvanceTo(t)
        s = person.state(pc)
        x = plant.EvalBodyPoseInWorld(mc, hand).translation()[0]
        curtain.append((x < PERSON.curtain_x, person.present_port.Eval(pc)[0] == 1.0))
        if s.carrying == "body_0":
            X_HO = plant.EvalBodyPoseInWorld(mc, hand).inverse() @ plant.EvalBodyPoseInWorld(
                mc, body
            )
            took = took if took is not None else s.X_HO[:3, 3].copy()
            offsets.append(np.linalg.norm(X_HO.translation() - s.X_HO[:3, 3]))
        if s.idle and s.actions and s.move is None:
            break
    s = person.state(pc)
    skip, act = s.actions  # the add after action 2 never comes: the robot did one action
    assert skip.outcome == "skipped" and skip.detail == "no peak in W^B"  # nothing to remove
    assert act.outcome == "done" and act.uid == "body_0" and (act.src, act.dst) == ("A", "B")
    assert act.start == pytest.approx(REACTION, abs=0.03) and 3.0 < act.end < 6.5
    assert [e.kind for e in s.script.unfired()] == ["add"]
    # the palm took the body from above: right over its top, centred on its footprint
    assert took is not None
    assert took[2] == pytest.approx(-(CLASSES["body"].height + GRIP_GAP), abs=0.004)
    assert np.linalg.norm(took[:2]) < 0.01
    # the light curtain: on exactly while the hand is on the robot's side; off when parked
    assert all(inside == on for inside, on in curtain)
    assert curtain[0] == (False, False) and any(on for _, on in curtain)
    # carried: the body kept its place in the hand (the carrying force holds it within 5 mm)
    assert len(offsets) >= 10 and max(offsets) < 0.005
    end = plant.EvalBodyPoseInWorld(mc, body)
    w = person.scenario.workspaces["B"]
    x, y, z = end.translation()
    assert w.contains(x, y) and abs(z) < 0.003
    # put down upright with the yaw it had
    assert end.rotation().matrix()[2, 2] > 0.999
    cos = np.dot(end.rotation().matrix()[:2, 0], start.rotation().matrix()[:2, 0])
    assert cos > 0.99
    # the hand is back at its park position, away from the table
    sim.AdvanceTo(t + 2.0)
    p = plant.EvalBodyPoseInWorld(mc, hand).translation()
    assert np.linalg.norm(p - np.array(PERSON.park)) < 0.01


def test_the_persons_light_curtain_wakes_the_safety_monitor():
    """With a scripted person the monitor's ``person_present`` is the person's curtain (not
    an exported input); the controller side still gets nothing of the person."""
    from tamp.sim.lots.station import build_station

    task = load_task("tower")
    cell = build_station(
        load_cell_scenario("tower"), person=load_events("tower_interference", task)
    )
    conn = cell.diagram.connection_map()
    src = conn[(cell.safety, cell.safety.present_port.get_index())]
    assert src[0] is cell.person and src[1] == cell.person.present_port.get_index()
    assert not cell.diagram.HasInputPort("person_present")


def test_hand_pixels_carry_the_hand_label(tmp_path):
    """Every visual of the hand is labelled HAND_LABEL; its collision box touches nothing."""
    from pydrake.geometry import Role

    sim, cell, _ = _person_cell(tmp_path, [], [])
    plant = cell.plant
    inspector = cell.scene_graph.model_inspector()
    hand = plant.GetBodyByName(PERSON.hand_body, cell.hand)
    gids = plant.GetVisualGeometriesForBody(hand)
    assert len(gids) >= 3
    for gid in gids:
        props = inspector.GetPerceptionProperties(gid)
        assert props.GetProperty("label", "id") == HAND_LABEL
    (palm,) = plant.GetCollisionGeometriesForBody(hand)
    others = [g for g in inspector.GetAllGeometryIds(Role.kProximity) if g != palm]
    assert others and all(inspector.CollisionFiltered(palm, g) for g in others)


def _cli(*args: str):
    from tamp.commands.main import main

    return main(["simulate", "lots", *args])


def test_cli_refuses_a_bad_interference_file_naming_the_field(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"version": 1, "events": [{"after": 1, "kind": "teleport"}]}))
    assert _cli("tower", "--interference", str(bad)) == 2
    assert "events[0].kind" in capsys.readouterr().err
    alien = tmp_path / "alien.yaml"
    alien.write_text(
        yaml.safe_dump(
            {"version": 1, "events": [{"after": 1, "kind": "add", "class": "ufo", "side": "B"}]}
        )
    )
    assert _cli("tower", "--interference", str(alien)) == 2
    err = capsys.readouterr().err
    assert "events[0].class" in err and "no 'ufo' objects" in err
