"""The refinement workcell: two Pioneer-like robots and the task's object in Drake.

It only measures programs (Figueroa Heredia et al. 2018 §4); the refinement loop is
`tamp.refine.refinement`, which calls `simulate.simulate` as its measuring function.
`scenario` (the scene a program runs in: objects and goals, from YAML), `station` (the
diagram: `build_station` -> `RefineStation`), `sensors` (force, IMU, odometry), `channel`
(the architecture's FIFO queues in a LeafSystem), `skills` (`PioneerStateMachine`: a
robot's `tamp.refine.machine.Machine` on delivered data), `supervisor` (Fig. 5 online),
`messages` (port values), `outcome` (what the objects did) and `simulate` (one measured
run: a `tamp.refine.measure.Run`; seeded runs). docs/refinement.md.
"""
