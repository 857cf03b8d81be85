"""The plant every workcell starts from: a discrete `MultibodyPlant` under SAP, with its parser.

SAP is Drake's discrete contact solver that weld constraints need (SMP-MRO youBot) and that
keeps friction grasps stable at millisecond steps (LOTS arm); both workcells take the time
step and the contact model (point / hydroelastic) from their scenario file.
"""

from __future__ import annotations

from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant, MultibodyPlantConfig

from tamp.sim.core.parsing import make_parser


def add_sap_plant(
    builder, *, time_step: float, contact_model: str
) -> tuple[MultibodyPlant, object, Parser]:
    """Adds plant + scene graph to ``builder``; returns them and a parser of our models."""
    config = MultibodyPlantConfig(
        time_step=time_step,
        discrete_contact_approximation="sap",
        contact_model=contact_model,
    )
    plant, scene_graph = AddMultibodyPlant(config, builder)
    return plant, scene_graph, make_parser(plant)
