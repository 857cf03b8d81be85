"""WorldStateEstimator: plant poses -> the symbolic `WorldState` every executor reads.

Inputs: the plant's body poses and the gripper's `GraspRequest`. Output (abstract): a
`tamp.world.WorldState` with the robot's base pose (x, y, yaw of ``base_link``), the held
object, every object inside the workspace (an object waiting outside it, such as Case 3's
O_a before a person puts it down, is not seen), and the areas of the demonstration.

``held`` is the object the gripper reports holding (`GraspRequest.holding`, its grasp
sensor: set after a lift checked on the plant, cleared after a place checked on the plant).
"""

from __future__ import annotations

from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.framework import LeafSystem

from tamp.sim.core.messages import GraspRequest
from tamp.world.geometry import Area, Point, Pose, Quaternion
from tamp.world.state import ObjectState, WorldState


def pose_of(X: RigidTransform) -> Pose:
    """A Drake pose as the symbolic `Pose` (position + unit quaternion x, y, z, w)."""
    p = X.translation()
    q = X.rotation().ToQuaternion()
    return Pose(
        Point(float(p[0]), float(p[1]), float(p[2])), Quaternion(q.x(), q.y(), q.z(), q.w())
    )


class WorldStateEstimator(LeafSystem):
    """Reads object and robot poses from the plant and outputs the symbolic WorldState."""

    def __init__(
        self,
        *,
        bodies: dict[str, int],
        base_body: int,
        areas: dict[str, Area],
        workspace: tuple[float, float, float, float],
    ):
        super().__init__()
        self.set_name("world_state_estimator")
        self._bodies = dict(bodies)
        self._base = base_body
        self._areas = dict(areas)
        self._workspace = workspace
        self.body_poses_port = self.DeclareAbstractInputPort(
            "body_poses", AbstractValue.Make([RigidTransform()])
        )
        self.grasp_port = self.DeclareAbstractInputPort("grasp", AbstractValue.Make(GraspRequest()))
        self.world_state_port = self.DeclareAbstractOutputPort(
            "world_state",
            lambda: AbstractValue.Make(WorldState(robot=Pose(Point(0.0, 0.0)))),
            self._calc,
        )

    def estimate(self, poses, grasp: GraspRequest) -> WorldState:
        X_B = poses[self._base]
        p = X_B.translation()
        yaw = RollPitchYaw(X_B.rotation()).yaw_angle()
        robot = Pose.at(float(p[0]), float(p[1]), 0.0, float(yaw))
        xmin, xmax, ymin, ymax = self._workspace
        objects = {}
        for uid, index in self._bodies.items():
            X = poses[index]
            x, y, _ = X.translation()
            if xmin <= x <= xmax and ymin <= y <= ymax:
                objects[uid] = ObjectState(uid, pose_of(X))
        held = grasp.holding if grasp.holding in objects else None
        return WorldState(robot=robot, held=held, objects=objects, areas=dict(self._areas))

    def _calc(self, context, output) -> None:
        poses = self.body_poses_port.Eval(context)
        grasp = self.grasp_port.Eval(context)
        output.set_value(self.estimate(poses, grasp))
