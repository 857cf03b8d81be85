"""RGB-D cameras on a robot body, their pinhole geometry, and seeded depth noise.

`camera_config` describes a camera as Drake's `CameraConfig`; `add_rgbd_camera` adds a plain
`RgbdSensor` of that config (it renders only when one of its image ports is evaluated: no
zero-order hold rendering at a fixed rate) at a pose on a body, with a VTK renderer over EGL
(headless: Debian's ``libegl1`` is all it needs). Every camera of every workcell is made by
these two.
`backproject` turns a pixel and its depth into a world point (Drake's camera frame: +z
along the optical axis, +x right, +y down).
`DepthNoise` adds per-pixel Gaussian noise to a depth image, drawn from the run's seed and
the frame's time only (`tamp.perturbation.stream`), so a seeded run renders the same
noisy images every time.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import MakeRenderEngineVtk, RenderEngineVtkParams
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem
from pydrake.systems.sensors import CameraConfig, ImageDepth32F, RgbdSensor

from tamp.grasp.pinhole import pixel_to_camera
from tamp.perturbation import stream

RENDERER = "vtk"


def camera_config(
    *, name: str, width: int, height: int, fov_y_deg: float, near: float = 0.05, far: float = 10.0
) -> CameraConfig:
    """Drake's `CameraConfig` of one of our cameras: colour, depth and label images of
    ``width`` x ``height`` with a vertical field of view ``fov_y_deg``, rendered by VTK."""
    return CameraConfig(
        width=width,
        height=height,
        focal=CameraConfig.FovDegrees(y=fov_y_deg),
        clipping_near=near,
        clipping_far=far,
        z_near=near,
        z_far=far,
        renderer_name=RENDERER,
        renderer_class="RenderEngineVtk",
        name=name,
        rgb=True,
        depth=True,
        label=True,
    )


def add_rgbd_camera(
    builder, plant, scene_graph, body, X_BC: RigidTransform, config: CameraConfig
) -> tuple[RgbdSensor, tuple[float, float, float, float]]:
    """A plain `RgbdSensor` configured by ``config`` at ``X_BC`` on ``body`` (and the VTK
    renderer, once per scene graph); returns it and its intrinsics (fx, fy, cx, cy).

    Not `ApplyCameraConfig`: that adds an `RgbdSensorDiscrete` whose zero-order hold renders
    at the config's fps all the time; ours renders only when an image port is evaluated."""
    if not scene_graph.HasRenderer(config.renderer_name):
        scene_graph.AddRenderer(
            config.renderer_name, MakeRenderEngineVtk(RenderEngineVtkParams(backend="EGL"))
        )
    color_cam, depth_cam = config.MakeCameras()
    camera = builder.AddSystem(
        RgbdSensor(plant.GetBodyFrameIdOrThrow(body.index()), X_BC, color_cam, depth_cam)
    )
    camera.set_name(config.name)
    builder.Connect(scene_graph.get_query_output_port(), camera.query_object_input_port())
    K = depth_cam.core().intrinsics()
    return camera, (K.focal_x(), K.focal_y(), K.center_x(), K.center_y())


def backproject(u, v, depth, intrinsics: tuple[float, float, float, float], X_WC) -> np.ndarray:
    """The world point(s) seen at pixel (u, v) with depth ``depth`` (along the optical axis):
    `tamp.grasp.pinhole.pixel_to_camera` moved by the camera pose (arrays: 3 x N)."""
    return X_WC.multiply(pixel_to_camera(u, v, depth, intrinsics))


def look_at(position, target) -> RigidTransform:
    """A camera pose at ``position`` whose optical axis points at ``target`` (image +y down)."""
    p = np.asarray(position, float)
    z = np.asarray(target, float) - p
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    from pydrake.math import RotationMatrix

    return RigidTransform(RotationMatrix(np.column_stack([x, y, z])), p)


class DepthNoise(LeafSystem):
    """depth image in -> the same image plus N(0, sigma) per valid pixel (seeded per frame)."""

    def __init__(self, *, width: int, height: int, sigma: float, seed: int, period: float):
        super().__init__()
        self.set_name("depth_noise")
        self._sigma = float(sigma)
        self._seed = int(seed)
        self._period = float(period)
        self.depth_in = self.DeclareAbstractInputPort(
            "depth_in", AbstractValue.Make(ImageDepth32F(width, height))
        )
        self.depth_out = self.DeclareAbstractOutputPort(
            "depth_out", lambda: AbstractValue.Make(ImageDepth32F(width, height)), self._calc
        )

    def _calc(self, context, output) -> None:
        image = self.depth_in.Eval(context)
        out = output.get_mutable_value()
        out.resize(image.width(), image.height())
        depth = np.array(image.data, copy=True)
        if self._sigma > 0:
            frame = int(round(context.get_time() / self._period))
            rng = stream(self._seed, "sensor", "depth", frame)
            noise = rng.standard_normal(depth.shape).astype(np.float32) * self._sigma
            valid = np.isfinite(depth) & (depth > 0)
            depth[valid] += noise[valid]
        out.mutable_data[:] = depth
