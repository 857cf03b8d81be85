"""The refinement workcell: two Pioneer-like robots and the task's object in Drake.

It only measures programs (Figueroa Heredia et al. 2018 §4); the refinement loop is
`tamp.refine.refinement`, which calls `simulate.simulate` as its measuring function.
`scenario` (what a run loads: the program, its architecture and its scene, the scene's
objects and goals from YAML), `station` (the
diagram: `build_station` -> `RefineStation`), `sensors` (force, IMU, odometry), `channel`
(the architecture's FIFO queues in a LeafSystem), `skills` (`PioneerStateMachine`: a
robot's `tamp.refine.machine.Machine` on delivered data), `supervisor` (Fig. 5 online),
`messages` (port values), `outcome` (what the objects did) and `simulate` (one measured
run: a `tamp.refine.measure.Run`; seeded runs; `RefineWorkcell`, exported here as
``WORKCELL``: the cell's `tamp.sim.core.workcell.Workcell`). Importing this package does not
import Drake. docs/refinement.md.
"""

from tamp.sim.refine.simulate import WORKCELL

__all__ = ["WORKCELL"]
