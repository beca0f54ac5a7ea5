"""Slow statistical studies, outside the default run: ``bash tests/run.sh -m slow``."""

import json

import numpy as np
import pandas as pd
import pytest

from gyrocal.simulation import simulate

from conftest import DATA, config_with, run_campaign

SEEDS = range(101, 113)


@pytest.mark.slow
def test_posterior_intervals_are_calibrated_over_many_seeds(tmp_path, config):
    """Across 12 simulated campaigns the 95 % intervals cover the truth about 95 % of the
    time, and the standardised errors (mean - truth) / sd look standard normal."""
    cfg = config_with(config, {"baseline": ["scale_factor", "misalignment", "bias"]})
    covered, z = [], []
    for seed in SEEDS:
        sim = tmp_path / f"sim{seed}"
        simulate.run(DATA / "tiny.yaml", sim, seed=seed)
        run_campaign(sim / "campaign", tmp_path / f"out{seed}", cfg)
        table = pd.read_csv(tmp_path / f"out{seed}" / "baseline" / "calibration.csv")
        truth = json.loads((sim / "truth.json").read_text())["parameters"]
        values = np.array([truth[r.channel][r.parameter] for r in table.itertuples()])
        covered += list((table["ci95_low"] <= values) & (values <= table["ci95_high"]))
        z += list((table["mean"] - values) / table["sd"])
    rate = np.mean(covered)
    n = len(covered)
    assert abs(rate - 0.95) < 3 * np.sqrt(0.95 * 0.05 / n) + 0.01, rate
    assert abs(np.mean(z)) < 0.25 and 0.85 < np.std(z) < 1.15, (np.mean(z), np.std(z))
