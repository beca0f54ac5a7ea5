"""The simulator's star-tracker Gauss-Markov part and its noise levels per maneuver (issue 30)."""

import numpy as np
import pytest
import yaml

from gyrocal.io import telemetry
from gyrocal.maneuvers import preprocess
from gyrocal.model.units import arcsec_to_rad
from gyrocal.simulation import simulate

from conftest import DATA, truth_vector


def test_gauss_markov_is_stationary_from_its_first_sample_with_lag_correlation_exp_minus_k_dt_over_tau():
    """Columns are independent realisations: every row's variance is 1 and rows k apart correlate
    as exp(-k dt / tau), the first row included (a stationary start)."""
    dt, tau, n_real = 1.0, 30.0, 20000
    x = simulate.gauss_markov(np.random.default_rng(1).normal(size=(61, n_real)), dt, tau)
    sd_var = np.sqrt(2 / n_real)
    for row in (0, 1, 30, 60):
        assert abs(x[row].var() - 1) < 4 * sd_var, row
    for k in (1, 10, 30, 60):
        expected = np.exp(-k * dt / tau)
        r = np.mean(x[0] * x[k])
        assert abs(r - expected) < 4 * np.sqrt((1 + expected**2) / n_real), (k, r, expected)


def test_star_tracker_gauss_markov_part_has_its_sigmas_across_and_about_the_boresight_and_its_tau():
    """One long series (white part off) projected on the boresight's frame: the variance of each
    axis is its sigma squared and its lag-k autocorrelation exp(-k dt / tau), within 4 sampling sds."""
    boresight = np.array([0.3, 0.0, 0.954]) / np.linalg.norm([0.3, 0.0, 0.954])
    cfg = {"boresight_body": boresight.tolist(), "sigma_cross_arcsec": 0.0, "sigma_about_arcsec": 0.0,
           "gm_sigma_cross_arcsec": 6.0, "gm_sigma_about_arcsec": 25.0, "gm_tau_s": 20.0}
    n, dt = 400_000, 0.5
    noise = simulate.star_tracker_noise(n, dt, cfg, 0.0, np.random.default_rng(2))
    about = noise @ boresight
    across = noise - about[:, None] * boresight
    assert np.allclose(across @ boresight, 0)
    phi = np.exp(-dt / cfg["gm_tau_s"])
    inflation = (1 + phi**2) / (1 - phi**2)  # the AR(1)'s variance factor for sample moments
    for series, sigma, dof in ((about, 25.0, 1), (across, 6.0, 2)):
        series = series.reshape(n, -1) / arcsec_to_rad(sigma)
        variance = np.mean(series**2) * series.shape[1] / dof
        assert abs(variance - 1) < 4 * np.sqrt(2 * inflation / (n * dof)), variance
        for k in (1, 40, 120):
            r = np.sum(series[:-k] * series[k:]) / np.sum(series**2)
            expected = phi**k
            assert abs(r - expected) < 4 * np.sqrt(inflation / (n * dof)), (k, r, expected)


def scenario_file(tmp_path, **star_tracker):
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario["star_tracker"].update(invalid_fraction=0.0, **star_tracker)
    scenario["maneuvers"][2].update(noise_scale=3.0, noise_group="loud")
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario, sort_keys=False))
    return path


def test_noise_scale_multiplies_a_maneuvers_scatter_and_its_group_reaches_the_campaign(tmp_path):
    simulate.run(scenario_file(tmp_path), tmp_path / "out")
    campaign = telemetry.read_campaign(tmp_path / "out" / "campaign")
    truth = yaml.safe_load((tmp_path / "out" / "truth.json").read_text())
    assert [m.noise_group for m in campaign.maneuvers] == ["all", "all", "loud", "all", "all", "all"]
    assert truth["maneuver_noise"]["roll_pos"] == {"noise_scale": 3.0, "noise_group": "loud"}
    params = truth_vector(campaign.channels, truth)
    scatter = {}
    for m in campaign.maneuvers:
        data = preprocess.slice_maneuver(campaign, m.id)
        assert data.noise_group == m.noise_group
        err = preprocess.error_angles(data, data.sets[0], params)
        scatter[m.id] = np.std(np.diff(err, axis=0), axis=0)  # the white part dominates sample to sample
    quiet = np.mean([scatter[k] for k in scatter if k != "roll_pos"], axis=0)
    ratio = scatter["roll_pos"] / quiet
    assert np.all(np.abs(ratio - 3.0) < 0.45), ratio


def test_the_gauss_markov_part_is_reproducible_and_declared_in_the_truth(tmp_path):
    path = scenario_file(tmp_path, gm_sigma_cross_arcsec=4.0, gm_sigma_about_arcsec=15.0, gm_tau_s=30.0)
    a, truth = simulate.simulate(simulate.load_scenario(path))
    b, _ = simulate.simulate(simulate.load_scenario(path))
    white, _ = simulate.simulate(simulate.load_scenario(scenario_file(tmp_path)))
    assert np.array_equal(a.st_quat, b.st_quat)
    assert np.array_equal(a.gyro_columns["dtg1_roll"], white.gyro_columns["dtg1_roll"])  # the gyros' draws unmoved
    assert not np.array_equal(a.st_quat, white.st_quat)
    assert truth["noise"]["gm_tau_s"] == 30.0 and truth["noise"]["gm_sigma_about_arcsec"] == 15.0
    # campaign.yaml states the total, as a data sheet does: white 5 / 20 and GM 4 / 15 arcsec
    assert a.star_tracker["sigma_cross_arcsec"] == pytest.approx(np.hypot(5.0, 4.0))
    assert a.star_tracker["sigma_about_arcsec"] == pytest.approx(np.hypot(20.0, 15.0))
    assert white.star_tracker["sigma_about_arcsec"] == pytest.approx(20.0)


def test_walk_steps_match_the_walk_a_gyro_interpolated_between_its_samples_has():
    """Monte Carlo: per-interval noise integrated and interpolated to star-tracker times that fall
    at the grid and mid-interval (2.5 Hz gyros, 1 Hz star tracker): the steps' variances and the
    consecutive steps' covariance are `walk_steps`', within 5 sampling sds."""
    from gyrocal.inference import errormodel

    gyro_time = 0.4 * np.arange(101)
    st_time = np.arange(1.0, 40.0)
    n_real = 40000
    noise = np.random.default_rng(3).normal(size=(n_real, 100)) * np.sqrt(0.4)  # unit ARW: variance dt
    k = np.searchsorted(gyro_time, st_time, side="left") - 1
    frac = (st_time - gyro_time[k]) / 0.4
    before = np.concatenate([np.zeros((n_real, 1)), np.cumsum(noise, axis=1)], axis=1)
    walk = before[:, k] + frac * noise[:, k]
    steps = np.diff(np.concatenate([np.zeros((n_real, 1)), walk], axis=1), axis=1)
    variance, shared = errormodel.walk_steps(gyro_time, st_time)
    assert np.allclose(steps.var(axis=0), variance, atol=5 * np.sqrt(2 / n_real) * variance.max())
    assert np.allclose(np.mean(steps[:, 1:] * steps[:, :-1], axis=0), shared, atol=5 * variance.max() / np.sqrt(n_real))
    assert np.isclose(variance[1], 1.0 - 0.4 * 0.25) and np.isclose(shared[0], 0.4 * 0.25)  # f = 1/2 at t = 1 s
    on_grid, none_shared = errormodel.walk_steps(gyro_time, 0.4 * np.arange(1, 50))
    assert np.allclose(on_grid, 0.4) and np.allclose(none_shared, 0.0)
