"""The reviewed model's noise, as the review shows it: each sampled noise scale beside what the campaign
states, and in words what its correlated part's time means on the clock it runs on (seconds at rest,
or an angle turned where campaign.yaml states ``star_tracker: gm_clock_s_per_rad``)."""

import numpy as np
import pandas as pd

from gyrocal.inference.noise.covariance import GM_FRACTION_SCALE, GM_TAU_SCALE
from gyrocal.io.campaign_yaml import GM_CLOCK_AUTO, GM_CLOCK_KEY

__all__ = ["clock_sentence", "noise_table"]

TAU_KEY, SHARE_KEY = GM_TAU_SCALE.key, GM_FRACTION_SCALE.key


def noise_table(diagnostics: dict) -> pd.DataFrame:
    """One row per noise scale the model sampled (and, where the stated noise is the white part, the parts):
    the stated value beside what it judges (empty where nothing states it, the prior's median then being
    the library's), the posterior mean and 95 % interval, and mean over stated."""
    judged = diagnostics.get("noise_judged", {})  # the stated white part sits beside the part it judges
    stated = {judged.get(k, k): v for k, v in diagnostics.get("noise_stated", {}).items()}
    ci95 = diagnostics.get("noise_posterior_ci95", {})
    rows = []
    for key, mean in diagnostics.get("noise_posterior", {}).items():
        low, high = ci95.get(key, (np.nan, np.nan))
        given = stated.get(key, np.nan)
        rows.append({"scale": key, "stated": given, "mean": mean, "ci95_low": low, "ci95_high": high,
                     "mean / stated": mean / given if np.isfinite(given) else np.nan})
    return pd.DataFrame(rows, columns=["scale", "stated", "mean", "ci95_low", "ci95_high", "mean / stated"])


def clock_sentence(diagnostics: dict, clock_s_per_rad: float, chosen: dict | None = None) -> str:
    """What the correlated part's time means: on the time clock, seconds; on the angle clock of
    ``clock_s_per_rad`` s/rad, the seconds it forgets over at rest or the angle it forgets over when
    the body turns fast (tau / K rad). Where the preprocessing chose the clock (``chosen``, its
    ``gm_clock.json``), why. Empty where the model's reference noise is white and no clock was chosen."""
    why = (f" The clock was chosen from the data ({GM_CLOCK_KEY}: {GM_CLOCK_AUTO}): {chosen['reason']}."
           if chosen else "")
    return (_time_sentence(diagnostics, clock_s_per_rad) + why).strip()


def _time_sentence(diagnostics: dict, clock_s_per_rad: float) -> str:
    posterior = diagnostics.get("noise_posterior", {})
    if TAU_KEY not in posterior:
        return ""
    tau = posterior[TAU_KEY]
    low, high = diagnostics.get("noise_posterior_ci95", {}).get(TAU_KEY, (np.nan, np.nan))
    share = f"holds {posterior[SHARE_KEY]:.1%} of the reference's variance and " if SHARE_KEY in posterior else ""
    if clock_s_per_rad <= 0:
        return (f"The reference error's correlated part {share}forgets over {tau:.3g} s "
                f"(95 % interval {low:.3g} to {high:.3g} s).")
    angle, angle_low, angle_high = (np.rad2deg(v / clock_s_per_rad) for v in (tau, low, high))
    return (f"The reference error's correlated part {share}runs on the angle clock of {clock_s_per_rad:g} s/rad "
            f"(campaign.yaml's star_tracker: {GM_CLOCK_KEY}): each step counts its seconds plus "
            f"{clock_s_per_rad:g} s for each radian the body turns. Its time, {tau:.3g} clock seconds "
            f"(95 % interval {low:.3g} to {high:.3g}), is {tau:.3g} s at rest, or {angle:.3g} deg turned "
            f"({angle_low:.3g} to {angle_high:.3g} deg) where the turning dominates: an error that follows "
            f"the attitude more than the time.")
