"""The LOTS workcell's MultibodyPlant: table, arm, baskets, objects (friction grasps, SAP).

Plant settings come from Drake's `MultibodyPlantConfig`: the discrete SAP solver and
hydroelastic contact (with point-contact fallback): the objects and finger pads are
compliant-hydroelastic boxes, the table and baskets rigid, so objects rest steadily on flat
faces and a closed gripper holds an object only by friction. Nothing is welded to the hand.

The arm's joints are driven by the plant's PD-controlled actuators (`PdControllerGains`,
implicit in SAP) tracking a desired state; gravity is switched off for the arm's model
instance only, which is ideal gravity compensation (Franka's controller compensates the
arm's own gravity too). Objects, and so a held object's weight, feel gravity. The finger
actuators' effort limit (40 N, from the SDF) bounds the squeeze force.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import (
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    CollisionFilterDeclaration,
    GeometrySet,
    PerceptionProperties,
    ProximityProperties,
    RenderLabel,
    Rgba,
    Role,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import PdControllerGains

from tamp.sim.core.models import absolute_uris, renamed_model, with_friction
from tamp.sim.core.plant import add_sap_plant
from tamp.sim.lots.catalogue import (
    ARM,
    HAND_LABEL,
    PERSON,
    READY,
    TABLE_URL,
    TRAY_URL,
    WASTE_BASKET_URL,
    ObjectClass,
)
from tamp.sim.lots.scenario import CellObject, CellScenario

#: colours of the workspace mats (W^A green, W^B blue), drawn 1 mm above the table
MAT_RGBA = {"A": (0.55, 0.75, 0.55, 1.0), "B": (0.55, 0.65, 0.85, 1.0)}


@dataclass
class CellPlant:
    """The plant and the handles the builder, skills and tests need."""

    plant: MultibodyPlant
    scene_graph: object
    arm: object  # ModelInstanceIndex
    bodies: dict[str, object]  # object id -> RigidBody
    classes: dict[str, str]  # object id -> class
    q0: np.ndarray  # the arm's 9 positions at the start (7 joints + 2 fingers)
    actuator_order: list[int]  # actuator k drives ARM.joints[actuator_order[k]]
    hand: object = None  # the person's hand (ModelInstanceIndex), when a person is scripted
    staged: tuple[str, ...] = ()  # ids of the objects waiting on the person's staging shelf


def object_sdf(
    c: ObjectClass, uid: str, rgb: tuple[float, float, float], friction: float | None = None
) -> str:
    """Class ``c``'s SDF text with the model renamed to ``uid``, its primary colour ``rgb``
    and, for a run with a drawn ``friction`` coefficient (``perturbation.friction``), that
    coefficient on every contact surface (relative ``<uri>``s made absolute: the text is
    parsed without its folder)."""
    text = renamed_model(c.sdf.read_text(encoding="utf-8"), uid)
    if friction is not None:
        text = with_friction(text, friction)
    if c.colour:
        colour = f"<diffuse>{rgb[0]:.3f} {rgb[1]:.3f} {rgb[2]:.3f} 1</diffuse>"
        text = re.sub(rf"<diffuse>\s*{re.escape(c.colour)}\s*</diffuse>", colour, text)
    return absolute_uris(text, c.sdf.parent)


def add_cell_plant(
    builder, scenario: CellScenario, staged: tuple[CellObject, ...] | None = None
) -> CellPlant:
    """Adds the finalised plant + scene graph of ``scenario`` to ``builder``.

    ``staged``: with a scripted person (`tamp.sim.lots.person`), the objects waiting on its
    staging shelf (workspace ``staging``, ``xy`` in the table frame); the hand and the shelf
    are added then. None: no person in the cell.
    """
    plant, scene_graph, parser = add_sap_plant(
        builder, time_step=scenario.plant.time_step, contact_model=scenario.plant.contact_model
    )
    (table,) = parser.AddModelsFromUrl(TABLE_URL)
    table_body = plant.GetBodyByName("lots_table", table)
    plant.WeldFrames(plant.world_frame(), table_body.body_frame())
    for side, w in scenario.workspaces.items():
        X = RigidTransform([w.center[0], w.center[1], 0.0005])
        plant.RegisterVisualGeometry(
            table_body, X, Box(w.size[0], w.size[1], 0.001), f"mat_{side}", np.array(MAT_RGBA[side])
        )
        if w.tray:
            (tray,) = parser.AddModelsFromUrl(TRAY_URL)
            plant.WeldFrames(
                plant.world_frame(),
                plant.GetFrameByName("lots_tray", tray),
                RigidTransform([w.center[0], w.center[1], 0.0]),
            )
    (basket,) = parser.AddModelsFromUrl(WASTE_BASKET_URL)
    bx, by = scenario.waste_basket
    plant.WeldFrames(
        plant.world_frame(),
        plant.GetFrameByName("lots_waste_basket", basket),
        RigidTransform([bx, by, 0.0]),
    )

    (arm,) = parser.AddModelsFromUrl(ARM.url)
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(ARM.base_frame, arm))
    q0 = np.r_[READY, ARM.finger_max, ARM.finger_max]
    for k, name in enumerate(ARM.joints):
        plant.GetJointByName(name, arm).set_default_positions([q0[k]])
        kp, kd = ARM.gains(name)
        plant.GetJointActuatorByName(name, arm).set_controller_gains(PdControllerGains(p=kp, d=kd))

    bodies, classes = {}, {}
    hand = None if staged is None else _add_person(plant, parser)
    friction = None if scenario.sample is None else scenario.sample.friction
    for o in (*scenario.objects, *(staged or ())):
        c = scenario.object_class(o.cls)
        (m,) = parser.AddModelsFromString(object_sdf(c, o.id, o.rgb, friction), "sdf")
        body = plant.GetBodyByName(c.body, m)
        w = scenario.workspaces.get(o.workspace)
        z = 0.01 if w is not None and w.tray else 0.0
        X = RigidTransform(RotationMatrix.MakeZRotation(o.yaw), [o.xy[0], o.xy[1], z + 1e-4])
        plant.SetDefaultFloatingBaseBodyPose(body, X)
        bodies[o.id] = body
        classes[o.id] = o.cls

    plant.mutable_gravity_field().set_enabled(arm, False)
    plant.Finalize()
    actuator_order = [
        ARM.joints.index(plant.get_joint_actuator(i).joint().name())
        for i in plant.GetJointActuatorIndices(arm)
    ]
    if hand is not None:
        _person_roles(plant, scene_graph, hand)
    staged_ids = tuple(o.id for o in staged or ())
    return CellPlant(plant, scene_graph, arm, bodies, classes, q0, actuator_order, hand, staged_ids)


def _add_person(plant: MultibodyPlant, parser) -> object:
    """The person's hand on its PD-driven prismatic joints (parked, no gravity: kinematic)
    and the staging shelf beside the table (rigid, level with the table top)."""
    (hand,) = parser.AddModelsFromUrl(PERSON.url)
    kp, kd = PERSON.gains
    for name, q in zip(PERSON.joints, PERSON.park, strict=True):
        plant.GetJointByName(name, hand).set_default_positions([q])
        plant.GetJointActuatorByName(name, hand).set_controller_gains(PdControllerGains(p=kp, d=kd))
    plant.mutable_gravity_field().set_enabled(hand, False)
    (sx, sy), (lx, ly) = PERSON.shelf_center, PERSON.shelf_size
    X = RigidTransform([sx, sy, -0.02])
    props = ProximityProperties()
    AddRigidHydroelasticProperties(props)
    AddContactMaterial(friction=CoulombFriction(0.6, 0.6), properties=props)
    plant.RegisterCollisionGeometry(plant.world_body(), X, Box(lx, ly, 0.04), "person_shelf", props)
    colour = np.array([0.6, 0.5, 0.4, 1.0])
    plant.RegisterVisualGeometry(plant.world_body(), X, Box(lx, ly, 0.04), "person_shelf", colour)
    return hand


def _person_roles(plant: MultibodyPlant, scene_graph, hand) -> None:
    """Every hand pixel carries `HAND_LABEL`; the hand's collision box touches nothing."""
    inspector = scene_graph.model_inspector()
    body = plant.GetBodyByName(PERSON.hand_body, hand)
    for gid in plant.GetVisualGeometriesForBody(body):
        old = inspector.GetPerceptionProperties(gid)
        if old is None:
            continue
        props = PerceptionProperties()
        props.AddProperty("phong", "diffuse", old.GetPropertyOrDefault("phong", "diffuse", Rgba()))
        props.AddProperty("label", "id", RenderLabel(HAND_LABEL))
        # perception roles cannot be replaced in place: remove, then assign anew
        scene_graph.RemoveRole(plant.get_source_id(), gid, Role.kPerception)
        scene_graph.AssignRole(plant.get_source_id(), gid, props)
    mine = GeometrySet(plant.GetCollisionGeometriesForBody(body))
    everything = GeometrySet(inspector.GetAllGeometryIds(Role.kProximity))
    scene_graph.collision_filter_manager().Apply(
        CollisionFilterDeclaration().ExcludeBetween(mine, everything)
    )
