"""Why a simulated run failed, said the same way by every workcell.

A run's JSON has ``status`` (SUCCESS | FAILURE | TIMEOUT), ``cause`` (None on success, else
one of `CAUSES`) and ``task_time`` (sim seconds), so a campaign can group failures without
parsing reasons. ``reason`` keeps the human sentence. No Drake import here.
"""

from __future__ import annotations

#: cause -> what it means (docs/simulation.md lists the same)
CAUSES: dict[str, str] = {
    "timeout": "no result within the run's sim-time limit",
    "grasp_missed": "the fingers closed on nothing (friction grasps: the gripper's sensor)",
    "grasp_slipped": "the object left the hand after the lift or while carried",
    "injected_failure": "a failure the scenario asked for (fail: or perturbation.skills)",
    "object_not_found": "the object was not perceived where the skill needed it",
    "unreachable": "no place to stand, no base path, or no arm pose for the skill",
    "area_occupied": "the place to put the object on is occupied",
    "placement_off": "an object does not rest in its goal area on the plant",
    "disturbed": "an object ended knocked over or on top of another, or moved though the "
    "robot never picked it (SMP-MRO cell)",
    "collision": "a robot's chassis or lever touched something (refinement workcell)",
    "order_violated": "the measured event order breaks the program's ordering property",
    "task_failed": "the controller gave up with no skill failure to blame",
    "sim_diverged": "the physics went non-finite (a contact the solver could not resolve); "
    "the run stopped there",
    "crash": "the simulation raised an error (a campaign records it, the run's own code not)",
}


def run_cause(
    status: str, skill_causes: list[str], plant_disagrees: bool, disturbed: bool = False
) -> str | None:
    """The cause of a run: None on SUCCESS; ``timeout``; ``placement_off`` when the
    controller succeeded but the plant disagrees about the goals; ``disturbed`` when it
    succeeded, the goals hold, but the plant shows an object left disturbed; else the last
    skill failure's cause (the one the controller could not recover from), or
    ``task_failed``."""
    if status == "SUCCESS":
        return None
    if status == "TIMEOUT":
        return "timeout"
    if plant_disagrees:
        return "placement_off"
    if disturbed:
        return "disturbed"
    return skill_causes[-1] if skill_causes else "task_failed"
