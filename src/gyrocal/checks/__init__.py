"""Every check of gyrocal as one kind of `Finding`: the input's format and physics, the outlier
screen and the reference mounting (the refusals before a posterior is sampled are the sampler's:
`gyrocal.inference.sampling.refusals`)."""

from gyrocal.checks.campaign import check, read_checked, summary
from gyrocal.checks.mounting import align, aligned, estimate_mounting
from gyrocal.finding import Finding, Findings, Status

__all__ = ["Finding", "Findings", "Status", "align", "aligned", "check", "estimate_mounting", "read_checked", "summary"]
