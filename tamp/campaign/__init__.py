"""Campaigns: many seeded runs of one scenario of any workcell, in parallel on Ray (a local
Ray, or a cluster with the same code) or one after the other in this process, summarised as
a success rate with its Wilson interval, a task-time distribution, failure causes with their
seeds, and plots.

Layout: `kinds` (what can run: the registered workcells, `tamp.sim.core.workcell`), `run` (one run:
`Job` -> `RunRecord`, done where it runs), `engines` (Ray / in-process, with the per-run
time limit), `campaign` (`run_campaign`: files, summary), `stats` (Wilson interval,
distributions, causes), `plots`. Ray is an optional dependency (``pip install
'tamp-hrc[campaign]'``): importing this package imports neither Ray nor Drake.
"""

from tamp.campaign.campaign import CampaignResult, CampaignSpec, run_campaign
from tamp.campaign.engines import LocalEngine, RayEngine, make_engine
from tamp.campaign.kinds import Workcell, get_kind, kinds, register, resolve_scenario
from tamp.campaign.run import Job, RunRecord, execute
from tamp.campaign.stats import wilson_interval

__all__ = [
    "CampaignResult",
    "CampaignSpec",
    "Job",
    "LocalEngine",
    "RayEngine",
    "RunRecord",
    "Workcell",
    "execute",
    "get_kind",
    "kinds",
    "make_engine",
    "register",
    "resolve_scenario",
    "run_campaign",
    "wilson_interval",
]
