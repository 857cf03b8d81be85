"""The SMP-MRO workcell (§V): a youBot-like mobile manipulator, bottles, area markers.

`robot` (model numbers), `scenario` (scenario files, `SimScenario.with_events`), `builder`
(the diagram), `controller`, `estimator`, `ik`, `motion`, `runner` (weld toggling and
appearances between chunks), `perturb` (a seed's perturbation applied), `perception` (object
poses from the camera) and `simulate` (`prepare`: plan and verify; `simulate_smp_mro`: plan,
verify, build, run; `run_seeded`: one seeded run as JSON).
"""
