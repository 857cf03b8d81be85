"""The SMP-MRO workcell (§V): a youBot-like mobile manipulator, bottles, area markers.

`robot` (model numbers), `scenario` (scenario files, `SimScenario.with_events`), `station`
(the diagram: `build_station` -> `SmpStation`), `skills` (`YouBotSkillController`),
`estimator`, `ik`, `motion`, `runner` (weld toggling and appearances between chunks, `judge`,
`SimResult`), `perturb` (a seed's perturbation applied), `perception` (object poses from the
camera, through the shared `tamp.sim.core.perception` detector) and `simulate` (`prepare`:
plan and verify; `simulate_smp_mro`: plan, verify, build, run; `run_seeded`: one seeded run
as JSON).
"""
