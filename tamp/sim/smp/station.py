"""The SMP-MRO station: `build_station` builds the Drake diagram of a `SimScenario` (one
function, one named Diagram) and returns its handles (`SmpStation`).

    MultibodyPlant + SceneGraph  (tamp/models/sdf: floor, youBot-like robot, objects, area discs)
      body_poses ─► WorldStateEstimator ─► world_state ─► BtExecutor ─► skill_command
      skill_command, robot state, body_poses ─► YouBotSkillController ─► desired_state (PD)
      YouBotSkillController.grasp ─► WorldStateEstimator, and the weld switch of `SimRunner`
    mast RgbdSensor ─► Perception ─► ObjectPoseEstimator ─► body_poses (``perception: camera``)
    MeshcatVisualizer (optional)

Exported ports of the Diagram: ``skill_command``, ``skill_status``, ``world_state``,
``robot_state`` (the youBot's plant state) and ``body_poses``.

Plant settings come from Drake's `MultibodyPlantConfig` (discrete SAP solver, needed by
weld constraints; hydroelastic contact for the objects on the floor). The robot's joints
are driven by the plant's PD-controlled actuators (`PdControllerGains`, implicit in SAP)
tracking the controller's desired state; gravity is switched off for the robot only
(ideal gravity compensation, as the real youBot's controllers provide), objects fall.

Grasps (``grasp:`` of the scenario). ``weld``: weld constraints, two per graspable object
(`tamp.sim.smp.ik.grasp_transform`), added before `Finalize`, all inactive at the start,
switched between simulation steps by `SimRunner` (see `tamp.sim.smp.runner`), never inside
an event. ``friction``: no weld at all; the fingers squeeze the object (their PD force) and
friction holds it, so a poor grasp slips. A run's drawn friction coefficient
(`RunConditions.friction`) replaces the objects' SDF coefficients. Each object is its kind's
SDF (packaged, or declared by the scenario: `tamp.sim.smp.object_models.object_sdf`) as one
model instance named by the object's id.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometrySet
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import (
    MultibodyPlant,
)
from pydrake.multibody.tree import PdControllerGains
from pydrake.systems.framework import Diagram, DiagramBuilder

from tamp.sim.core.executor import BtExecutor, Policy
from tamp.sim.core.models import model_url, sdf_path
from tamp.sim.core.plant import add_sap_plant
from tamp.sim.core.recording import add_visualizer
from tamp.sim.smp.estimator import WorldStateEstimator
from tamp.sim.smp.ik import grasp_transform
from tamp.sim.smp.object_models import object_sdf
from tamp.sim.smp.robot import CAMERA, HOME_ARM, ROBOT, grasped_kinds
from tamp.sim.smp.scenario import SimScenario
from tamp.sim.smp.skills import YouBotSkillController
from tamp.world.geometry import Area


@dataclass
class SmpStation:
    """The built diagram and the handles the runner, tests and notebooks need."""

    diagram: Diagram
    plant: MultibodyPlant
    scenario: SimScenario
    robot: Any  # ModelInstanceIndex
    bodies: dict[str, Any]  # object id -> RigidBody
    welds: dict[tuple[str, int], Any]  # (object id, variant) -> MultibodyConstraintId
    executor: BtExecutor
    skills: YouBotSkillController
    estimator: WorldStateEstimator
    areas: dict[str, Area]
    visualizer: Any = None
    meshcat: Any = None  # pydrake.geometry.Meshcat
    q_start: np.ndarray = field(default_factory=lambda: np.zeros(len(ROBOT.joints)))
    perception: Any = None  # ObjectPoseEstimator (perception: camera), else None


def area_marker_sdf(name: str, radius: float, free: bool) -> str:
    """The SDF of an area's floor marker: a translucent disc of ``radius``, grey for a free
    area, green for a goal (also rendered for the mast camera's detector data)."""
    text = sdf_path("area_marker").read_text()
    text = text.replace('<model name="area_marker">', f'<model name="area_{name}">')
    text = re.sub(r"<radius>[^<]*</radius>", f"<radius>{radius:.4f}</radius>", text, count=1)
    if free:
        text = text.replace("0.2 0.75 0.3 0.35", "0.6 0.6 0.6 0.35")
    return text


def _add_camera(builder, plant, scene_graph, scenario: SimScenario, robot, bodies, kinds, palm):
    """The mast camera, depth noise, the detector and the pose estimator (wired)."""
    from tamp.sim.core.camera import DepthNoise, add_rgbd_camera, camera_config, look_at
    from tamp.sim.core.detector import shipped
    from tamp.sim.core.perception import DetectorNoise, LabelOracle, Perception, Region
    from tamp.sim.smp.mast_data import ABOVE_FLOOR, FLOOR
    from tamp.sim.smp.mast_data import WEIGHTS_FILE as MAST_WEIGHTS
    from tamp.sim.smp.perception import VIEW_SIDE, ObjectPoseEstimator, prior_poses

    base = plant.GetBodyByName(ROBOT.base_body, robot)
    X_BC = look_at(CAMERA.position, CAMERA.target)
    config = camera_config(
        name="mast_camera", width=CAMERA.width, height=CAMERA.height, fov_y_deg=CAMERA.fov_y_deg
    )
    camera, K = add_rgbd_camera(builder, plant, scene_graph, base, X_BC, config)
    run = scenario.conditions
    # the classes are the object models' (identity is the estimator's: by position)
    task_classes = sorted({k.name for k in kinds.values()})
    noise = None if run.detector is None else DetectorNoise(run.detector, run.seed)
    if scenario.detector == "learned":  # colour + depth + the camera's pose: no label input
        xmin, xmax, ymin, ymax = scenario.workspace
        # the floor is the known support (`mast_data.FLOOR`, `ABOVE_FLOOR`), as in training
        floor = Region(
            ((xmin + xmax) / 2, (ymin + ymax) / 2),
            (xmax - xmin, ymax - ymin),
            floor=FLOOR,
            above=ABOVE_FLOOR,
        )
        source = dict(source=shipped(MAST_WEIGHTS), regions={VIEW_SIDE: floor})
    else:
        labels = {int(b.index()): kinds[uid].name for uid, b in bodies.items()}
        source = dict(source=LabelOracle(labels))
    # with the intrinsics and each request's camera pose perception places what it sees (a
    # noisy detector's jumps and false positives too, whichever detector reads the views)
    detector = builder.AddSystem(
        Perception(
            **source,
            intrinsics=K,
            width=CAMERA.width,
            height=CAMERA.height,
            period=CAMERA.period,
            noise=noise,
            task_classes=task_classes,
        )
    )
    depth = camera.depth_image_32F_output_port()
    if run.depth_noise > 0:
        noise = builder.AddSystem(
            DepthNoise(
                width=CAMERA.width,
                height=CAMERA.height,
                sigma=run.depth_noise,
                seed=run.seed,
                period=CAMERA.period,
            )
        )
        builder.Connect(depth, noise.depth_in)
        depth = noise.depth_out
    builder.Connect(depth, detector.depth_port)
    if detector.label_port is not None:
        builder.Connect(camera.label_image_output_port(), detector.label_port)
    builder.Connect(camera.color_image_output_port(), detector.color_port)
    shown = {uid: (x, y, yaw) for uid, x, y, yaw in run.nominal}
    objects = [
        dataclasses.replace(o, xy=shown[o.id][:2], yaw=shown[o.id][2]) if o.id in shown else o
        for o in scenario.objects
    ]
    estimator = builder.AddSystem(
        ObjectPoseEstimator(
            bodies={k: int(b.index()) for k, b in bodies.items()},
            kinds=kinds,
            prior=prior_poses(objects, scenario.parking),
            camera_body=int(base.index()),
            X_BC=X_BC,
            intrinsics=K,
            palm_body=int(palm.index()),
            grasp_offset=ROBOT.grasp_offset,
            period=CAMERA.period,
            pose_noise=run.pose_noise,
            seed=run.seed,
        )
    )
    builder.Connect(detector.observation_port, estimator.observation_port)
    builder.Connect(estimator.view_request_port, detector.request_port)
    return estimator


def build_station(scenario: SimScenario, policy: Policy, *, meshcat: Any = None) -> SmpStation:
    """The named Diagram of ``scenario`` with ``policy`` (the grown BT) in the BtExecutor."""
    builder = DiagramBuilder()
    plant, scene_graph, parser = add_sap_plant(
        builder, time_step=scenario.plant.time_step, contact_model=scenario.plant.contact_model
    )

    (floor,) = parser.AddModelsFromUrl(model_url("floor"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("floor", floor))
    areas = scenario.areas
    free_names = {a.name for a in scenario.demo.free_areas}
    for name, area in areas.items():
        (m,) = parser.AddModelsFromString(
            area_marker_sdf(name, area.radius, name in free_names), "sdf"
        )
        plant.WeldFrames(
            plant.world_frame(),
            plant.GetFrameByName("marker", m),
            RigidTransform([area.pos.x, area.pos.y, 0.0]),
        )

    (robot,) = parser.AddModelsFromUrl(ROBOT.url)
    rx, ry, ryaw = scenario.robot_start
    q_start = np.zeros(len(ROBOT.joints))
    q_start[0:3] = (rx, ry, ryaw)
    q_start[3:8] = HOME_ARM
    q_start[8:10] = ROBOT.finger_open
    for k, name in enumerate(ROBOT.joints):
        joint = plant.GetJointByName(name, robot)
        joint.set_default_positions([q_start[k]])
        actuator = plant.GetJointActuatorByName(name, robot)
        kp, kd = ROBOT.gains(name)
        actuator.set_controller_gains(PdControllerGains(p=kp, d=kd))

    bodies = {}
    kinds = {}
    welds = {}
    palm = plant.GetBodyByName(ROBOT.palm_body, robot)
    parser.SetAutoRenaming(True)
    for i, obj in enumerate(scenario.objects):
        text = object_sdf(obj.kind, obj.id, scenario.conditions.friction)
        (m,) = parser.AddModelsFromString(text, "sdf")
        body = plant.GetBodyByName(obj.kind.body, m)
        if obj.appear is None:
            x, y = obj.xy
        else:
            x, y = scenario.parking(i)
        X = RigidTransform(RotationMatrix.MakeZRotation(obj.yaw), [x, y, obj.kind.half_height])
        plant.SetDefaultFloatingBaseBodyPose(body, X)
        bodies[obj.id] = body
        kinds[obj.id] = obj.kind
        for variant in (0, 1) if scenario.grasp == "weld" else ():
            welds[(obj.id, variant)] = plant.AddWeldConstraint(
                palm, grasp_transform(obj.kind, variant), body, RigidTransform()
            )

    kinds = grasped_kinds(kinds, scenario.grasp)
    plant.mutable_gravity_field().set_enabled(robot, False)
    plant.Finalize()

    # the robot does not collide with itself (its links overlap at the joints)
    robot_geoms = []
    for index in plant.GetBodyIndices(robot):
        robot_geoms += plant.GetCollisionGeometriesForBody(plant.get_body(index))
    scene_graph.collision_filter_manager().Apply(
        CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_geoms))
    )

    actuator_order = []
    for index in plant.GetJointActuatorIndices(robot):
        name = plant.get_joint_actuator(index).joint().name()
        actuator_order.append(ROBOT.joints.index(name))

    estimator = builder.AddSystem(
        WorldStateEstimator(
            bodies={k: int(b.index()) for k, b in bodies.items()},
            base_body=int(plant.GetBodyByName(ROBOT.base_body, robot).index()),
            areas=areas,
            workspace=scenario.workspace,
        )
    )
    skills = builder.AddSystem(
        YouBotSkillController(
            period=scenario.executor.controller_period,
            bodies={k: int(b.index()) for k, b in bodies.items()},
            kinds=kinds,
            palm_body=int(palm.index()),
            areas=areas,
            actuator_order=actuator_order,
            q_start=q_start,
            base_limits=scenario.base,
            workspace=scenario.workspace,
            failures=scenario.failures,
            chance_failures=scenario.conditions.chance_failures,
            grasp=scenario.grasp,
            perception=scenario.perception,
        )
    )
    executor = builder.AddSystem(BtExecutor(policy, period=scenario.executor.bt_period))

    poses = plant.get_body_poses_output_port()
    perception = None
    if scenario.perception == "camera":  # object poses from images, not from the plant
        perception = _add_camera(builder, plant, scene_graph, scenario, robot, bodies, kinds, palm)
        builder.Connect(poses, perception.body_poses_in)
        builder.Connect(skills.grasp_port, perception.grasp_port)
        poses = perception.body_poses_port
    builder.Connect(poses, estimator.body_poses_port)
    builder.Connect(poses, skills.body_poses_port)
    builder.Connect(plant.get_state_output_port(robot), skills.robot_state_port)
    builder.Connect(skills.grasp_port, estimator.grasp_port)
    builder.Connect(estimator.world_state_port, executor.world_state_port)
    builder.Connect(skills.status_port, executor.skill_status_port)
    builder.Connect(executor.command_port, skills.command_port)
    builder.Connect(skills.desired_state_port, plant.get_desired_state_input_port(robot))

    builder.ExportOutput(executor.command_port, "skill_command")
    builder.ExportOutput(skills.status_port, "skill_status")
    builder.ExportOutput(estimator.world_state_port, "world_state")
    builder.ExportOutput(plant.get_state_output_port(robot), "robot_state")
    builder.ExportOutput(plant.get_body_poses_output_port(), "body_poses")

    visualizer = None
    if meshcat is not None:
        visualizer = add_visualizer(builder, scene_graph, meshcat)

    diagram = builder.Build()
    diagram.set_name(f"smp_mro_{scenario.name}")
    return SmpStation(
        diagram=diagram,
        plant=plant,
        scenario=scenario,
        robot=robot,
        bodies=bodies,
        welds=welds,
        executor=executor,
        skills=skills,
        estimator=estimator,
        areas=areas,
        visualizer=visualizer,
        meshcat=meshcat,
        q_start=q_start,
        perception=perception,
    )
