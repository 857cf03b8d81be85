"""Drake simulation of the workcells: one subpackage per workcell plus a shared core.

``tamp.sim.core`` holds what every workcell shares: where the models are
(`core.models.models_dir`, the ``tamp_models`` package data), the offline parser, the port
messages, the `BtExecutor` LeafSystem that ticks the very behavior tree of `tamp.bt`
through `PortWorld`, the chunked runner and Meshcat recording. ``tamp.sim.smp`` is the
SMP-MRO workcell (§V: a youBot-like mobile manipulator, bottles, area markers; Cases 1-3);
the LOTS and refinement workcells sit beside it.

This is the only package (with the grasp renderer) that imports Drake; import the
submodules directly (``from tamp.sim.smp.builder import build_diagram``) so that importing
``tamp.sim`` itself stays cheap.
"""
