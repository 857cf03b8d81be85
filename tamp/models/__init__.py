"""The project's model data, package data of ``tamp`` (the Drake package ``tamp_models``).

``sdf/`` (the workcells' robots, objects and markers, ``package://tamp_models/...`` through
``package.xml``) and ``weights/`` (trained grasp networks). Data only: find it with
`tamp.sim.core.models.models_dir`, never relative to a source file.
"""
