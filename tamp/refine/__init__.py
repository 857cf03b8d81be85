"""Two-robot refinement (Figueroa Heredia et al. 2018): programs, architecture, refinement steps.

No Drake here: programs are state machines of behaviors (`program`, loaded by `loader`), the
communication architecture is a network of FIFO servers (`architecture`, `queues`), and the
refinement steps are pure functions over programs (`steps`). The simulation that measures
behavior durations and message delays lives in `tamp.sim.refine`.
"""
