"""The refinement workcell (seed 002): two Pioneer-like robots and the task object in Drake.

`builder` (the diagram), `sensors` (force, IMU, odometry), `channel` (the architecture's
FIFO queues in a LeafSystem), `machine` + `executor` (the state machine on delivered data),
`supervisor` (Fig. 5 online), `runner` (one measured run: a `Timeline`), `refinement` (the
four phases). docs/refinement.md.
"""
