"""tamp: task-and-motion planning for human-robot collaboration, with formal verification.

Layers (docs/architecture.md has them all): ``tamp.world`` (shared symbolic world),
``tamp.demo`` (demonstration → goals + constraints), ``tamp.rg`` (reachability graph and
search), ``tamp.bt`` (behavior trees), ``tamp.lots`` (LTL with local observation),
``tamp.grasp`` (HRG-Net), ``tamp.sim`` (Drake). Nothing outside ``tamp.sim`` and
``tamp.grasp.synthetic`` imports Drake.
"""

__version__ = "0.2.0"
