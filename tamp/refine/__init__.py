"""Two-robot refinement (Figueroa Heredia et al. 2018): programs, architecture, refinement.

No Drake here: programs are state machines of behaviors (`program`, loaded by `loader`; a
robot's machine as its main CPU runs it: `machine`), the communication architecture is a
network of FIFO servers (`architecture`, `queues`), the refinement steps are pure functions
over programs (`steps`) and the refinement loop (`refinement`) runs the four phases on runs
measured by a function it is given (`measure`). The Drake workcell that provides that
function lives in `tamp.sim.refine`.
"""
