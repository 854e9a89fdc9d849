"""Fault campaigns: seeded random fault plans simulated and checked.

The campaign is a client of the simulator (:func:`workcell.simulate`) and of
the sweep runner (:mod:`workcell.experiments`), so it lives beside both
rather than inside :mod:`workcell.sim`: the simulator never imports the
experiments.

* :mod:`.episodes` -- one episode: drawn from (cell, seed, index), simulated
  and checked; the findings.
* :mod:`.runner` -- many episodes in batches through the sweep runner (local
  processes or Dask), the episodes table, the summary, the replay.

``multiarm campaign CELL`` is the command line (docs/simulation.md).
"""

from workcell.campaign.episodes import (
    COORDINATIONS,
    FAULT_KINDS,
    FINDING_KINDS,
    HAIRS,
    REPLAY_SHARE,
    CampaignCell,
    Episode,
    EpisodeResult,
    Finding,
    check_result,
    check_tasks,
    draw_episode,
    prepare,
    replans,
    required_tasks,
    run_episode,
    simulate_episode,
)
from workcell.campaign.runner import (
    COLUMNS,
    CampaignOutcome,
    campaign_batch,
    campaign_instances,
    describe,
    parse_replay,
    replay,
    run_campaign,
)

__all__ = [
    "COLUMNS",
    "COORDINATIONS",
    "FAULT_KINDS",
    "FINDING_KINDS",
    "HAIRS",
    "REPLAY_SHARE",
    "CampaignCell",
    "CampaignOutcome",
    "Episode",
    "EpisodeResult",
    "Finding",
    "campaign_batch",
    "campaign_instances",
    "check_result",
    "check_tasks",
    "describe",
    "draw_episode",
    "parse_replay",
    "prepare",
    "replans",
    "replay",
    "required_tasks",
    "run_campaign",
    "run_episode",
    "simulate_episode",
]
