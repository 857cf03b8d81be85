"""The LOTS station: `build_station` builds the workcell's Drake diagram from a
`CellScenario` (the manipulation course's station idiom: one function, one named Diagram,
exported ports) and returns its handles (`LotsStation`).

    MultibodyPlant + SceneGraph (tamp.sim.lots.plant: table, arm, baskets, objects)
      wrist RgbdSensor (CameraConfig, VTK over EGL) ─► color/depth ─► Perception
        (+ label: only for ``camera.detector: oracle``, the perfect stand-in)
      Perception.observation ─► PandaSkillController ─► ArmCommandStream (1 kHz)
        ─► SafetyMonitor ─► desired_state (the arm's PD actuators)
      SafetyMonitor.stopped ─► PandaSkillController.hold
      safety RgbdSensor (depth only, 1/4 size, at the wrist camera) ─► SafetyMonitor
      PandaSkillController.view_request ─► Perception
    PersonSystem (optional, tamp.sim.lots.person) ─► the hand's desired state, carry forces
    exported: skill_command, person_present (in; the person's curtain when scripted);
      skill_status, observation, view_request, arm_state, safety_stopped (out)
    MeshcatVisualizer, ViewLog (optional, drawn runs: every view's cloud, camera, grasps)

The camera is configured through Drake's `CameraConfig` (D435 colour intrinsics at a reduced
resolution) but added as a plain `RgbdSensor`, not through `ApplyCameraConfig`: that adds an
`RgbdSensorDiscrete` whose zero-order hold renders at ``fps`` whatever happens; a plain
sensor renders only when Perception evaluates its ports (see `tamp.sim.core.perception`).
Nothing outside the plant reads object poses: the skills see the arm's state and the
camera's answers only (a test checks the diagram's connections).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.sensors import CameraConfig, RgbdSensor

from tamp.lots.task import Event
from tamp.sim.core.camera import DepthNoise, add_rgbd_camera, camera_config
from tamp.sim.core.detector import Detector, shipped
from tamp.sim.core.perception import DetectorNoise, LabelOracle, Perception, Region
from tamp.sim.core.recording import add_visualizer
from tamp.sim.core.stack_reading import StackModel
from tamp.sim.core.timing import Stopwatch
from tamp.sim.core.view_log import ViewLog
from tamp.sim.lots.catalogue import ARM
from tamp.sim.lots.command import ArmCommandStream
from tamp.sim.lots.depth_safety import safety_camera_config
from tamp.sim.lots.grasping import GraspPlanner
from tamp.sim.lots.kinematics import ArmKinematics
from tamp.sim.lots.person import add_person, staged_objects
from tamp.sim.lots.plant import CellPlant, add_cell_plant
from tamp.sim.lots.safety import SafetyMonitor
from tamp.sim.lots.scenario import TRAY_FLOOR, TRAY_INSIDE, TRAY_OUTSIDE, CellScenario, Workspace
from tamp.sim.lots.skills import PandaSkillController
from tamp.sim.lots.stack import STACK_SIDE


@dataclass
class LotsStation:
    """The built diagram and the handles the driver, tests and notebooks need."""

    diagram: Diagram
    scenario: CellScenario
    cell: CellPlant
    camera: RgbdSensor
    camera_config: CameraConfig
    perception: Perception
    skills: PandaSkillController
    planner: GraspPlanner
    visualizer: object = None
    meshcat: Any = None
    command: ArmCommandStream | None = None
    safety: SafetyMonitor | None = None
    person: Any = None  # the PersonSystem, when a person is scripted
    #: every view's cloud, camera and target, kept when the run is drawn in Meshcat
    view_log: ViewLog | None = None

    @property
    def plant(self) -> MultibodyPlant:
        return self.cell.plant

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        return self.planner.intrinsics


def wrist_camera_config(scenario: CellScenario) -> CameraConfig:
    """The wrist camera as a `CameraConfig`: colour, depth and label at the scenario's size and
    vertical field of view (`tamp.sim.core.camera.camera_config`)."""
    cam = scenario.camera
    return camera_config(
        name="wrist_camera",
        width=cam.width,
        height=cam.height,
        fov_y_deg=cam.fov_y_deg,
        near=cam.near,
        far=cam.far,
    )


def add_wrist_camera(builder, plant, scene_graph, arm, config: CameraConfig):
    """The wrist camera (`tamp.sim.core.camera.add_rgbd_camera`) at the arm's ``camera``
    frame on the hand; (sensor, (fx, fy, cx, cy))."""
    hand = plant.GetBodyByName(ARM.hand_body, arm)
    X_HC = plant.GetFrameByName(ARM.camera_frame, arm).GetFixedPoseInBodyFrame()
    return add_rgbd_camera(builder, plant, scene_graph, hand, RigidTransform(X_HC), config)


def noisy_depth(builder, scenario: CellScenario, depth_port):
    """The depth image every consumer reads: the camera's own, or with the run's drawn
    Gaussian noise (``perturbation.sensor.depth_noise``, `DepthNoise`, seeded per frame)."""
    sigma = scenario.perturbation.depth_noise
    if sigma <= 0 or scenario.sample is None:
        return depth_port
    noise = builder.AddSystem(
        DepthNoise(
            width=scenario.camera.width,
            height=scenario.camera.height,
            sigma=sigma,
            seed=scenario.sample.seed,
            period=scenario.control.perception_period,
        )
    )
    builder.Connect(depth_port, noise.depth_in)
    return noise.depth_out


def detector_noise(scenario: CellScenario) -> DetectorNoise | None:
    """The seeded noisy detector perception applies to every view
    (``perturbation.sensor.detector``, drawn from the run's seed), or None."""
    level = scenario.perturbation.detector
    if level is None or scenario.sample is None:
        return None
    return DetectorNoise(level, scenario.sample.seed)


def region(w: Workspace) -> Region:
    """What perception knows of workspace ``w``: its rectangle and, with a tray, the tray's
    floor height and walls (a fixture of the cell, as the arm's own links are)."""
    if not w.tray:
        return Region(w.center, w.size)
    return Region(w.center, w.size, floor=TRAY_FLOOR, rim=(TRAY_INSIDE, TRAY_OUTSIDE))


def shipped_detector() -> Detector:
    """The learned detector of the wrist camera's shipped weights (`detector.shipped`:
    loaded once per process)."""
    return shipped()


def view_source(scenario: CellScenario, cell: CellPlant) -> LabelOracle | Detector:
    """What reads the wrist camera's views (``camera.detector``): the label image as a
    perfect detector (each object body's render label mapped to its class), or the learned
    detector (an object of a class it was not trained on is what it makes of it: ``unknown``
    at best; `tamp.sim.lots.simulate` refuses a task that counts such a class)."""
    if scenario.camera.detector == "oracle":
        return LabelOracle(
            {int(body.index()): cell.classes[uid] for uid, body in cell.bodies.items()}
        )
    return shipped_detector()


def stack_model(scenario: CellScenario) -> StackModel | None:
    """The stack a learned detector's views of W^B are read by (`tamp.sim.core.
    stack_reading`): the scenario's declared order with each class's height from its model;
    None without a declared stack or with the label oracle (which names every part)."""
    if not scenario.stack or scenario.camera.detector == "oracle":
        return None
    heights = tuple(scenario.object_class(c).footprint.top for c in scenario.stack)
    return StackModel(STACK_SIDE, tuple(scenario.stack), heights)


def build_station(
    scenario: CellScenario,
    *,
    meshcat: Any = None,
    person: Sequence[Event] | None = None,
) -> LotsStation:
    """The named Diagram of ``scenario``; drive it through ``skill_command`` (see `CellDriver`).

    ``person``: the events of an interference script: a scripted person's hand carries them
    out (`tamp.sim.lots.person`); None: no person in the cell.
    """
    builder = DiagramBuilder()
    staged = None if person is None else staged_objects(person, scenario)
    cell = add_cell_plant(builder, scenario, staged)
    plant, scene_graph = cell.plant, cell.scene_graph
    config = wrist_camera_config(scenario)
    camera, intrinsics = add_wrist_camera(builder, plant, scene_graph, cell.arm, config)
    perception = builder.AddSystem(
        Perception(
            view_source(scenario, cell),
            task_classes=sorted(set(cell.classes.values())),
            spans={c: scenario.object_class(c).footprint.span for c in set(cell.classes.values())},
            width=scenario.camera.width,
            height=scenario.camera.height,
            period=scenario.control.perception_period,
            intrinsics=intrinsics,
            noise=detector_noise(scenario),
            regions={side: region(w) for side, w in scenario.workspaces.items()},
            stack=stack_model(scenario),
        )
    )
    depth = noisy_depth(builder, scenario, camera.depth_image_32F_output_port())
    builder.Connect(camera.color_image_output_port(), perception.color_port)
    builder.Connect(depth, perception.depth_port)
    if perception.label_port is not None:  # the label oracle only
        builder.Connect(camera.label_image_output_port(), perception.label_port)

    kin = ArmKinematics(scenario.control.period)
    planner = GraspPlanner(scenario.grasp, intrinsics)
    skills = builder.AddSystem(
        PandaSkillController(scenario, kin, planner, cell.q0, cell.actuator_order)
    )
    builder.Connect(plant.get_state_output_port(cell.arm), skills.arm_state_port)
    builder.Connect(perception.observation_port, skills.observation_port)
    builder.Connect(skills.view_request_port, perception.request_port)
    command, safety = _add_safety(builder, scenario, cell, perception, skills)

    builder.ExportInput(skills.command_port, "skill_command")
    person_system = None
    if person is not None:
        person_system = add_person(builder, cell, plant, scenario, person, skills)
        builder.ConnectInput("skill_command", person_system.command_port)
    builder.ExportOutput(skills.status_port, "skill_status")
    builder.ExportOutput(perception.observation_port, "observation")
    builder.ExportOutput(skills.view_request_port, "view_request")
    builder.ExportOutput(plant.get_state_output_port(cell.arm), "arm_state")
    if safety is not None:
        if person_system is not None:  # the person's light curtain wakes the monitor
            builder.Connect(person_system.present_port, safety.present_port)
        else:
            builder.ExportInput(safety.present_port, "person_present")
        builder.ExportOutput(safety.stopped_port, "safety_stopped")

    visualizer = view_log = None
    if meshcat is not None:
        visualizer = add_visualizer(builder, scene_graph, meshcat)
        view_log = builder.AddSystem(
            ViewLog(
                width=scenario.camera.width,
                height=scenario.camera.height,
                period=scenario.control.perception_period,
                intrinsics=intrinsics,
            )
        )
        builder.Connect(depth, view_log.depth_port)
        builder.Connect(skills.view_request_port, view_log.request_port)
        builder.Connect(perception.observation_port, view_log.observation_port)
    diagram = builder.Build()
    diagram.set_name(f"lots_cell_{scenario.name}")
    return LotsStation(
        diagram,
        scenario,
        cell,
        camera,
        config,
        perception,
        skills,
        planner,
        visualizer,
        meshcat,
        command,
        safety,
        person_system,
        view_log,
    )


def _add_safety(builder, scenario, cell, perception, skills):
    """The arm command path: skills ─► 1 kHz command stream ─► safety monitor ─► plant
    (`tamp.sim.lots.command`, `tamp.sim.lots.safety`); without the monitor when the
    scenario's ``safety.enabled`` is false. The monitor sees through its own low-resolution
    depth camera at the wrist camera's frame (`tamp.sim.lots.depth_safety`)."""
    plant = cell.plant
    arm_slots = [k < len(ARM.arm_joints) for k in cell.actuator_order]
    q0_actuators = cell.q0[cell.actuator_order]
    command = builder.AddSystem(
        ArmCommandStream(
            scenario.control.command_period, scenario.control.period, arm_slots, q0_actuators
        )
    )
    builder.Connect(skills.desired_state_port, command.target_port)
    if not scenario.safety.enabled:
        builder.Connect(command.desired_state_port, plant.get_desired_state_input_port(cell.arm))
        return command, None
    cam = scenario.camera
    config = safety_camera_config(cam.width, cam.height, cam.fov_y_deg, cam.near, cam.far)
    camera, intrinsics = add_wrist_camera(builder, plant, cell.scene_graph, cell.arm, config)
    safety = builder.AddSystem(
        SafetyMonitor(
            scenario.safety,
            intrinsics=intrinsics,
            width=config.width,
            height=config.height,
            perception_period=scenario.control.perception_period,
            actuator_order=cell.actuator_order,
        )
    )
    builder.Connect(command.desired_state_port, safety.command_port)
    builder.Connect(command.count_port, safety.count_port)
    builder.Connect(plant.get_state_output_port(cell.arm), safety.arm_state_port)
    builder.Connect(camera.depth_image_32F_output_port(), safety.depth_port)
    builder.Connect(skills.view_request_port, safety.request_port)
    builder.Connect(perception.observation_port, safety.observation_port)
    builder.Connect(safety.desired_state_port, plant.get_desired_state_input_port(cell.arm))
    builder.Connect(safety.stopped_port, skills.hold_port)
    return command, safety


def fov_deg(intrinsics: tuple[float, float, float, float], width: int, height: int):
    """(horizontal, vertical) field of view in degrees."""
    fx, fy, _, _ = intrinsics
    return (
        2 * math.degrees(math.atan(width / 2 / fx)),
        2 * math.degrees(math.atan(height / 2 / fy)),
    )


def cell_parts(station: LotsStation) -> dict[str, Stopwatch]:
    """The non-overlapping timed parts of a built station (`tamp.sim.core.timing.breakdown`
    adds the rest): camera renders, perception's analysis, the grasp network, and the skills'
    own update (differential IK, view handlers: their update time without the network calls)."""
    sk, net = station.skills.control, station.planner.network
    skills = Stopwatch(max(sk.wall - net.wall, 0.0), max(sk.cpu - net.cpu, 0.0), sk.calls)
    return {
        "render": station.perception.render,
        "perception": station.perception.analysis,
        "network": net,
        "skills": skills,
    }
