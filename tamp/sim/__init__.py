"""Drake simulation of SMP-MRO (§V: youBot pick-and-place, Cases 1-3).

A `MultibodyPlant` + `SceneGraph` diagram with a youBot-like mobile manipulator, bottles and
area markers (``models/sdf``), where a `BtExecutor` LeafSystem ticks the very behavior tree
of `tamp.bt` against the plant through `PortWorld`, a `SkillController` moves the robot
(MoveTo / Pick / Place), and a `WorldStateEstimator` turns plant poses into the symbolic
`WorldState`. Entry points: `load_scenario`, `build_diagram`, `SimRunner`, and
`simulate_smp_mro` (plan, verify, build, run) in `tamp.sim.smp.simulate`.

This is the only package (with the grasp renderer) that imports Drake; import the
submodules directly (``from tamp.sim.smp.builder import build_diagram``) so that importing
``tamp.sim`` itself stays cheap.
"""
