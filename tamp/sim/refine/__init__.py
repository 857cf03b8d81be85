"""The refinement workcell: two Pioneer-like robots and the task object (seed 002).

Built so far: `ordering` (the LTL gate on a program before it is simulated). The diagram,
the Channel, StateMachineExecutor and RateTuningSupervisor LeafSystems and the runner come
next (docs/refinement.md).
"""
