"""Meshcat views of a workcell: a live view while it runs, or a self-contained recording.

Every workcell adds the same `MeshcatVisualizer` (illustration geometry, 30 frames per
second) and records the same way: the visualizer keeps the frames while the simulator
runs, then `save_recording` replays them into the Meshcat scene and writes Meshcat's
static HTML (the animation embedded, openable offline). Both open framed on the workcell:
`add_visualizer` points Meshcat's camera at the bounds of the cell's geometry in its
default configuration (`cell_bounds`, `camera_for`), so the robot is not a speck at
Meshcat's default view. A live view asked for on the command line (`live_view`) is the
one Meshcat every run in its block draws into, and `hold_open` keeps it served after the
run until the user closes it. This is the only module that imports `Meshcat`.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role

FRAME_RATE = 30.0
#: Geometry larger than this (m, half extent) is the ground or a wall, not the cell.
MAX_FRAMED_EXTENT = 5.0
#: Meshcat's default vertical field of view (degrees).
FIELD_OF_VIEW = 75.0
#: Direction from the cell's centre to the camera: a three-quarter view from above.
VIEW_DIRECTION = (1.0, -1.2, 0.9)

_LIVE: list[Meshcat] = []


def new_meshcat() -> Meshcat:
    """A local Meshcat server on a free port (its URL: ``web_url()``); inside `live_view`,
    that view's Meshcat (so a run that records while it is watched uses one server)."""
    return _LIVE[-1] if _LIVE else Meshcat(0)


@contextmanager
def live_view() -> Iterator[Meshcat]:
    """A local Meshcat that every run inside the block draws into (`new_meshcat`)."""
    meshcat = Meshcat(0)
    _LIVE.append(meshcat)
    try:
        yield meshcat
    finally:
        _LIVE.remove(meshcat)


def hold_open(meshcat: Meshcat, wait: Callable[[str], object] = input) -> None:
    """Keep ``meshcat`` served after the run until the user presses Enter (or Ctrl-C, or
    closes standard input), so a live view does not vanish when the simulation ends."""
    print(
        f"meshcat: {meshcat.web_url()} stays open; press Enter (or Ctrl-C) to close",
        file=sys.stderr,
        flush=True,
    )  # on stderr: stdout stays the run's report (or its JSON document)
    try:
        wait("")
    except (EOFError, KeyboardInterrupt):
        print(file=sys.stderr)


def add_visualizer(builder, scene_graph, meshcat: Meshcat) -> MeshcatVisualizer:
    """A visualizer of ``scene_graph``'s illustration geometry, published at `FRAME_RATE`,
    with Meshcat's camera framing the cell (when the builder holds a finalized plant)."""
    params = MeshcatVisualizerParams(publish_period=1.0 / FRAME_RATE, role=Role.kIllustration)
    visualizer = MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)
    bounds = cell_bounds(builder, scene_graph)
    if bounds is not None:
        position, target = camera_for(*bounds)
        meshcat.SetCameraPose(position, target)
    return visualizer


def cell_bounds(builder, scene_graph) -> tuple[np.ndarray, np.ndarray] | None:
    """Lower and upper corners of the illustration geometry of the builder's finalized
    `MultibodyPlant` in its default configuration, plus the world-anchored geometry: the
    corners of each shape's own bounding box (`shape_half_extents`) in the world; shapes
    larger than `MAX_FRAMED_EXTENT` (ground, walls) are left out. None without a finalized
    plant or any framed shape."""
    from pydrake.math import RigidTransform
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.multibody.tree import BodyIndex

    plants = [s for s in builder.GetSystems() if isinstance(s, MultibodyPlant)]
    if not plants or not plants[0].is_finalized():
        return None
    plant = plants[0]
    inspector = scene_graph.model_inspector()
    context = plant.CreateDefaultContext()
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    points: list[np.ndarray] = []

    def add(X_WG: RigidTransform, half: np.ndarray | None) -> None:
        if half is None or float(half.max()) > MAX_FRAMED_EXTENT:
            return
        corners = signs * half  # the shape's box in its own frame, 8 x 3
        points.append(X_WG.rotation().matrix() @ corners.T + X_WG.translation()[:, None])

    for i in range(plant.num_bodies()):
        body = plant.get_body(BodyIndex(i))
        X_WB = plant.EvalBodyPoseInWorld(context, body)
        for gid in plant.GetVisualGeometriesForBody(body):
            add(X_WB @ inspector.GetPoseInFrame(gid), shape_half_extents(inspector.GetShape(gid)))
    for gid in inspector.GetGeometries(inspector.world_frame_id(), Role.kIllustration):
        add(inspector.GetPoseInFrame(gid), shape_half_extents(inspector.GetShape(gid)))
    if not points:
        return None
    stacked = np.hstack(points)
    return stacked.min(axis=1), stacked.max(axis=1)


def shape_half_extents(shape) -> np.ndarray | None:
    """Half extents of ``shape``'s bounding box in its own frame (None: unbounded, e.g. a
    half space); a mesh counts as a 0.1 m cube around its frame (the cell's boxes carry
    the bounds)."""
    from pydrake.geometry import Box, Capsule, Cylinder, Ellipsoid, HalfSpace, Sphere

    if isinstance(shape, Box):
        return 0.5 * np.array([shape.width(), shape.depth(), shape.height()])
    if isinstance(shape, Sphere):
        return np.full(3, shape.radius())
    if isinstance(shape, Cylinder):
        r = shape.radius()
        return np.array([r, r, 0.5 * shape.length()])
    if isinstance(shape, Capsule):
        r = shape.radius()
        return np.array([r, r, r + 0.5 * shape.length()])
    if isinstance(shape, Ellipsoid):
        return np.array([shape.a(), shape.b(), shape.c()])
    if isinstance(shape, HalfSpace):
        return None
    return np.full(3, 0.1)


def camera_for(
    lower: Sequence[float], upper: Sequence[float], *, fov_deg: float = FIELD_OF_VIEW
) -> tuple[np.ndarray, np.ndarray]:
    """Camera position and target (world frame) that show the box ``lower``..``upper``
    whole: the target is its centre, the camera along `VIEW_DIRECTION` at the distance
    where the box's bounding sphere fills the field of view ``fov_deg``."""
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    target = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.25)
    distance = radius / math.sin(math.radians(fov_deg) / 2)
    direction = np.asarray(VIEW_DIRECTION) / np.linalg.norm(VIEW_DIRECTION)
    return target + distance * direction, target


def start_recording(visualizer: MeshcatVisualizer) -> None:
    """Keep every published frame (before the simulator starts)."""
    visualizer.StartRecording(set_transforms_while_recording=False)


#: colours of a view's overlays (`draw_views`): its point cloud, frustum, grasp candidates and
#: the best of them
CLOUD_RGBA = (0.15, 0.55, 1.0, 1.0)
FRUSTUM_RGBA = (1.0, 0.85, 0.1, 1.0)
GRASP_RGBA = (1.0, 0.45, 0.0, 1.0)
BEST_GRASP_RGBA = (0.1, 0.9, 0.2, 1.0)
#: size of a drawn point (m)
POINT_SIZE = 0.004


def draw_views(
    meshcat: Meshcat,
    visualizer: MeshcatVisualizer,
    views: Sequence,
    *,
    intrinsics: tuple[float, float, float, float],
    size: tuple[int, int],
    end: float,
    grasps: Callable[[object], Sequence] | None = None,
    prefix: str = "/views",
) -> int:
    """Draw every view of ``views`` (`tamp.sim.core.view_log.ViewRecord`) under ``prefix``:
    its depth as a world point cloud, the camera's frustum and, where ``grasps`` gives them
    (best first), the grasp candidates as closing lines (the best in green); and key each
    view's visibility in the visualizer's recording so that it shows from its own time to the
    next view's (`view_log.visible_spans`). Call before `save_recording`. Returns the number
    of views drawn."""
    from pydrake.geometry import Rgba
    from pydrake.perception import PointCloud

    from tamp.sim.core.view_log import frustum_segments, grasp_segments, visible_spans

    recording = visualizer.get_mutable_recording()
    spans = visible_spans([v.time for v in views], end)
    for k, (view, (t0, t1)) in enumerate(zip(views, spans, strict=True)):
        path = f"{prefix}/{k:03d}"
        cloud = PointCloud(len(view.points))
        cloud.mutable_xyzs()[:] = np.asarray(view.points, float).T
        meshcat.SetObject(f"{path}/cloud", cloud, POINT_SIZE, Rgba(*CLOUD_RGBA))
        start, stop = frustum_segments(view.X_WC, intrinsics, size)
        meshcat.SetLineSegments(f"{path}/frustum", start, stop, 2.0, Rgba(*FRUSTUM_RGBA))
        found = list(grasps(view)) if grasps is not None else []
        if found:
            start, stop = grasp_segments(found[:1])
            meshcat.SetLineSegments(f"{path}/best", start, stop, 4.0, Rgba(*BEST_GRASP_RGBA))
        if len(found) > 1:
            start, stop = grasp_segments(found[1:])
            meshcat.SetLineSegments(f"{path}/grasps", start, stop, 2.0, Rgba(*GRASP_RGBA))
        meshcat.SetProperty(path, "visible", False)
        first, last = recording.frame(t0), recording.frame(t1)
        last = max(last, first + 1)
        if first > 0:
            recording.SetProperty(0, path, "visible", False)
        recording.SetProperty(first, path, "visible", True)
        recording.SetProperty(last, path, "visible", False)
    return len(views)


def save_recording(visualizer: MeshcatVisualizer, meshcat: Meshcat, path: str | Path) -> str:
    """Stop recording and write the animation as one self-contained HTML file at ``path``
    (it opens on the camera `add_visualizer` set)."""
    visualizer.StopRecording()
    visualizer.PublishRecording()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(meshcat.StaticHtml())
    return str(out)
