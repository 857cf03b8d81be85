"""Drake simulation of the workcells: one subpackage per workcell plus a shared core.

``tamp.sim.core`` holds what every workcell shares: where the models are
(`core.models.models_dir`, the ``tamp_models`` package data), the offline parser, the port
messages, the `BtExecutor` LeafSystem that ticks the very behavior tree of `tamp.bt`
through `PortWorld`, the chunked runner and Meshcat recording. ``tamp.sim.smp`` is the
SMP-MRO workcell (§V: a youBot-like mobile manipulator, bottles, area markers; Cases 1-3);
the LOTS (``tamp.sim.lots``) and refinement (``tamp.sim.refine``) workcells sit beside it.
A cell never imports another cell; what two cells share lives in ``core``. Each cell names
its files by role: ``scenario`` (its scenario files), ``station`` (the Drake diagram,
``build_station``), ``skills`` (the skill LeafSystem) and ``simulate`` (the run and its result).

This is the only package (with the grasp renderer) that imports Drake; import the
submodules directly (``from tamp.sim.smp.station import build_station``) so that importing
``tamp.sim`` itself stays cheap.
"""
