"""The linear error model against the exact one, where the posterior lives."""

import dataclasses

import numpy as np
import pytest
from scipy.stats import chi2

from gyrocal import cli, linearity
from gyrocal.preprocess import ManeuverData


def test_probe_steps_sit_on_the_99_percent_ellipsoid_in_pairs():
    rng = np.random.default_rng(2)
    a = rng.normal(size=(5, 5))
    cov = a @ a.T + 5 * np.eye(5)
    steps = linearity.probe_steps(cov)
    distances = np.einsum("pi,pi->p", steps, np.linalg.solve(cov, steps.T).T)
    assert distances == pytest.approx(np.full(4, chi2.ppf(0.99, 5)), rel=1e-10)
    assert np.allclose(steps[0], -steps[1]) and np.allclose(steps[2], -steps[3])


def test_on_the_tiny_campaign_the_linear_model_holds_and_its_error_is_the_curvature(tiny_run):
    """Constant-rate turns: the averaged columns are the exact derivative, and what the linear model
    misses is the exact model's curvature, which grows with the square of the step (doubling
    the covariance's square root quadruples it)."""
    from gyrocal.estimate import PointEstimate
    from gyrocal.steps.common import known_effects
    out, npz = tiny_run
    maneuvers = [ManeuverData.load(p) for p in npz]
    est = PointEstimate.load(out / "baseline" / "point_estimate.npz", known_effects([]))
    table = linearity.check(maneuvers, est)
    assert (table["mismatch_rms_arcsec"] < 0.01 * table["change_rms_arcsec"]).all()
    assert (table["quadratic_part_rms_arcsec"] > 0).all()
    wider = linearity.check(maneuvers, dataclasses.replace(est, cov=4.0 * est.cov))
    assert wider["change_rms_arcsec"].to_numpy() == pytest.approx(2 * table["change_rms_arcsec"].to_numpy(), rel=1e-9)
    ratio = wider["quadratic_part_rms_arcsec"] / table["quadratic_part_rms_arcsec"]
    assert ratio.to_numpy() == pytest.approx(np.full(4, 4.0), rel=0.1)


def test_the_command_names_a_missing_model(tmp_path, capsys):
    assert cli.main(["linearity", str(tmp_path), "--model", "nosuch"]) == 2
    assert "no point estimate of model 'nosuch'" in capsys.readouterr().err
