"""The LOTS workcell (Zhou et al., IEEE T-ASE 2023, §V): a Panda-like 7-DoF arm with a wrist
camera over a table with two workspaces (W^A, W^B) and a waste basket, the tools of the
paper's tasks, and optionally a scripted person's hand. `catalogue` (the arm's numbers, the
packaged object classes), `scenario` (cell scenario files on the typed loader, a scenario's
own object classes, seeded perturbations), `plant` (the plant: table, arm, baskets,
objects), `station` (the diagram: `build_station` -> `LotsStation`), `skills`
(`PandaSkillController`: LookAt, Pick, Place, Discard, Wait), `kinematics`, `grasping` (the
grasp network's candidates), `command` (the 1 kHz arm command stream), `safety` (the monitor
that holds the arm while a hand is near), `person` (the scripted person),
`controller_system` (the LOTS controller as a LeafSystem), `driver` (start, poll, cancel a
skill over a `Simulator`) and `simulate` (`LotsScenario`: a task, its cell and the person's
script; `simulate_lots`: one run and its `LotsSimResult`; `LotsWorkcell`, exported here as
``WORKCELL``: the cell's `tamp.sim.core.workcell.Workcell`). Perception is the shared
detector of `tamp.sim.core.perception`. Importing this package does not import Drake.
"""

from tamp.sim.lots.simulate import WORKCELL

__all__ = ["WORKCELL"]
