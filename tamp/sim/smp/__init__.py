"""The SMP-MRO workcell (§V): a youBot-like mobile manipulator, bottles, area markers.

Entry points: `tamp.sim.smp.scenario.load_scenario`, `tamp.sim.smp.builder.build_diagram`,
`tamp.sim.smp.runner.SimRunner` and `tamp.sim.smp.simulate.simulate_smp_mro` (plan, verify,
build, run).
"""
