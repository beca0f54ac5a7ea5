"""Noise levels per maneuver group: the REML's levels, and a campaign flown at two levels."""

import json

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import minimize

from gyrocal.inference.fit.likelihood import Stats
from gyrocal.inference.fit.noisefit import profile_group_levels
from gyrocal.simulation import simulate

from conftest import DATA, config_with, run_campaign


def _group_stats(levels, n=(400, 250), p=3, seed=0):
    """Two groups sharing parameters, their noise sd ``levels``: unit-scale statistics."""
    rng = np.random.default_rng(seed)
    theta = rng.normal(size=p)
    parts = []
    for sd, count in zip(levels, n):
        x = rng.normal(size=(count, p))
        y = x @ theta + sd * rng.normal(size=count)
        parts.append(Stats(x.T @ x, x.T @ y, float(y @ y), 0.0, count))
    return parts


def test_group_levels_are_the_optimum_of_the_restricted_likelihood():
    """The fixed point is where the restricted likelihood is largest, and near the truth."""
    parts = _group_stats((1.0, 3.0))
    negative, log_sd = profile_group_levels(parts)
    A = [s.A for s in parts]

    def restricted(log_sd):
        w = np.exp(-2 * log_sd)
        P = sum(wk * a for wk, a in zip(w, A))
        theta = np.linalg.solve(P, sum(wk * s.b for wk, s in zip(w, parts)))
        rss = np.array([s.c - 2 * s.b @ theta + theta @ s.A @ theta for s in parts])
        n = np.array([s.n for s in parts])
        return 0.5 * (np.sum(2 * n * log_sd + rss * w) + np.linalg.slogdet(P)[1])

    best = minimize(restricted, np.zeros(2), method="Nelder-Mead", options={"xatol": 1e-9, "fatol": 1e-12})
    # the fixed point divides by the REML degrees of freedom: within (p / n) of the ML optimum
    np.testing.assert_allclose(log_sd, best.x, atol=0.01)
    np.testing.assert_allclose(np.exp(log_sd), [1.0, 3.0], rtol=0.1)
    assert negative == pytest.approx(restricted(log_sd), abs=0.05)


@pytest.mark.full
def test_a_campaign_at_two_noise_levels_gets_a_level_per_group(tmp_path, short_chains):
    """Roll maneuvers three times as noisy as the others: the groups' levels are three apart,
    and each group's bands are checked."""
    simulate.run(DATA / "noise_groups.yaml", tmp_path / "sim")
    cfg = config_with(short_chains, {"baseline": ["scale_factor", "misalignment", "bias"]})
    run_campaign(tmp_path / "sim" / "campaign", tmp_path / "out", cfg, ("baseline",), tmp_path / "sim" / "truth.json")
    summary = pd.read_csv(tmp_path / "out" / "baseline" / "posterior_summary.csv").set_index("label")
    ratio = summary.loc["noise.level.loud", "mean"] / summary.loc["noise.level.quiet", "mean"]
    assert ratio == pytest.approx(3.0, rel=0.1)
    checks = {c["check"] for c in json.loads((tmp_path / "out" / "baseline" / "diagnostics.json").read_text())["checks"]}
    assert {"bands:quiet", "bands:loud"} <= checks
