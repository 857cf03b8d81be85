"""Training and test data of the detector for the SMP-MRO cell's mast camera (Drake renders).

The learned detector (`tamp.sim.core.detector`: proposals from depth, a crop classifier
naming each) was trained on the LOTS wrist camera's views, 0.2-0.5 m above a table. The
youBot's mast camera (`tamp.sim.smp.robot.CAMERA`, 256 x 192) looks at the floor 0.5-4 m
ahead, with the robot's own arm in view: the shipped wrist weights call its bottles
``unknown`` and its arm a ``hand`` (measured on Case 3 camera frames). A real robot's
detector would be fine-tuned on its own camera's images; this module renders them, in the
data set format of `tamp.sim.core.segdata` (same classes, same files), so that the same
`tamp detect train --kind classifier` trains the mast camera's weights
(``detector_mast_rgbd.pt``) and `tamp detect eval` scores them.

Scenes (`sample_scene`), each rendered through the cell's own camera model
(`tamp.sim.core.camera.add_rgbd_camera` with `CAMERA`'s size and field of view, on the
youBot's base, VTK's default light as in the cell):

- the cell's floor and two to five area markers (goal discs green, free areas grey; of the
  cell's radii), labelled ``table`` (the support, never an instance);
- one to six of the cell's object models (``bottle``, ``obstacle``: `OBJECT_KINDS`, their
  packaged SDFs and colours) standing on the floor 0.5-3.8 m ahead of the camera, a third of
  them pushed against another until they touch, one lying on its side in one scene of six
  (a knocked-over bottle is still a bottle);
- zero to two objects of shapes the cell does not know (`tamp.sim.core.segdata`'s
  unknown shapes, scaled 1-2.5 times for a floor), labelled ``unknown``: an object a
  person brings in is seen as unknown, never as a task class; the test scenes' shapes
  are never rendered in training (`UNKNOWN_TEST_KINDS`);
- per view, the robot in the cell's workspace (x -1-4 m, y -2.2-2.8 m) facing them, its arm
  at the ready pose, a reach towards the floor ahead (`ArmIK`) or a carry pose, the fingers
  open or closed, and in one view of four a bottle held in the fingers (labelled
  ``bottle``, as the cell's perception sees it while carrying); the robot's own links are
  ``background`` (its kinematics says where they are; the detector never reports them);
- per scene, depth noise of 0-3 mm (sigma, per pixel, as the cell's `DepthNoise`).

The floor's height (`FLOOR`) and the height over it that makes a pixel an object's
(`ABOVE_FLOOR`, 2 cm) are recorded with each scene: the cell gives both to the detector (a
`Region` with ``floor`` and ``above``). With the tabletop default (4 mm over a plane
estimated from the view) the far floor rose into the proposals and swallowed the objects
standing on it: 112 of the 133 missed objects of 40 held-out scenes lay inside a floor
proposal of 1,500-5,000 pixels (measured on these scenes).

Object-wise and scene-wise split as in `tamp.sim.core.segdata` (`split_of`, recorded in
``dataset.json``). Everything of scene ``i`` is drawn from ``default_rng((seed, i))``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from tamp.sim.core.segdata import (
    TABLE,
    UNKNOWN,
    UNKNOWN_TEST_KINDS,
    UNKNOWN_TRAIN_KINDS,
    DatasetInfo,
    SegClass,
    class_names,
    scene_file,
    split_of,
    unknown_visuals,
    view_targets,
    write_info,
    write_scene,
)
from tamp.sim.smp.robot import CAMERA, HOME_ARM, OBJECT_KINDS, ROBOT

#: the mast camera's weights file (``tamp/models/weights``)
WEIGHTS_FILE = "detector_mast_rgbd.pt"
#: where objects stand, ahead of the camera's mount (m, along the floor)
NEAR, FAR = 0.5, 3.8
#: the floor's height: the cell knows its support plane, and gives it to the detector
FLOOR = 0.0
#: how far over the floor a pixel must be to be an object's (m): the mast camera's depth
#: places the bare floor 0.27 % of the distance too high (measured on noiseless renders:
#: 2.7 mm at 1 m, 8.8 mm at 3.3 m, 11.8 mm at 4.4 m; the same at every column, i.e. a pitch
#: of 0.15 degree between the render and the intrinsics) plus 2-3 mm of depth noise; the
#: lowest object (a bottle on its side) is 7 cm high
ABOVE_FLOOR = 0.02
#: the arm's carry pose: the hand raised over the base (a lifted object clears the floor)
CARRY_ARM = (0.0, 0.2, 0.9, 1.2, 0.0)


@dataclass(frozen=True)
class MastDataConfig:
    """What `generate` renders: views per scene, seed, share of test scenes, objects per
    scene, the depth noise's largest sigma (m)."""

    views: int = 3
    seed: int = 0
    test_fraction: float = 0.15
    max_objects: int = 6
    max_unknown: int = 2
    max_depth_noise: float = 0.003
    camera: str = "mast"
    width: int = CAMERA.width
    height: int = CAMERA.height
    fov_y_deg: float = CAMERA.fov_y_deg


@dataclass(frozen=True)
class Placed:
    """One object of a scene: its class, the model kind (a cell model's name, or an unknown
    shape's visuals) and its pose on the floor (x, y, yaw; ``lying``: on its side)."""

    cls: str
    x: float
    y: float
    yaw: float
    kind: str = ""
    visuals: tuple = ()
    lying: bool = False
    radius: float = 0.05


@dataclass(frozen=True)
class RobotView:
    """One view: the base pose (x, y, yaw), the arm's five joints, the fingers' opening
    and whether a bottle is held."""

    base: tuple[float, float, float]
    arm: tuple[float, ...]
    fingers: float
    held: bool


@dataclass(frozen=True)
class MastScene:
    """One sampled scene: area markers ((x, y, radius, free) each), objects, views, depth
    noise sigma, split."""

    markers: tuple[tuple[float, float, float, bool], ...]
    objects: tuple[Placed, ...]
    views: tuple[RobotView, ...]
    depth_noise: float
    split: str = "train"


def _ahead(rng: np.random.Generator, base: tuple[float, float, float]) -> tuple[float, float]:
    """A floor point the mast camera sees from ``base``: NEAR-FAR ahead, inside its field
    of view (the horizontal half-angle, a little inside)."""
    half = math.atan(math.tan(math.radians(CAMERA.fov_y_deg) / 2) * CAMERA.width / CAMERA.height)
    r = float(rng.uniform(NEAR, FAR))
    a = base[2] + float(rng.uniform(-0.85, 0.85)) * half
    mount = (
        base[0] + CAMERA.position[0] * math.cos(base[2]),
        base[1] + CAMERA.position[0] * math.sin(base[2]),
    )
    return mount[0] + r * math.cos(a), mount[1] + r * math.sin(a)


def _free(x: float, y: float, r: float, placed: Sequence[Placed], gap: float) -> bool:
    return all(math.hypot(x - p.x, y - p.y) >= r + p.radius + gap for p in placed)


def sample_scene(rng: np.random.Generator, cfg: MastDataConfig, split: str) -> MastScene:
    """A scene as the module docstring describes (all of it drawn from ``rng``)."""
    base0 = (float(rng.uniform(-1.0, 4.0)), float(rng.uniform(-2.2, 2.8)),
             float(rng.uniform(-math.pi, math.pi)))  # fmt: skip
    markers = []
    for _ in range(int(rng.integers(2, 6))):
        x, y = _ahead(rng, base0)
        markers.append((x, y, float(rng.uniform(0.15, 0.3)), bool(rng.random() < 0.5)))
    placed: list[Placed] = []
    kinds = list(OBJECT_KINDS)
    for _ in range(int(rng.integers(1, cfg.max_objects + 1))):
        kind = OBJECT_KINDS[kinds[int(rng.integers(len(kinds)))]]
        lying = kind.name == "bottle" and rng.random() < 1 / 6
        r = kind.radius if not lying else kind.half_height
        for _ in range(30):
            if placed and rng.random() < 1 / 3:  # against another, touching
                other = placed[int(rng.integers(len(placed)))]
                a = float(rng.uniform(-math.pi, math.pi))
                d = other.radius + r + 0.002
                x, y = other.x + d * math.cos(a), other.y + d * math.sin(a)
                gap = 0.0
            else:
                x, y = _ahead(rng, base0)
                gap = 0.05
            if _free(x, y, r, placed, gap - 0.004):
                yaw = float(rng.uniform(-math.pi, math.pi))
                placed.append(Placed(kind.name, x, y, yaw, kind.name, lying=lying, radius=r))
                break
    shapes = UNKNOWN_TRAIN_KINDS if split == "train" else UNKNOWN_TEST_KINDS
    for _ in range(int(rng.integers(0, cfg.max_unknown + 1))):
        shape = shapes[int(rng.integers(len(shapes)))]
        scale = float(rng.uniform(1.0, 2.5))
        visuals = _scaled(unknown_visuals(shape, rng), scale)
        for _ in range(30):
            x, y = _ahead(rng, base0)
            if _free(x, y, 0.12 * scale, placed, 0.03):
                yaw = float(rng.uniform(-math.pi, math.pi))
                placed.append(Placed(UNKNOWN, x, y, yaw, shape, visuals, radius=0.12 * scale))
                break
    views = []
    for v in range(cfg.views):
        jitter = rng.normal(0.0, [0.15, 0.15, 0.25]) if v else np.zeros(3)
        base = (base0[0] + float(jitter[0]), base0[1] + float(jitter[1]),
                base0[2] + float(jitter[2]))  # fmt: skip
        pose = int(rng.integers(3))  # ready, reach, carry
        held = pose != 1 and rng.random() < 0.25
        views.append(RobotView(base, _arm(rng, pose), 0.0 if held else _fingers(rng), held))
    sigma = float(rng.choice([0.0, rng.uniform(0.0, cfg.max_depth_noise)]))
    return MastScene(tuple(markers), tuple(placed), tuple(views), sigma, split)


def _fingers(rng: np.random.Generator) -> float:
    return float(rng.choice([ROBOT.finger_open, rng.uniform(0.0, ROBOT.finger_open)]))


_IK = None


def _arm(rng: np.random.Generator, pose: int) -> tuple[float, ...]:
    """The arm's joints: the ready pose, a reach towards the floor ahead (`ArmIK`, a point
    0.3-0.45 m ahead and 0.05-0.35 m up), or a carry pose; each jittered a little."""
    global _IK
    if pose == 1:
        from tamp.sim.smp.ik import ArmIK

        _IK = _IK or ArmIK()
        q = np.zeros(len(ROBOT.joints))
        q[3:8] = HOME_ARM
        point = [rng.uniform(0.3, 0.45), rng.uniform(-0.15, 0.15), rng.uniform(0.05, 0.35)]
        sol = _IK.solve(q, np.asarray(point))
        if sol is not None:
            return tuple(float(a) for a in sol)
    nominal = np.asarray(HOME_ARM if pose == 0 else CARRY_ARM, float)
    return tuple(float(a) for a in nominal + rng.normal(0.0, 0.05, 5))


def _scaled(visuals: Sequence, k: float) -> tuple:
    """An unknown shape's visuals ``k`` times larger (sizes and offsets)."""
    import dataclasses

    out = []
    for v in visuals:
        X = np.array(v.X_BG, float)
        X[:3, 3] *= k
        out.append(dataclasses.replace(v, size=tuple(s * k for s in v.size), X_BG=X))
    return tuple(out)


def render_scene(scene: MastScene, classes: Sequence[SegClass], rng: np.random.Generator) -> list:
    """Every view of ``scene`` (`tamp.sim.core.segdata.View`s: images, per-pixel classes,
    instances, the camera's intrinsics and pose), rendered by a diagram of the cell's floor,
    markers, robot, mast camera and the scene's objects; ``rng`` draws the depth noise."""
    from pydrake.geometry import Box, Cylinder, Sphere
    from pydrake.math import RigidTransform, RollPitchYaw
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.multibody.tree import SpatialInertia
    from pydrake.systems.framework import DiagramBuilder

    from tamp.sim.core.camera import add_rgbd_camera, camera_config, look_at
    from tamp.sim.core.models import model_url
    from tamp.sim.core.parsing import make_parser
    from tamp.sim.smp.ik import grasp_transform
    from tamp.sim.smp.object_models import object_sdf
    from tamp.sim.smp.station import area_marker_sdf

    names = class_names(classes)
    index = {n: i for i, n in enumerate(names)}
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    parser = make_parser(plant)
    parser.SetAutoRenaming(True)
    (floor,) = parser.AddModelsFromUrl(model_url("floor"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("floor", floor))
    lut: dict[int, int] = {}
    for k, (x, y, r, free) in enumerate(scene.markers):
        (m,) = parser.AddModelsFromString(area_marker_sdf(f"m{k}", r, free), "sdf")
        frame = plant.GetFrameByName("marker", m)
        plant.WeldFrames(plant.world_frame(), frame, RigidTransform([x, y, 0.0]))
        lut[int(frame.body().index())] = index[TABLE]
    (robot,) = parser.AddModelsFromUrl(ROBOT.url)
    bodies = []
    inertia = SpatialInertia.SolidBoxWithMass(0.1, 0.05, 0.05, 0.05)
    shapes = {"box": Box, "cylinder": Cylinder, "sphere": Sphere}
    for k, o in enumerate(scene.objects):
        if o.cls == UNKNOWN:
            body = plant.AddRigidBody(f"unknown{k}", plant.AddModelInstance(f"unknown{k}"), inertia)
            for j, vis in enumerate(o.visuals):
                plant.RegisterVisualGeometry(
                    body, RigidTransform(vis.X_BG), shapes[vis.shape](*vis.size),
                    f"unknown{k}_v{j}", np.array(vis.rgba),
                )  # fmt: skip
        else:
            (m,) = parser.AddModelsFromString(object_sdf(OBJECT_KINDS[o.kind], f"o{k}"), "sdf")
            body = plant.GetBodyByName(OBJECT_KINDS[o.kind].body, m)
        bodies.append(body)
        lut[int(body.index())] = index[o.cls]
    held = None
    if any(v.held for v in scene.views):
        bottle = OBJECT_KINDS["bottle"]
        (m,) = parser.AddModelsFromString(object_sdf(bottle, "held"), "sdf")
        held = plant.GetBodyByName(bottle.body, m)
        lut[int(held.index())] = index["bottle"]
    plant.Finalize()
    base = plant.GetBodyByName(ROBOT.base_body, robot)
    palm = plant.GetBodyByName(ROBOT.palm_body, robot)
    X_BC = look_at(CAMERA.position, CAMERA.target)
    config = camera_config(
        name="mast_camera", width=CAMERA.width, height=CAMERA.height, fov_y_deg=CAMERA.fov_y_deg
    )
    camera, K = add_rgbd_camera(builder, plant, scene_graph, base, X_BC, config)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    pc = plant.GetMyMutableContextFromRoot(context)
    cc = camera.GetMyContextFromRoot(context)
    for o, body in zip(scene.objects, bodies, strict=True):
        if o.cls == UNKNOWN:
            X = RigidTransform(RollPitchYaw(0.0, 0.0, o.yaw), [o.x, o.y, 0.0])
        elif o.lying:
            kind = OBJECT_KINDS[o.kind]
            X = RigidTransform(RollPitchYaw(math.pi / 2, 0.0, o.yaw), [o.x, o.y, kind.radius])
        else:
            X = RigidTransform(
                RollPitchYaw(0.0, 0.0, o.yaw), [o.x, o.y, OBJECT_KINDS[o.kind].half_height]
            )
        plant.SetFreeBodyPose(pc, body, X)
    K_matrix = np.array([[K[0], 0.0, K[2]], [0.0, K[1], K[3]], [0.0, 0.0, 1.0]])
    table_body = int(plant.GetBodyByName("floor", floor).index())
    views = []
    for view in scene.views:
        q = np.zeros(len(ROBOT.joints))
        q[0:3] = view.base
        q[3:8] = view.arm
        q[8:10] = view.fingers
        q_all = plant.GetPositions(pc)
        for k, name in enumerate(ROBOT.joints):
            q_all[plant.GetJointByName(name, robot).position_start()] = q[k]
        plant.SetPositions(pc, q_all)
        if held is not None:
            X_WP = plant.EvalBodyPoseInWorld(pc, palm)
            away = RigidTransform([0.0, 0.0, -50.0])
            plant.SetFreeBodyPose(
                pc, held, X_WP @ grasp_transform(OBJECT_KINDS["bottle"], 0) if view.held else away
            )
        rgb = np.array(camera.color_image_output_port().Eval(cc).data)[..., :3].copy()
        depth = np.array(camera.depth_image_32F_output_port().Eval(cc).data)[..., 0].copy()
        label = np.array(camera.label_image_output_port().Eval(cc).data)[..., 0].copy()
        depth[~np.isfinite(depth)] = 0.0
        if scene.depth_noise > 0:
            valid = depth > 0
            depth[valid] += rng.normal(0.0, scene.depth_noise, int(valid.sum())).astype(np.float32)
        X_WC = plant.EvalBodyPoseInWorld(pc, base) @ X_BC
        views.append(
            view_targets(rgb, depth, label, lut, table_body, K_matrix, X_WC.GetAsMatrix4())
        )
    return views


def generate(
    out: str | Path, scenes: int, classes: Sequence[SegClass], cfg: MastDataConfig
) -> DatasetInfo:
    """Render ``scenes`` scenes into ``out`` and write ``dataset.json`` (the format of
    `tamp.sim.core.segdata`: `tamp detect train` and `tamp detect eval` read it)."""
    from tqdm import tqdm

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    views = 0
    for i in tqdm(range(scenes), desc="render", unit="scene"):
        rng = np.random.default_rng((cfg.seed, i))
        scene = sample_scene(rng, cfg, split_of(i, cfg.seed, cfg.test_fraction))
        rendered = render_scene(scene, classes, rng)
        write_scene(scene_file(out, i), rendered, plane=(FLOOR, ABOVE_FLOOR))
        views += len(rendered)
    return write_info(out, class_names(classes), asdict(cfg), scenes, views)
