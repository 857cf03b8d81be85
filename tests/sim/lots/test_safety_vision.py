"""The distance of the nearest foreign depth point (class-agnostic: no label image) against
SceneGraph's signed distance between a sphere standing in for the person's hand and the
gripper's collision geometry, in front of the arm at Franka's ready pose; at the monitor's
resolution (`tamp.sim.lots.depth_safety.safety_camera_config`)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.geometry import (
    GeometryInstance,
    IllustrationProperties,
    MakeRenderEngineVtk,
    PerceptionProperties,
    RenderEngineVtkParams,
    RenderLabel,
    Rgba,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

from tamp.sim.core.camera import RENDERER
from tamp.sim.core.parsing import make_parser
from tamp.sim.lots.catalogue import ARM, HAND_LABEL, READY
from tamp.sim.lots.depth_safety import Scene, depth_points, safety_camera_config, separation
from tamp.sim.lots.safety import EE_BODIES, GripperModel
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.station import add_wrist_camera

pytestmark = pytest.mark.slow  # renders images
RADIUS = 0.03
SKIN = Rgba(0.9, 0.7, 0.6, 1.0)


class CameraScene:
    """Arm at the ready pose (fingers open), a free sphere labelled as a hand, the camera."""

    def __init__(self):
        b = DiagramBuilder()
        plant, sg = AddMultibodyPlantSceneGraph(b, 0.0)
        (arm,) = make_parser(plant).AddModelsFromUrl(ARM.url)
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(ARM.base_frame, arm))
        person = plant.AddModelInstance("person")
        hand = plant.AddRigidBody(
            "person_hand", person, SpatialInertia.SolidSphereWithMass(0.4, RADIUS)
        )
        plant.RegisterCollisionGeometry(
            hand, RigidTransform(), Sphere(RADIUS), "hand", CoulombFriction(0.5, 0.5)
        )
        visual = GeometryInstance(RigidTransform(), Sphere(RADIUS), "hand_visual")
        looks = PerceptionProperties()
        looks.AddProperty("label", "id", RenderLabel(HAND_LABEL))
        looks.AddProperty("phong", "diffuse", SKIN)
        visual.set_perception_properties(looks)
        shown = IllustrationProperties()
        shown.AddProperty("phong", "diffuse", SKIN)
        visual.set_illustration_properties(shown)
        plant.RegisterVisualGeometry(hand, visual)
        plant.Finalize()
        sg.AddRenderer(RENDERER, MakeRenderEngineVtk(RenderEngineVtkParams(backend="EGL")))
        cam = load_cell_scenario("tower").camera
        config = safety_camera_config(cam.width, cam.height, cam.fov_y_deg, cam.near, cam.far)
        self.camera, self.intrinsics = add_wrist_camera(b, plant, sg, arm, config)
        self.diagram = b.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant, self.sg, self.hand = plant, sg, hand
        self.plant_context = plant.GetMyContextFromRoot(self.context)
        self.q9 = np.r_[READY, ARM.finger_max, ARM.finger_max]
        plant.SetPositions(self.plant_context, arm, self.q9)
        self.tcp = plant.GetFrameByName(ARM.tcp_frame, arm).CalcPoseInWorld(self.plant_context)
        self.hand_ids = set(plant.GetCollisionGeometriesForBody(hand))
        self.ee_ids = {
            gid
            for name in EE_BODIES
            for gid in plant.GetCollisionGeometriesForBody(plant.GetBodyByName(name, arm))
        }
        self.gripper = GripperModel()
        self.gripper.set(self.q9)

    def place(self, offset) -> None:
        p = self.tcp.translation() + np.asarray(offset)
        self.plant.SetFreeBodyPose(self.plant_context, self.hand, RigidTransform(p))

    def signed_distance(self) -> float:
        query = self.sg.get_query_output_port().Eval(self.sg.GetMyContextFromRoot(self.context))
        return min(
            r.distance
            for r in query.ComputeSignedDistancePairwiseClosestPoints(0.5)
            if {r.id_A, r.id_B} & self.hand_ids and {r.id_A, r.id_B} & self.ee_ids
        )

    def image_distance(self) -> float:
        cam = self.camera.GetMyContextFromRoot(self.context)
        depth = self.camera.depth_image_32F_output_port().Eval(cam).data[..., 0]
        points, too_close = depth_points(depth, self.intrinsics, self.gripper.camera_pose())
        assert too_close == 0
        # no table in this scene: its plane far below
        return separation(points, Scene(-10.0, self.gripper.boxes_in_world()))


@pytest.fixture(scope="module")
def scene():
    return CameraScene()


# sphere centres relative to the TCP (world frame; the gripper points down)
IN_VIEW = [
    (0.0, 0.0, -0.05),  # under the fingertips, 2.3 cm away
    (0.0, 0.0, -0.07),
    (0.0, 0.0, -0.09),  # just beyond 5 cm
    (0.0, 0.0, -0.13),
    (0.04, 0.0, -0.06),  # towards the camera's side
    (-0.03, 0.0, -0.07),  # away from it: the closest point is partly hidden
]


@pytest.mark.parametrize("offset", IN_VIEW)
def test_image_distance_matches_scene_graph(scene, offset):
    scene.place(offset)
    truth = scene.signed_distance()
    seen = scene.image_distance()
    # the camera sees only the hand's visible surface: never nearer than the truth (up to
    # the depth image's float precision), at most a few millimetres farther
    assert truth - 1e-3 <= seen <= truth + 6e-3
    assert (seen < 0.05) == (truth < 0.05)


def test_the_arm_alone_shows_nothing_foreign(scene):
    """The gripper's own pixels (fingers in view) are subtracted by its collision boxes; the
    nearest thing left is the arm's base far below (no table here), 0.44 m away."""
    scene.place((0.0, 0.0, 5.0))  # far out of view
    assert scene.image_distance() > 0.4


def test_a_hand_beside_the_fingers_is_out_of_view(scene):
    """The wrist camera's blind spot: 1.2 cm beside the pads, outside the field of view."""
    scene.place((0.0, 0.09, -0.02))
    assert scene.signed_distance() < 0.05
    assert scene.image_distance() > 0.4  # the hand is not seen
