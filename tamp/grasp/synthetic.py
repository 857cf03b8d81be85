"""Synthetic grasp dataset rendered with Drake, written in the Jacquard format.

Each scene puts one to three objects (:mod:`tamp.grasp.objects`: the LOTS tools and blocks
and random primitives) on a table and renders them with ``RgbdSensor`` + the VTK render
engine (headless, EGL) from several eye-in-hand viewpoints: top-down-ish cameras at
0.20-0.32 m above a target object, tilted up to 15 degrees, at a random yaw, as the hand
camera sees the table while the arm approaches a grasp (§IV-B, Fig. 6). The ground-truth
rectangles come from the objects' geometry projected through the camera intrinsics; a
grasp is kept only when the label image shows its own object at the grasp centre (not
occluded, inside the view). Everything is drawn from ``numpy.random.default_rng((seed,
scene))``, so a dataset is reproducible scene by scene. ``SynthConfig.table = "mats"`` adds a
coloured mat of random hue under the objects (the LOTS workcell's objects lie on mats); the
mat is drawn last, so the rest of a scene is the plain set's.

Layout (Jacquard): ``OUT/scene_NNNNN/V_scene_NNNNN_{RGB.png,perfect_depth.tiff,
grasps.txt,camera.json}``; one folder per scene, so the object-wise split keeps all views of
a scene together. ``camera.json`` (extra, ignored by the Jacquard loader) holds the
intrinsics and the camera pose X_WC for world-frame checks.

The same `SceneRenderer` renders the detector's training scenes (`tamp.sim.core.segdata`):
there it is also given whole bodies of primitive visuals (`VisualBody`: the catalogue's
objects read from their SDF files, the wrist camera's gripper, the person's hand), the
image's width and height, and the lights of the scene.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.grasp.formats import write_jacquard
from tamp.grasp.objects import PRIMITIVES, TOOLS, GraspObject, grasp_world, make_object
from tamp.grasp.pinhole import camera_to_pixel
from tamp.grasp.rect import GraspRect

TABLE_TOP = 0.0


@dataclass(frozen=True, slots=True)
class SynthConfig:
    """What to render: image size, vertical field of view, views per scene, seed."""

    size: int = 128
    fov_y_deg: float = 45.0
    views: int = 4
    seed: int = 0
    max_objects: int = 3
    min_height: float = 0.2
    max_height: float = 0.32
    max_tilt_deg: float = 15.0
    #: "plain": a beige-grey table; "mats": in three scenes of four a coloured mat of random
    #: hue lies under the objects, as the LOTS workcell's green and blue workspace mats do
    #: (`Mat`)
    table: str = "plain"


TABLES = ("plain", "mats")


@dataclass(frozen=True, slots=True)
class Mat:
    """A thin coloured rectangle on the table under the objects (visual only, 1 mm proud)."""

    size: tuple[float, float]
    center: tuple[float, float]
    yaw: float
    rgba: tuple[float, float, float, float]


def sample_mat(rng: np.random.Generator, placements: list[Placement]) -> Mat | None:
    """A mat for ``table: mats`` (None in one scene of four): 0.25-0.6 m a side, about the
    objects' centre, any hue at moderate saturation and brightness (the workcell's mats are
    a pale green and a pale blue; a random hue keeps the network from learning those two)."""
    import colorsys

    if rng.random() < 0.25:
        return None
    cx = float(np.mean([p.x for p in placements])) + rng.uniform(-0.1, 0.1)
    cy = float(np.mean([p.y for p in placements])) + rng.uniform(-0.1, 0.1)
    r, g, b = colorsys.hsv_to_rgb(rng.uniform(0, 1), rng.uniform(0.2, 0.6), rng.uniform(0.45, 0.85))
    size = (float(rng.uniform(0.25, 0.6)), float(rng.uniform(0.25, 0.6)))
    return Mat(size, (cx, cy), float(rng.uniform(-math.pi, math.pi)), (r, g, b, 1.0))


@dataclass(frozen=True, slots=True)
class Visual:
    """One primitive visual of a `VisualBody`: ``shape`` box (``size`` = x, y, z), cylinder
    (radius, length, along the visual's z) or sphere (radius), its pose ``X_BG`` (4x4) in the
    body and its colour."""

    shape: str
    size: tuple[float, ...]
    X_BG: np.ndarray
    rgba: tuple[float, float, float, float]


@dataclass(frozen=True, slots=True)
class VisualBody:
    """A rigid body made of primitive visuals, welded at ``X_WB`` (4x4) in the scene."""

    name: str
    X_WB: np.ndarray
    visuals: tuple[Visual, ...]


@dataclass(frozen=True, slots=True)
class Placement:
    obj: GraspObject
    x: float
    y: float
    yaw: float


def look_at(eye: np.ndarray, target: np.ndarray, yaw: float) -> np.ndarray:
    """Rotation R_WC of a camera (x right, y down, z forward) at ``eye`` looking at ``target``.

    ``yaw`` turns the image about the optical axis (the hand's rotation about the approach).
    """
    z = target - eye
    z = z / np.linalg.norm(z)
    hint = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    x = hint - np.dot(hint, z) * z
    x = x / np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def project(K: np.ndarray, X_WC: np.ndarray, points_W: np.ndarray) -> np.ndarray:
    """Pixel (u, v) of world points (N x 3) for intrinsics K and camera pose X_WC (4x4)."""
    R, p = X_WC[:3, :3], X_WC[:3, 3]
    pc = (np.asarray(points_W) - p) @ R
    return np.stack(camera_to_pixel(pc.T, (K[0, 0], K[1, 1], K[0, 2], K[1, 2])), axis=1)


def grasp_rectangle(K, X_WC, center_W, yaw_W, opening, jaw) -> GraspRect:
    """Image rectangle of a top-down world grasp (centre, closing yaw, opening, jaw size)."""
    d = np.array([math.cos(yaw_W), math.sin(yaw_W), 0.0])
    n = np.array([-math.sin(yaw_W), math.cos(yaw_W), 0.0])
    pts = np.stack([center_W, center_W + d * opening / 2, center_W - d * opening / 2,
                    center_W + n * jaw / 2, center_W - n * jaw / 2])  # fmt: skip
    uv = project(K, X_WC, pts)
    du, dv = uv[1] - uv[2]
    return GraspRect(
        float(uv[0, 0]),
        float(uv[0, 1]),
        math.atan2(-dv, du),
        float(np.hypot(du, dv)),
        float(np.hypot(*(uv[3] - uv[4]))),
    )


def sample_scene(rng: np.random.Generator, max_objects: int) -> list[Placement]:
    """One to ``max_objects`` objects, half tools and half primitives, not overlapping."""
    count = int(rng.integers(1, max_objects + 1))
    placed: list[Placement] = []
    for i in range(count):
        kinds = TOOLS if rng.random() < 0.5 else PRIMITIVES
        obj = make_object(str(rng.choice(kinds)), rng)
        for _ in range(30):
            x, y = rng.uniform(-0.03, 0.03, 2) if i == 0 else rng.uniform(-0.17, 0.17, 2)
            if all(math.hypot(x - q.x, y - q.y) > obj.radius + q.obj.radius + 0.01 for q in placed):
                placed.append(
                    Placement(obj, float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
                )
                break
    return placed


class SceneRenderer:
    """A Drake diagram of one scene with one RgbdSensor per viewpoint."""

    def __init__(self, placements: list[Placement], cameras: list[np.ndarray], cfg: SynthConfig,
                 table_rgba: tuple[float, float, float, float],
                 mat: Mat | None = None, *, bodies: tuple[VisualBody, ...] = (),
                 image: tuple[int, int] | None = None, lights: tuple = (),
                 near: float = 0.02):  # fmt: skip
        """``bodies``: more bodies welded in the scene (their body indices, the label image's
        values for them, are ``self.body_of_extra``); ``image``: (width, height) instead of
        the square ``cfg.size``; ``lights``: Drake ``LightParameter``s (none: VTK's default
        head light); ``near``: the nearest rendered depth (m)."""
        from pydrake.geometry import (
            Box,
            ClippingRange,
            ColorRenderCamera,
            Cylinder,
            DepthRange,
            DepthRenderCamera,
            MakeRenderEngineVtk,
            RenderCameraCore,
            RenderEngineVtkParams,
            Sphere,
        )
        from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
        from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
        from pydrake.multibody.tree import SpatialInertia
        from pydrake.systems.framework import DiagramBuilder
        from pydrake.systems.sensors import CameraInfo, RgbdSensor

        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
        scene_graph.AddRenderer(
            "vtk", MakeRenderEngineVtk(RenderEngineVtkParams(lights=list(lights)))
        )
        inertia = SpatialInertia.SolidBoxWithMass(0.1, 0.05, 0.05, 0.05)
        table = plant.AddRigidBody("table", inertia)
        self.table_body = int(table.index())
        plant.WeldFrames(plant.world_frame(), table.body_frame(),
                         RigidTransform([0.0, 0.0, TABLE_TOP - 0.025]))  # fmt: skip
        plant.RegisterVisualGeometry(table, RigidTransform(), Box(1.5, 1.5, 0.05), "table",
                                     np.array(table_rgba))  # fmt: skip
        if mat is not None:  # its top 1 mm above the table's (0.025 m above the table body)
            X_TM = RigidTransform(RollPitchYaw(0, 0, mat.yaw), [*mat.center, 0.025])
            plant.RegisterVisualGeometry(table, X_TM, Box(*mat.size, 0.002), "mat",
                                         np.array(mat.rgba))  # fmt: skip
        self.body_of: list[int] = []
        for k, pl in enumerate(placements):
            body = plant.AddRigidBody(f"obj{k}_{pl.obj.name}", inertia)
            self.body_of.append(int(body.index()))
            X_WO = RigidTransform(RollPitchYaw(0, 0, pl.yaw), [pl.x, pl.y, TABLE_TOP])
            plant.WeldFrames(plant.world_frame(), body.body_frame(), X_WO)
            for j, part in enumerate(pl.obj.parts):
                R = RotationMatrix.MakeZRotation(part.yaw)
                if part.shape == "box":
                    shape = Box(*part.size)
                else:
                    shape = Cylinder(*part.size)
                    if part.lying:
                        R = R @ RotationMatrix.MakeYRotation(math.pi / 2)
                plant.RegisterVisualGeometry(body, RigidTransform(R, list(part.xyz)), shape,
                                             f"obj{k}_part{j}", np.array(part.rgba))  # fmt: skip
        self.body_of_extra: list[int] = []
        for extra in bodies:
            body = plant.AddRigidBody(extra.name, inertia)
            self.body_of_extra.append(int(body.index()))
            plant.WeldFrames(plant.world_frame(), body.body_frame(), RigidTransform(extra.X_WB))
            for j, vis in enumerate(extra.visuals):
                shape = {"box": Box, "cylinder": Cylinder, "sphere": Sphere}[vis.shape](*vis.size)
                plant.RegisterVisualGeometry(body, RigidTransform(vis.X_BG), shape,
                                             f"{extra.name}_v{j}", np.array(vis.rgba))  # fmt: skip
        plant.Finalize()
        width, height = image if image is not None else (cfg.size, cfg.size)
        info = CameraInfo(width, height, math.radians(cfg.fov_y_deg))
        core = RenderCameraCore("vtk", info, ClippingRange(min(0.01, near), 3.0), RigidTransform())
        self.K = info.intrinsic_matrix()
        self.sensors = []
        for X_WC in cameras:
            sensor = builder.AddSystem(
                RgbdSensor(
                    scene_graph.world_frame_id(),
                    RigidTransform(X_WC),
                    ColorRenderCamera(core, False),
                    DepthRenderCamera(core, DepthRange(near, 2.5)),
                )
            )
            builder.Connect(scene_graph.get_query_output_port(), sensor.query_object_input_port())
            self.sensors.append(sensor)
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()

    def render(self, view: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rgb uint8 HxWx3, depth float32 metres HxW, label int HxW) of one viewpoint."""
        sensor = self.sensors[view]
        ctx = sensor.GetMyContextFromRoot(self.context)
        rgb = np.array(sensor.color_image_output_port().Eval(ctx).data)[..., :3].copy()
        depth = np.array(sensor.depth_image_32F_output_port().Eval(ctx).data)[..., 0].copy()
        label = np.array(sensor.label_image_output_port().Eval(ctx).data)[..., 0].copy()
        depth[~np.isfinite(depth)] = 0.0
        return rgb, depth, label


def sample_cameras(rng: np.random.Generator, placements: list[Placement], cfg: SynthConfig):
    """Eye-in-hand viewpoints: above a random object, tilted, at a random yaw."""
    cams = []
    for _ in range(cfg.views):
        pl = placements[int(rng.integers(len(placements)))]
        target = np.array([pl.x, pl.y, TABLE_TOP]) + np.r_[rng.uniform(-0.04, 0.04, 2), 0.0]
        h = rng.uniform(cfg.min_height, cfg.max_height)
        cams.append(tilted_camera(rng, target, h, cfg.max_tilt_deg))
    return cams


def tilted_camera(
    rng: np.random.Generator, target: np.ndarray, height: float, max_tilt_deg: float
) -> np.ndarray:
    """A camera pose (4 x 4, world from camera) ``height`` from ``target`` along a direction
    tilted up to ``max_tilt_deg`` from the vertical at a random azimuth, looking at the target
    at a random roll: the eye-in-hand views of every rendered data set."""
    tilt = math.radians(rng.uniform(0.0, max_tilt_deg))
    az = rng.uniform(-math.pi, math.pi)
    eye = target + height * np.array(
        [math.sin(tilt) * math.cos(az), math.sin(tilt) * math.sin(az), math.cos(tilt)]
    )
    X = np.eye(4)
    X[:3, :3] = look_at(eye, target, rng.uniform(-math.pi, math.pi))
    X[:3, 3] = eye
    return X


def visible_grasps(K, X_WC, placements, body_of, label, size) -> list[GraspRect]:
    """Ground-truth rectangles of every grasp whose centre shows its own object."""
    rects = []
    for pl, body in zip(placements, body_of, strict=True):
        for g in pl.obj.grasps:
            center, yaw = grasp_world(g, pl.x, pl.y, pl.yaw)
            rect = grasp_rectangle(K, X_WC, center, yaw, g.opening, g.jaw)
            u, v = int(round(rect.x)), int(round(rect.y))
            if not (2 <= u < size - 2 and 2 <= v < size - 2) or rect.width < 3:
                continue
            if int(label[v, u]) != body:
                continue  # occluded by another object
            rects.append(rect)
    return rects


def generate(
    out: str | Path,
    scenes: int,
    cfg: SynthConfig = SynthConfig(),
    *,
    progress: bool = True,
    on_scene: Callable[[int], None] | None = None,
    first: int = 0,
    jobs: int = 1,
) -> dict[str, int]:
    """Render scenes ``first .. first + scenes - 1`` into ``out``; returns counts of scenes,
    images and grasps. Scene ``i`` depends on ``(seed, i)`` alone, so ``jobs > 1`` renders
    chunks of scenes in that many processes and writes the same files as one process."""
    if cfg.table not in TABLES:
        raise ValueError(f"SynthConfig.table: expected one of {TABLES}, got {cfg.table!r}")
    if jobs > 1 and scenes > 1:
        return _generate_in_processes(Path(out), scenes, cfg, first, jobs, progress, on_scene)
    from tqdm import tqdm

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    images = grasps = 0
    for i in tqdm(range(first, first + scenes), desc="render", unit="scene", disable=not progress):
        rng = np.random.default_rng((cfg.seed, i))
        placements = sample_scene(rng, cfg.max_objects)
        cams = sample_cameras(rng, placements, cfg)
        shade = rng.uniform(0.3, 0.8)
        table_rgba = (shade, shade * rng.uniform(0.8, 1.0), shade * rng.uniform(0.6, 1.0), 1.0)
        # drawn after everything "plain" draws: a plain set stays the same file for file
        mat = sample_mat(rng, placements) if cfg.table == "mats" else None
        renderer = SceneRenderer(placements, cams, cfg, table_rgba, mat)
        name = f"scene_{i:05d}"
        for v, X_WC in enumerate(cams):
            rgb, depth, label = renderer.render(v)
            rects = visible_grasps(renderer.K, X_WC, placements, renderer.body_of, label, cfg.size)
            if not rects:
                continue
            prefix = f"{v}_{name}"
            write_jacquard(out / name, prefix, rgb, depth, rects)
            meta = {"K": renderer.K.tolist(), "X_WC": X_WC.tolist(),
                    "objects": [pl.obj.name for pl in placements]}  # fmt: skip
            (out / name / f"{prefix}_camera.json").write_text(json.dumps(meta))
            images += 1
            grasps += len(rects)
        if on_scene:
            on_scene(i)
    return {"scenes": scenes, "images": images, "grasps": grasps}


def _generate_chunk(out: Path, first: int, scenes: int, cfg: SynthConfig) -> dict[str, int]:
    return generate(out, scenes, cfg, progress=False, first=first)


def _generate_in_processes(
    out: Path,
    scenes: int,
    cfg: SynthConfig,
    first: int,
    jobs: int,
    progress: bool,
    on_scene: Callable[[int], None] | None,
) -> dict[str, int]:
    """``generate`` over chunks of scenes (at most 10 each, about four chunks per process so
    that the work evens out) in ``jobs`` spawned processes, each building its own Drake
    diagrams (spawned, not forked: a forked VTK/EGL context is unsafe)."""
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from multiprocessing import get_context

    from tqdm import tqdm

    out.mkdir(parents=True, exist_ok=True)
    size = max(1, min(10, math.ceil(scenes / (4 * jobs))))
    end = first + scenes
    chunks = [(s, min(size, end - s)) for s in range(first, end, size)]
    total = {"scenes": scenes, "images": 0, "grasps": 0}
    with (
        ProcessPoolExecutor(jobs, mp_context=get_context("spawn")) as pool,
        tqdm(total=scenes, desc="render", unit="scene", disable=not progress) as bar,
    ):
        futures = {pool.submit(_generate_chunk, out, s, n, cfg): (s, n) for s, n in chunks}
        for future in as_completed(futures):
            done = future.result()
            total["images"] += done["images"]
            total["grasps"] += done["grasps"]
            s, n = futures[future]
            bar.update(n)
            for i in range(s, s + n) if on_scene else ():
                on_scene(i)
    return total
