"""The reference error's Gauss-Markov part on a clock that runs on the angle turned as well as on time
(campaign.yaml's ``star_tracker: gm_clock_s_per_rad``): the clock's steps, the linearisation that carries
them, the likelihood that prefers the true clock, and tau's prior on it."""

import copy
import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gyrocal.inference import errormodel
from gyrocal.inference.fit import noisefit
from gyrocal.inference.noise import covariance
from gyrocal.io.scenario import load_scenario
from gyrocal.maneuvers import preprocess
from gyrocal.model import kinematics
from gyrocal.model.spec import baseline
from gyrocal.model.units import deg_h_to_rad_s
from gyrocal.simulation.simulate import simulate

from conftest import DATA


def test_the_clock_adds_kappa_seconds_for_each_radian_turned_between_samples():
    """Turning at 0.2 rad/s about x, the reference at 0.55 s, 1.55 s, ...: each turn is 0.2 rad a second
    (the first from t0, 0.11 rad), and each 1-s step of the clock 1 + 0.2 kappa seconds."""
    rate, kappa = 0.2, 50.0
    st_time = np.arange(0.55, 9.6, 1.0)
    at_st = Rotation.from_rotvec(np.outer(rate * st_time, [1.0, 0.0, 0.0]))
    turns = kinematics.net_turns(Rotation.identity(), at_st)
    st_dt = np.diff(st_time, prepend=0.0)
    np.testing.assert_allclose(turns, rate * st_dt, rtol=1e-12)
    np.testing.assert_allclose(errormodel.gm_clock_steps(st_dt, turns, kappa), st_dt * (1.0 + rate * kappa), rtol=1e-12)


def test_at_rest_the_clock_counts_the_gyros_noise_over_a_step_not_sample_by_sample():
    """A MEMS gyro at rest (0.49 deg/sqrt(h), 286 Hz) seen every 0.1 s: the net turn over each step is
    its noise over 29 samples, about sqrt(29) times less than the path of the samples (which made the
    clock run 38 s a second at rest at 10 000 s/rad)."""
    rng = np.random.default_rng(1)
    dt, per_step, n_steps = 1 / 286.0, 29, 400
    sigma = np.deg2rad(0.49) / 60.0 * np.sqrt(dt)
    increments = rng.normal(scale=sigma, size=(per_step * n_steps, 3))
    attitudes = Rotation.from_rotvec(np.cumsum(increments, axis=0))  # small: the sum is the rotation
    at_st = attitudes[per_step - 1::per_step]
    turns = kinematics.net_turns(Rotation.identity(), at_st)
    path = np.linalg.norm(increments, axis=1).reshape(n_steps, per_step).sum(axis=1)
    assert np.mean(turns) == pytest.approx(np.sqrt(8 / np.pi) * sigma * np.sqrt(per_step), rel=0.1)
    assert np.mean(path) / np.mean(turns) > 4.0


def _tiny(gm: dict, n_maneuvers: int = 3, seed: int = 3):
    scenario = copy.deepcopy(load_scenario(DATA / "tiny.yaml"))
    scenario["star_tracker"].update(gm)
    campaign, truth = simulate(scenario, seed)
    spec = baseline(campaign.channels)
    theta = spec.core_vector(spec.params_from_contract(scenario["truth"]))
    biases = deg_h_to_rad_s(np.array([truth["parameters"][c.name]["bias_deg_h"] for c in spec.channels]))
    data = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers[:n_maneuvers]]
    return data, spec, theta, biases, np.asarray(scenario["star_tracker"]["boresight_body"], dtype=float)


def _linearized(data, spec, theta, biases, kappa):
    return [errormodel.linearize(dataclasses.replace(d, gm_clock_s_per_rad=kappa), spec, theta, biases) for d in data]


def test_a_maneuver_with_the_clock_carries_its_steps_and_without_it_is_the_same_bits():
    """Each tiny maneuver turns 90 deg: its clock runs kappa pi/2 s beyond time (to 1 %: the gyros'
    noise); at kappa 0 the linearisation has no clock of its own and the same residuals to the bit."""
    data, spec, theta, biases, _ = _tiny({})
    assert all(d.gm_clock_s_per_rad == 0.0 for d in data)  # a campaign that states no clock
    plain = _linearized(data, spec, theta, biases, 0.0)
    clocked = _linearized(data, spec, theta, biases, 100.0)
    for a, b in zip(plain, clocked):
        assert a.gm_dt is None and a.gm_steps is a.st_dt
        np.testing.assert_array_equal(a.z, b.z)
        np.testing.assert_array_equal(a.st_dt, b.st_dt)
        np.testing.assert_array_equal(a.walk_var, b.walk_var)  # the gyro's walk stays on time
        assert np.sum(b.gm_dt - b.st_dt) / 100.0 == pytest.approx(np.pi / 2, rel=0.01)


def test_a_maneuver_takes_its_clock_from_the_campaign_and_keeps_it_through_its_file(tmp_path):
    """The preprocessing cuts a maneuver with campaign.yaml's clock; its file keeps it, and a file
    without one (a campaign that states none: the same bytes as before the key) loads at 0."""
    scenario = copy.deepcopy(load_scenario(DATA / "tiny.yaml"))
    campaign, _ = simulate(scenario, 3)
    campaign.star_tracker["gm_clock_s_per_rad"] = 250.0
    data = preprocess.slice_maneuver(campaign, campaign.maneuvers[0].id)
    assert data.gm_clock_s_per_rad == 250.0
    data.save(tmp_path / "m.npz")
    assert preprocess.ManeuverData.load(tmp_path / "m.npz").gm_clock_s_per_rad == 250.0
    dataclasses.replace(data, gm_clock_s_per_rad=0.0).save(tmp_path / "none.npz")
    with np.load(tmp_path / "none.npz") as saved:
        assert "gm_clock_s_per_rad" not in saved.files
    assert preprocess.ManeuverData.load(tmp_path / "none.npz").gm_clock_s_per_rad == 0.0


GM_ANGLE = {"gm_sigma_cross_arcsec": 30.0, "gm_sigma_about_arcsec": 30.0, "gm_tau_s": 3000.0, "gm_clock_s_per_rad": 3000.0}
"""A reference error that holds at rest (50 min) and forgets over a radian turned: 3000 s a radian."""


def _profile(lins, boresight, log_sigma) -> float:
    ratios = covariance.ratios_of(log_sigma)
    noises = [covariance.build(lin, boresight, covariance.correlation_time_of(ratios)) for lin in lins]
    return float(noisefit.profile_reml(noises, ratios)[0])


def _gain(gm: dict, kappa: float, n_maneuvers: int = 3) -> float:
    """The REML's negative log-likelihood on the time clock less on ``kappa`` s/rad, each fitted."""
    data, spec, theta, biases, b = _tiny(gm, n_maneuvers)
    start = covariance.log_sigma_of({"sigma_cross_arcsec": 5.0, "sigma_about_arcsec": 20.0, "arw_deg_sqrt_h": 0.003})
    values = []
    for k in (0.0, kappa):
        lins = _linearized(data, spec, theta, biases, k)
        values.append(_profile(lins, b, noisefit.estimate_correlated_noise(lins, b, start, 10.0)[0]))
    return values[0] - values[1]


@pytest.mark.full  # 8 s; the fast tier keeps the clock's steps, the chained clock and the plan on the clock
def test_the_remls_fit_gains_on_the_true_angle_clock():
    """Three tiny maneuvers whose reference error runs on the angle clock: stated, the clock gains tens of
    log-likelihood units (58-67 over three seeds) over the best the time clock fits."""
    assert _gain(GM_ANGLE, 3000.0) > 30.0


@pytest.mark.full
def test_a_clock_stated_where_the_error_runs_on_time_costs_the_fit():
    """The same on two maneuvers whose error runs on time (tau 30 s): the stated clock loses 200-310 units."""
    assert _gain({**GM_ANGLE, "gm_tau_s": 30.0, "gm_clock_s_per_rad": 0.0}, 3000.0, 2) < -100.0


def test_taus_prior_on_the_angle_clock_is_thirty_seconds_or_a_radian_turned():
    stated = {"sigma_cross_arcsec": 10.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003}
    assert covariance.gm_tau_prior_s(stated) == 30.0
    clocked = {**stated, "gm_clock_s_per_rad": 3000.0}
    assert covariance.gm_tau_prior_s(clocked) == 3030.0
    tau = covariance.position(covariance.log_sigma_of(clocked, correlated=True), covariance.GM_TAU_SCALE)
    assert np.exp(covariance.log_sigma_of(clocked, correlated=True)[tau]) == pytest.approx(3030.0)
    knowledge = covariance.noise_knowledge({"star_tracker": {"gm_clock_s_per_rad": 3000.0}, "gyro": {}},
                                           {**stated, "boresight_body": [0, 0, 1]})
    assert knowledge["gm_clock_s_per_rad"] == 3000.0


def test_a_saved_linearisation_is_not_taken_for_a_maneuver_on_another_clock():
    from gyrocal.inference.fit.estimate import PointEstimate

    data, spec, theta, biases, b = _tiny({}, n_maneuvers=1)
    est = PointEstimate(spec, theta, None, biases[None], None, np.zeros(3), np.nan, 0, "test", 0.0,
                        {"boresight_body": b.tolist()})
    keys = {k: est.linearization_key(dataclasses.replace(data[0], gm_clock_s_per_rad=k), 0) for k in (0.0, 1.0, 2.0)}
    assert len(set(keys.values())) == 3


def test_the_remls_tau_starts_ten_clock_steps_in_on_the_angle_clock():
    """On the angle clock the residuals' correlation time (which presumes equal steps) is not the start:
    ten of the clock's median steps are; on time the residuals' estimate stays."""
    data, spec, theta, biases, _ = _tiny({}, n_maneuvers=2)
    clocked = _linearized(data, spec, theta, biases, 100.0)
    steps = np.concatenate([lin.gm_dt[1:] for lin in clocked])
    assert noisefit.tau_start_s(clocked) == pytest.approx(noisefit.TAU_START_INTERVALS * np.median(steps))
    on_time = _linearized(data, spec, theta, biases, 0.0)
    assert noisefit.tau_start_s(on_time) == (noisefit.correlation_time(on_time)
                                             or noisefit.TAU_START_INTERVALS * np.median(np.concatenate(
                                                 [lin.st_dt[1:] for lin in on_time])))


def test_maneuvers_chained_run_on_their_clock_and_a_gap_on_its_time():
    """Two tiny maneuvers chained (`segments.build`): on the clock the covariance differs from the time
    clock's; with the clock's steps given as time steps instead, and the gap the same, it is the same bits."""
    from gyrocal.inference.noise import segments

    data, spec, theta, biases, b = _tiny({}, n_maneuvers=2)
    clocked = _linearized(data, spec, theta, biases, 300.0)
    gap = np.array([data[1].st_time[0] - data[0].st_time[-1]])
    on_clock = segments.build(clocked, gap, b, 50.0)
    on_time = segments.build([dataclasses.replace(lin, gm_dt=None) for lin in clocked], gap, b, 50.0)
    as_time = segments.build([dataclasses.replace(lin, st_dt=lin.gm_dt, gm_dt=None) for lin in clocked], gap, b, 50.0)
    var = covariance.unit_variances(covariance.ratios_of(covariance.log_sigma_of(
        {"sigma_cross_arcsec": 5.0, "sigma_about_arcsec": 20.0, "arw_deg_sqrt_h": 0.003}, correlated=True)))
    assert not np.allclose(on_clock.covariance(var), on_time.covariance(var))
    np.testing.assert_array_equal(on_clock.covariance(var), as_time.covariance(var))
    np.testing.assert_array_equal(on_clock.rhs, as_time.rhs)
