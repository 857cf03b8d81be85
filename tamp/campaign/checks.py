"""What the driver validates before a campaign starts, per kind: the file loads (and its
``perturbation`` section with it), so that bad input is exit 2 before any run, not N
crashed runs. Each check is the kind's own loader; the runs load the file again where they
run (`tamp.campaign.kinds`)."""

from __future__ import annotations


def check_smp_mro(scenario: str) -> None:
    from tamp.sim.smp.scenario import load_scenario, scenario_path

    load_scenario(scenario_path(scenario))


def check_lots(task: str, interference: str | None = None, scenario: str | None = None) -> None:
    """The task, its workcell (``scenario``, default the packaged one named like the task;
    perturbation included), that they match, and the person's interference file."""
    from tamp.lots.task import load_events, load_task
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.simulate import check_matches

    loaded = load_task(task)
    check_matches(loaded, load_cell_scenario(scenario or loaded.name))
    if interference:
        from tamp.sim.lots.simulate import check_person_classes

        check_person_classes(load_events(interference, loaded))


def check_refine(scenario: str) -> None:
    """The program, its architecture and its perturbation section."""
    from tamp.refine.architecture import load_architecture
    from tamp.refine.loader import load_program
    from tamp.sim.refine.seeded import program_perturbation

    program = load_program(scenario)
    if program.architecture:
        load_architecture(program.architecture)
    program_perturbation(program)
