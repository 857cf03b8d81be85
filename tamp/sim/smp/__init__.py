"""The SMP-MRO workcell (§V): a youBot-like mobile manipulator, bottles, area markers.

`robot` (model numbers), `scenario` (scenario files, `SimScenario.with_events`),
`object_models` (object models a scenario declares), `station` (the diagram:
`build_station` -> `SmpStation`), `skills` (`YouBotSkillController`), `estimator`, `ik`,
`motion`, `runner` (weld toggling and appearances between chunks, `judge`, `SimResult`),
`perturb` (a seed's perturbation applied), `perception` (object poses from the camera,
through the shared `tamp.sim.core.perception` detector) and `simulate` (`prepare`: plan and
verify; `simulate`: plan, verify, perturb, build, run; `SmpMroWorkcell`, exported here as
``WORKCELL``: the cell's `tamp.sim.core.workcell.Workcell`). Importing this package does not
import Drake.
"""

from tamp.sim.smp.simulate import WORKCELL

__all__ = ["WORKCELL"]
