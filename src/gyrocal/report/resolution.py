"""What the review says the data resolve: per channel its scale factors' mean and asymmetry and its
misalignments against their priors, one sentence per channel with the maneuver that would resolve
what is not, the directions of the channel parameters left to the prior, and, for a reference whose
mounting was estimated, which misalignment combinations the mounting takes up
(`gyrocal.model.combinations`)."""

import numpy as np
import pandas as pd

from gyrocal.model import combinations as comb

__all__ = ["LOADINGS_SHOWN", "channel_sentences", "mounting_table", "prior_directions", "resolution_table"]

LOADINGS_SHOWN = 4
"""How many parameters (largest loadings first) describe a direction left to the prior."""


def resolution_table(spec, calibration: pd.DataFrame, width_limits: dict | None = None) -> pd.DataFrame:
    """Per channel, its channel-model terms and then its combinations (``sf_mean``, ``sf_asym``):
    posterior mean, sd and 95 % interval (``calibration.csv``), prior sd (the spec's declared priors, with
    the config's and ``prior_from``'s overrides), their ratio and whether it is resolved
    (`comb.RESOLVED_RATIO_MAX`); with ``width_limits`` (unit: widest acceptable 95 % interval, the
    verdict's), the interval's width against it: a term may be resolved against a loose prior and
    still be too wide to act on."""
    cal = calibration.set_index(["channel", "parameter"])
    combos = {c.label: c for c in comb.scale_combinations(spec)}
    combo_prior = dict(zip(combos, comb.prior_sd(list(combos.values()), spec))) if combos else {}
    rows = []
    for channel in spec.channels:
        own = [p for p in spec.parameters[spec.core] if p.owner == channel.name]
        items = [(p.name, p.prior_sd) for p in own]
        items += [(c.name, combo_prior[c.label]) for c in combos.values() if c.owner == channel.name]
        for name, prior in items:
            if (channel.name, name) not in cal.index:
                continue
            r = cal.loc[(channel.name, name)]
            rows.append({"channel": channel.name, "parameter": name, "unit": r["unit"], "mean": r["mean"],
                         "sd": r["sd"], "ci95_low": r["ci95_low"], "ci95_high": r["ci95_high"], "prior_sd": prior,
                         "sd_over_prior": r["sd"] / prior,
                         "resolved": bool(r["sd"] / prior <= comb.RESOLVED_RATIO_MAX),
                         "ci95_width": r["ci95_high"] - r["ci95_low"],
                         "width_limit": (width_limits or {}).get(r["unit"], np.nan)})
    frame = pd.DataFrame(rows)
    return frame.assign(narrow_enough=~(frame["ci95_width"] > frame["width_limit"]))


def channel_sentences(spec, table: pd.DataFrame, maneuvers) -> list:
    """`comb.channel_sentence` per channel, over its combinations and misalignments (the scale
    factors of each direction are said through their mean and asymmetry)."""
    flown = comb.flown_directions(maneuvers)
    order = {name: i for i, name in enumerate(comb.COMBINATION_NAMES)}
    said = table[table["parameter"].isin(comb.COMBINATION_NAMES) | table["parameter"].str.startswith("mis_")]
    said = said.assign(order=said["parameter"].map(order).fillna(len(order))).sort_values(["order"], kind="stable")
    return [comb.channel_sentence(c, [{"parameter": r.parameter, "sd": r.sd, "ratio": r.sd_over_prior, "unit": r.unit,
                                       "width": r.ci95_width, "limit": None if np.isnan(r.width_limit) else r.width_limit}
                                      for r in said[said["channel"] == c.name].itertuples()], flown)
            for c in spec.channels]


def prior_directions(spec, cov_unit: np.ndarray) -> pd.DataFrame:
    """The eigen-directions of the channel parameters' posterior relative to their prior
    (`comb.directions`) that are not resolved, least resolved first: each with its sd over the
    prior's and the parameters it loads on most (weights on the parameters over their prior sd)."""
    core = np.arange(spec.n_core)
    prior = np.array([p.prior_sd for p in spec.parameters])[core]
    free = spec.free[core]
    ratio, vectors = comb.directions(cov_unit[np.ix_(core, core)], prior, free)
    rows = []
    for k in np.argsort(-ratio):
        if ratio[k] <= comb.RESOLVED_RATIO_MAX:
            break
        v = vectors[:, k]
        top = sorted(range(len(v)), key=lambda i: (-round(abs(v[i]), 2), i))[:LOADINGS_SHOWN]
        v = v * np.sign(v[top[0]])
        rows.append({"sd_over_prior": round(float(ratio[k]), 3),
                     "direction": " ".join(f"{v[i]:+.2f} {spec.labels[i]}" for i in top if abs(v[i]) >= 0.05)})
    return pd.DataFrame(rows, columns=["sd_over_prior", "direction"])


def mounting_table(spec, cov_unit: np.ndarray, mounting: dict) -> pd.DataFrame:
    """For a mounting estimated from the data: per axis and pair of opposite misalignments, the
    rotation and non-orthogonality with their sd over the prior's as fitted and with the mounting
    free (`comb.mounting_separability`), and whether each is separable from the mounting. Empty for
    a declared mounting or none (the reference frame is then given, not taken from the data)."""
    columns = ["axis", "kind", "combination", "ratio_fitted", "ratio_mounting_free", "separable"]
    if not mounting or "sd_deg" not in mounting:
        return pd.DataFrame(columns=columns)
    rows = comb.mounting_separability(cov_unit, spec)
    frame = pd.DataFrame(rows, columns=columns[:-1]).round({"ratio_fitted": 3, "ratio_mounting_free": 3})
    return frame.assign(separable=frame["ratio_mounting_free"] <= comb.RESOLVED_RATIO_MAX)
