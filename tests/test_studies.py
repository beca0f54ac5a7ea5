"""Slow statistical studies, outside the default run: ``bash tests/run.sh -m slow``."""

import json
from pathlib import Path

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


def test_compare_trials_on_point_estimates_draws_the_wls_mean_and_sd(tiny_run):
    """``studies/compare_trials.py --point``: a run's point estimate as a normal, its sf_pos mean and sd
    those of the WLS ``theta`` and ``cov`` (20 000 draws: within 2 % of the sd), and a run against
    itself at z 0."""
    import importlib.util

    from gyrocal.inference.fit.estimate import PointEstimate

    path = Path(__file__).parent.parent / "studies" / "compare_trials.py"
    spec = importlib.util.spec_from_file_location("compare_trials", path)
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    run = tiny_run[0] / "baseline"
    table = study.summaries(run, point=True)
    est = PointEstimate.load(run / "point_estimate.npz", linearizations=False)
    i = est.spec.labels.index("dtg1_roll.sf_pos")
    row = table.loc[("dtg1_roll", "sf_pos")]
    sd = np.sqrt(est.cov[i, i]) / est.spec.si_per_unit[i]
    assert row["sd"] == pytest.approx(sd, rel=0.02)
    assert row["mean"] == pytest.approx(est.theta[i] / est.spec.si_per_unit[i], abs=0.05 * sd)
    assert (study.compare(table, table)["z"] == 0).all()
    assert any(term.startswith("nonorth") for _, term in table.index)
