"""Every registered workcell builds its packaged scenario into a Drake Diagram whose ports
are exported by name (the `tamp.sim.core.workcell.Workcell` contract), without running it."""

from __future__ import annotations

import pytest
from pydrake.systems.framework import Diagram

from tamp.sim.core.workcell import get

#: cell -> (the packaged main input, the ports its Diagram must export)
PORTS = {
    "smp-mro": ("case1", {"skill_command", "skill_status", "world_state", "robot_state"}),
    "lots": ("tower", {"skill_command", "skill_status", "observation", "arm_state"}),
    "refine": ("task4", {"R1_state", "R2_state", "R1_progress", "R2_progress", "rates"}),
}


@pytest.mark.parametrize("name", sorted(PORTS))
def test_build_gives_a_diagram_with_named_ports(name):
    cell = get(name)
    main, expected = PORTS[name]
    diagram = cell.build(cell.load(main))
    assert isinstance(diagram, Diagram)
    ports = {diagram.get_input_port(i).get_name() for i in range(diagram.num_input_ports())}
    ports |= {diagram.get_output_port(i).get_name() for i in range(diagram.num_output_ports())}
    assert expected <= ports, sorted(ports)
    diagram.CreateDefaultContext()  # a valid diagram
