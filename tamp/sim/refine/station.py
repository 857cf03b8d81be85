"""The refinement workcell's station: the diagram of a program in its scene (one Diagram).

    MultibodyPlant + SceneGraph (SAP; floor, two Pioneer-like robots, the scene's objects)
    per robot:  plant state, reaction forces, contact forces -> SensorReadings -> readings
                readings, command -> Channel -> delivered -> PioneerStateMachine -> command
                Channel.actuation -> the robot's PD actuators (desired state)
                the other machine's progress -> PioneerStateMachine.others
    Channels' deliveries -> RateTuningSupervisor -> rates -> both state machines
    plant contact results -> ContactMonitor (colliding pairs, every step; `contacts`)
    MeshcatVisualizer (optional, `tamp.sim.core.recording`)

Exported ports of the Diagram, per robot ``R``: ``R_state`` (its plant state),
``R_progress`` (its state machine's progress), ``R_delivered`` (what its channel delivered);
and ``rates`` (the supervisor's command rates).

Robots (``tamp/models/sdf/pioneer_lift.sdf``, ``pioneer_parallel.sdf``, Fig. 7): the base moves
on planar joints (x, y, yaw) driven along its heading or about the vertical axis, the lift
lever pitches (``arm_pitch``, up positive) and two prismatic paddles/fingers open and close
(`tamp.refine.machine.JOINTS`). Every joint is a PD-controlled actuator of the plant (SAP,
implicit; `GAINS`). The scene's objects (`tamp.sim.refine.scenario`) are added from their
models, named as the scene names them, and welded to the world when fixed.

The plant steps every `time_step` (`FINE_STEP`, 10 ms, unless the scene allows a coarser
step, `tamp.sim.refine.scenario.Scene.time_step`, and the program's motions are slow enough
for it: no section's setpoint moves more than `MAX_TRAVEL` per step; Task 4 in the chair's
scene runs at 20 ms); the Channels, state machines and the supervisor update on the same
tick (the Channels take every sensor sample in
between at its own time, so sensors may be faster than the tick). A command leaves on a
state machine's tick, so P is at most 1 / time step (100 Hz, 50 Hz) here: the online rate
search stops there too. Gravity is off for the
robots (their drivers hold the lever), so the force sensor reads only what the gripper
touches. Contact is hydroelastic where the models say so (the chair's frames, the
objects), point contact otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometrySet
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, PdControllerGains, RevoluteJoint
from pydrake.systems.framework import Diagram, DiagramBuilder

from tamp.errors import InfeasibleError, InputError
from tamp.refine.architecture import Architecture, trigger_sensors
from tamp.refine.machine import FINGER_MAX, JOINTS, Machine
from tamp.refine.program import SENSORS, Program
from tamp.refine.steps import RateSearch
from tamp.sim.core.models import model_url, sdf_path
from tamp.sim.core.plant import add_sap_plant
from tamp.sim.refine.channel import Channel, ChannelState
from tamp.sim.refine.contacts import CollisionRule, ContactMonitor
from tamp.sim.refine.scenario import Scene
from tamp.sim.refine.sensors import SensorReadings
from tamp.sim.refine.skills import PioneerStateMachine
from tamp.sim.refine.supervisor import RateTuningSupervisor

FINE_STEP = 0.01  # s, the plant's step unless a scene and a program allow a coarser one
#: m (base, gripper) or rad (base turn, arm) a motion's setpoint may advance per step for a
#: scene's coarser step to be used (`time_step`): slow programs only
MAX_TRAVEL = 1.0e-3
#: (kp, kd) of each joint's PD actuator
GAINS = {
    "base_x": (6000.0, 1200.0),
    "base_y": (6000.0, 1200.0),
    "base_yaw": (800.0, 150.0),
    "arm_pitch": (400.0, 30.0),
    "finger_left_joint": (600.0, 10.0),
    "finger_right_joint": (600.0, 10.0),
}
#: bodies whose contact with anything is a collision (the gripper's contacts are intended)
CHASSIS_BODIES = ("base_link", "arm_link")
GRIPPER_MOUNT = "gripper_mount"  # the welded joint whose reaction force is the force sensor


@dataclass
class RefineStation:
    """The built diagram and the handles the run loop needs."""

    diagram: Diagram
    plant: MultibodyPlant
    program: Program
    scene: Scene
    robots: dict[str, Any]  # robot name -> ModelInstanceIndex
    machines: dict[str, PioneerStateMachine]
    channels: dict[str, Channel]
    supervisor: RateTuningSupervisor
    objects: dict[str, Any]  # object name -> ModelInstanceIndex
    chassis: dict[int, str] = field(default_factory=dict)  # body index -> "R1.base_link"
    names: dict[int, str] = field(default_factory=dict)  # body index -> readable name
    visualizer: Any = None
    meshcat: Any = None
    robot_of: dict[int, str] = field(default_factory=dict)  # body index -> robot name
    scenery: frozenset[int] = frozenset()  # bodies of the scene's fixed objects (the table)

    monitor: ContactMonitor | None = None
    movable: frozenset[int] = frozenset()  # bodies of the scene's free objects
    time_step: float = FINE_STEP  # s, the plant's step and the systems' tick (`time_step`)

    def collision(self, a: int, b: int) -> tuple[str, str] | None:
        """The contact of bodies ``a`` and ``b`` as a collision ``(robot body, other)``, or
        None when it is intended (`tamp.sim.refine.contacts.CollisionRule`)."""
        return self.rule().classify(a, b)

    def rule(self) -> CollisionRule:
        return CollisionRule(
            self.robot_of, frozenset(self.chassis), self.scenery, self.names, self.movable
        )


def time_step(program: Program, scene: Scene) -> float:
    """The plant's step (and the systems' tick) for ``program`` in ``scene``: the scene's
    ``time_step`` when every motion advances at most `MAX_TRAVEL` per step at it, else
    `FINE_STEP` (a fast fork runs further past the latch between two coarse steps: at
    20 ms the short Task 4 at 22 Hz left the chair less open than at 10 ms)."""
    coarse = scene.time_step
    if coarse <= FINE_STEP:
        return coarse
    fastest = max(b.motion.speed for _, _, b in program.behaviors())
    return coarse if fastest * coarse <= MAX_TRAVEL + 1e-12 else FINE_STEP


def _model_text(model: str, name: str) -> str:
    return sdf_path(model).read_text().replace(f'<model name="{model}">', f'<model name="{name}">')


def build_station(
    program: Program,
    architecture: Architecture,
    scene: Scene,
    *,
    tune: bool = False,
    meshcat: Any = None,
) -> RefineStation:
    """The diagram of ``program`` in ``scene`` (the program's, `scenario.load_scene`);
    ``tune`` runs Fig. 5 in the supervisor."""
    comm = program.communication
    period = time_step(program, scene)
    for robot, _, b in program.behaviors():
        if program.rate(b) > 1.0 / period + 1e-9:  # one command per tick at most
            raise InfeasibleError(
                f"{robot.name}.{b.name} commands at {program.rate(b):g} Hz; scene "
                f"{scene.name}'s {1e3 * period:g} ms step sends at most {1.0 / period:g} Hz"
            )
    builder = DiagramBuilder()
    plant, scene_graph, parser = add_sap_plant(
        builder, time_step=period, contact_model="hydroelastic_with_fallback"
    )
    (floor,) = parser.AddModelsFromUrl(model_url("floor"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("floor", floor))

    robots = {}
    for r in program.robots:
        (m,) = parser.AddModelsFromString(_model_text(r.model, r.name), "sdf")
        robots[r.name] = m
        start = dict(zip(JOINTS, (*r.start, 0.0, FINGER_MAX, FINGER_MAX), strict=True))
        for j in JOINTS:
            plant.GetJointByName(j, m).set_default_positions([start[j]])
            kp, kd = GAINS[j]
            plant.GetJointActuatorByName(j, m).set_controller_gains(PdControllerGains(p=kp, d=kd))
        plant.mutable_gravity_field().set_enabled(m, False)

    objects, fixed = {}, []
    for i, p in enumerate(scene.objects):
        m = _add_object(plant, parser, scene, i, taken=set(robots))
        objects[p.name] = m
        body = plant.get_body(plant.GetBodyIndices(m)[0])
        X = RigidTransform(RotationMatrix.MakeZRotation(p.yaw), [p.x, p.y, p.z])
        if p.fixed:
            plant.WeldFrames(plant.world_frame(), body.body_frame(), X)
            fixed.append(m)
        else:
            plant.SetDefaultFloatingBaseBodyPose(body, X)
    plant.Finalize()
    _check_goals(plant, scene, objects)

    chassis, names, robot_of = {}, {}, {}
    scenery = frozenset(int(i) for m in fixed for i in plant.GetBodyIndices(m))
    for m in list(robots.values()) + list(objects.values()) + [floor]:
        for index in plant.GetBodyIndices(m):
            b = plant.get_body(index)
            names[int(index)] = f"{plant.GetModelInstanceName(m)}.{b.name()}"
    for name, m in robots.items():
        geoms = []
        for index in plant.GetBodyIndices(m):
            b = plant.get_body(index)
            robot_of[int(index)] = name
            geoms += plant.GetCollisionGeometriesForBody(b)
            if b.name() in CHASSIS_BODIES:
                chassis[int(index)] = f"{name}.{b.name()}"
        scene_graph.collision_filter_manager().Apply(
            CollisionFilterDeclaration().ExcludeWithin(GeometrySet(geoms))
        )
        order = [
            plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices(m)
        ]
        assert tuple(order) == JOINTS, order  # the Channel's actuation is in JOINTS order

    qi = plant.GetPositionsFromArray
    machines, channels = {}, {}
    empty = None
    reaction = plant.get_reaction_forces_output_port()
    for r in program.robots:
        m = robots[r.name]
        nq, nv = plant.num_positions(m), plant.num_velocities(m)
        gq = list(qi(m, np.arange(plant.num_positions(), dtype=float)).astype(int))
        gv = list(plant.GetVelocitiesFromArray(m, np.arange(plant.num_velocities(), dtype=float)))
        gv = [int(v) for v in gv]
        jq = {j: gq.index(plant.GetJointByName(j, m).position_start()) for j in JOINTS}
        jv = {j: gv.index(plant.GetJointByName(j, m).velocity_start()) for j in JOINTS}
        sensors = builder.AddSystem(
            SensorReadings(
                r.name,
                nq=nq,
                nv=nv,
                pose_index=(jq["base_x"], jq["base_y"], jq["base_yaw"]),
                arm_index=jq["arm_pitch"],
                finger_index=(jv["finger_left_joint"], jv["finger_right_joint"]),
                mount_joint=int(plant.GetJointByName(GRIPPER_MOUNT, m).index()),
                reaction_model=reaction.Allocate(),
            )
        )
        machine = Machine(program, r.name)
        network = architecture.network(comm.category)
        channel = builder.AddSystem(
            Channel(
                r.name,
                network,
                {x: architecture.sensor_rate(x, comm.sensor_rate_hz) for x in SENSORS},
                np.array(machine.joint_setpoints(machine.initial().setpoints)),
                period,
                partial(architecture.command_stream, comm.category),
            )
        )
        empty = ChannelState(network.initial())
        machine = builder.AddSystem(PioneerStateMachine(program, r.name, period, empty))
        builder.Connect(plant.get_state_output_port(m), sensors.state_port)
        builder.Connect(reaction, sensors.reaction_port)
        builder.Connect(plant.get_generalized_contact_forces_output_port(m), sensors.contact_port)
        builder.Connect(sensors.readings_port, channel.readings_port)
        builder.Connect(machine.command_port, channel.command_port)
        builder.Connect(channel.delivered_port, machine.delivered_port)
        builder.Connect(channel.actuation_port, plant.get_desired_state_input_port(m))
        machines[r.name], channels[r.name] = machine, channel

    movable = frozenset(
        int(i) for m in objects.values() if m not in fixed for i in plant.GetBodyIndices(m)
    )
    rule = CollisionRule(robot_of, frozenset(chassis), scenery, names, movable)
    geometry_body = {
        g.get_value(): int(index)
        for index in range(plant.num_bodies())
        for g in plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(index)))
    }
    contact_results = plant.get_contact_results_output_port()
    monitor = builder.AddSystem(
        ContactMonitor(rule, geometry_body, contact_results.Allocate(), period)
    )
    builder.Connect(contact_results, monitor.contact_port)

    watched = {r.name: trigger_sensors(program, r.name) for r in program.robots}
    searches = None
    if tune:
        searches = {}
        for r in program.robots:
            current = program.rate(r.behaviors[0])
            searches[r.name] = {}
            for sensor in watched[r.name] or ("force",):
                s = architecture.search(comm.category, current, comm.sensor_rate_hz, (sensor,))
                limit = min(s.limit, 1.0 / period)  # a command leaves on a tick
                searches[r.name][sensor] = RateSearch(current, s.step, s.threshold, limit)
    supervisor = builder.AddSystem(
        RateTuningSupervisor(watched, period, architecture.probe_window, empty, searches)
    )
    a, b = (r.name for r in program.robots)
    for name, other in ((a, b), (b, a)):
        builder.Connect(machines[other].progress_port, machines[name].others_port)
        builder.Connect(supervisor.rates_port, machines[name].rates_port)
        builder.Connect(channels[name].delivered_port, supervisor.delivered_ports[name])

    for r in program.robots:
        builder.ExportOutput(plant.get_state_output_port(robots[r.name]), f"{r.name}_state")
        builder.ExportOutput(machines[r.name].progress_port, f"{r.name}_progress")
        builder.ExportOutput(channels[r.name].delivered_port, f"{r.name}_delivered")
    builder.ExportOutput(supervisor.rates_port, "rates")

    visualizer = None
    if meshcat is not None:
        from tamp.sim.core.recording import add_visualizer

        visualizer = add_visualizer(builder, scene_graph, meshcat)
    diagram = builder.Build()
    diagram.set_name(f"refine_{program.name}")
    return RefineStation(
        diagram,
        plant,
        program,
        scene,
        robots,
        machines,
        channels,
        supervisor,
        objects,
        chassis,
        names,
        visualizer,
        meshcat,
        robot_of,
        scenery,
        monitor,
        movable,
        period,
    )


def _add_object(plant, parser, scene: Scene, i: int, taken: set[str]):
    """Object ``i`` of ``scene`` added from its model (one model per file) and named as the
    scene names it; ``taken``: the robots' names."""
    o = scene.objects[i]
    where = f"objects[{i}]"
    if o.name in taken or o.name == "floor":
        raise InputError(
            f"{o.name!r} names a robot or the floor here", file=scene.file, field=f"{where}.name"
        )
    if o.model.startswith("package://"):
        models = parser.AddModelsFromUrl(o.model)
    else:
        models = parser.AddModels(o.model)
    if len(models) != 1:
        raise InputError(
            f"the model file holds {len(models)} models, expected one",
            file=scene.file,
            field=f"{where}.model",
        )
    (m,) = models
    if plant.GetModelInstanceName(m) != o.name:
        plant.RenameModelInstance(m, o.name)
    return m


def _check_goals(plant, scene: Scene, objects: dict[str, Any]) -> None:
    """Every goal on a joint names a revolute joint of its object's model."""
    for i, g in enumerate(scene.goals):
        name, _, what = g.quantity.partition(".")
        if what in ("tilt", "rise"):
            continue
        m = objects[name]
        joint = plant.GetJointByName(what, m) if plant.HasJointNamed(what, m) else None
        if not isinstance(joint, RevoluteJoint):
            joints = [
                plant.get_joint(j).name()
                for j in plant.GetJointIndices(m)
                if isinstance(plant.get_joint(j), RevoluteJoint)
            ]
            raise InputError(
                f"{name} has no revolute joint {what!r} (its revolute joints: "
                f"{', '.join(joints) or 'none'}; or tilt, rise)",
                file=scene.file,
                field=f"goals[{i}].quantity",
            )


def search_of(station: RefineStation, context) -> dict[str, RateSearch]:
    """The supervisor's searches in ``context`` (root context of the diagram), keyed
    ``ROBOT.SENSOR``."""
    sup = station.supervisor
    s = sup.state(sup.GetMyContextFromRoot(context))
    return {f"{n}.{k}": v for n, w in s.robots.items() for k, v in w.searches.items()}
