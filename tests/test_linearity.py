"""The linear error model against the exact one, where the posterior lives."""

import dataclasses

import numpy as np
import pytest
from scipy.stats import chi2

from gyrocal.criticism import linearity
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.pipeline import cli


def test_probe_steps_sit_on_the_99_percent_ellipsoid_in_pairs():
    rng = np.random.default_rng(2)
    a = rng.normal(size=(5, 5))
    cov = a @ a.T + 5 * np.eye(5)
    steps = linearity.probe_steps(cov)
    distances = np.einsum("pi,pi->p", steps, np.linalg.solve(cov, steps.T).T)
    assert distances == pytest.approx(np.full(4, chi2.ppf(0.99, 5)), rel=1e-10)
    assert np.allclose(steps[0], -steps[1]) and np.allclose(steps[2], -steps[3])


def test_split_recovers_the_linear_and_quadratic_parts():
    a, b = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.0, -4.0])
    d = 0.7
    linear, quadratic = linearity.split(a * d + b * d**2, a * d / 10 + b * (d / 10) ** 2)
    assert linear == pytest.approx(a * d, abs=1e-12) and quadratic == pytest.approx(b * d**2, abs=1e-12)


@pytest.fixture(scope="module")
def tiny_estimate(tiny_run):
    from gyrocal.inference.fit.estimate import PointEstimate
    from gyrocal.model import effects
    out, npz = tiny_run
    return [ManeuverData.load(p) for p in npz], PointEstimate.load(out / "baseline" / "point_estimate.npz",
                                                                    effects.known([]))


def test_on_the_tiny_campaign_the_linear_model_moves_no_parameter(tiny_estimate):
    maneuvers, est = tiny_estimate
    table = linearity.check(maneuvers, est)
    assert (table["mismatch_rms_arcsec"] < 0.01 * table["change_rms_arcsec"]).all()
    assert table[["curvature_shift_sd", "columns_shift_sd"]].to_numpy().max() < 0.02


def test_the_curvature_grows_with_the_square_of_the_step(tiny_estimate):
    """Far out (the covariance 100 and 400 times wider, so that the curvature stands clear of the
    rounding in ``m(d / 10)``), doubling the step doubles the change and about quadruples the
    curvature (a cubic term is left in it)."""
    maneuvers, est = tiny_estimate
    table = linearity.check(maneuvers, dataclasses.replace(est, cov=100.0 * est.cov))
    wider = linearity.check(maneuvers, dataclasses.replace(est, cov=400.0 * est.cov))
    assert wider["change_rms_arcsec"].to_numpy() == pytest.approx(2 * table["change_rms_arcsec"].to_numpy(), rel=1e-6)
    ratio = wider["curvature_rms_arcsec"] / table["curvature_rms_arcsec"]
    assert ratio.to_numpy() == pytest.approx(np.full(4, 4.0), rel=0.25)


def test_the_command_names_a_missing_model(tmp_path, capsys):
    assert cli.main(["linearity", str(tmp_path), "--model", "nosuch"]) == 2
    assert "no point estimate of model 'nosuch'" in capsys.readouterr().err
