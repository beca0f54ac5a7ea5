"""The Monte Carlo validation study: simulated campaigns through the pipeline, and the tables and
figures of coverage, efficiency against the Cramér-Rao bound and SBC; what the scripts in ``studies/``
share. Its entry points, below, are imported when first asked for (`gyrocal.exports`)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"run_chunk": "steps", "summarize": "steps", "campaign_scenario": "campaign",
                 "baseline_ranking": "baseline"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
