"""The posterior-predictive bands checked per noise group.

A campaign whose maneuvers were flown at different noise levels (`noise_group` in
campaign.yaml) gets one level per group; whether each group's 95 % bands hold about 95 % of its
points is the check that the levels fit, group by group: one loud trial cannot hide a quiet
one's misfit, nor the reverse.
"""

import pandas as pd

from gyrocal.finding import Finding
from gyrocal.model.units import AXES

__all__ = ["band_findings", "outside_by_group"]


def outside_by_group(fit: pd.DataFrame, groups: dict) -> pd.Series:
    """The share of each group's points (sample, set and axis) outside their 95 % bands; ``groups``
    maps each maneuver to its noise group, ``fit`` is the posterior step's per-sample table."""
    outside = fit[[f"outside_{a}" for a in AXES]].to_numpy(dtype=float).mean(axis=1)
    return pd.Series(outside, index=fit.index).groupby(fit["maneuver"].map(groups), sort=False).mean()


def band_findings(fit: pd.DataFrame, groups: dict, limit: float) -> list:
    """One `Finding` per noise group where there is more than one: its share outside at most ``limit``."""
    if len(set(groups.values())) < 2:
        return []
    return [Finding.judged(
        f"bands:{group}", bool(share <= limit),
        f"noise group {group}: {100 * share:.1f} % of its points lie outside their 95 % bands "
        f"(limit {100 * limit:.0f} %)",
        figure=float(share), threshold=float(limit), unit="share outside", where=f"noise group {group}")
        for group, share in outside_by_group(fit, groups).items()]
