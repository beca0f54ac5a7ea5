"""The reference's timing jitter (`st_jitter`) beside its Gauss-Markov noise (`st_correlated_noise`): the
jitter is white, so it filters as the tracker's white noise does (`markov`), one more component with no
Gauss-Markov counterpart; its covariance against dense references, its REML on a simulated campaign
with both, and the noise scales' layout of a model with both."""

from dataclasses import replace

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation
from test_numerics import BORESIGHT, band_to_dense, dense_covariance

from gyrocal.inference import errormodel
from gyrocal.inference.noise import covariance, segments

from conftest import DATA, ROOT

VAR = {"cross": 2.0e-10, "about": 3.5e-9, "walk": 4.0e-12, "gm_cross": 6.0e-10, "gm_about": 1.05e-8, "jitter": 5.0e-11}
"""Variances (rad^2, rad^2/s, s^2) whose components are of one size at body rates of 2 rad/s: none hides another."""


def _tiny(m=6, n_sets=2, seed=0):
    """A synthetic maneuver of ``m`` reference samples: uneven steps, an attitude that turns about a
    changing axis, random body rates (rad/s) and designs."""
    rng = np.random.default_rng(seed)
    st_dt = rng.uniform(0.5, 2.0, m)
    rotvec = np.cumsum(rng.normal(0.0, 0.4, (m, 3)), axis=0)
    return errormodel.Linearization(
        maneuver=f"tiny{seed}", sets=[("a",)] * n_sets, z=rng.normal(0, 1e-4, (m, n_sets, 3)),
        design=rng.normal(0, 1e-3, (m, n_sets, 3, 2)), bias_design=rng.normal(size=(m, n_sets, 3, n_sets)),
        st_matrix=Rotation.from_rotvec(rotvec).as_matrix(), st_dt=st_dt, shared_walk=None,
        body_error=rng.normal(0, 1e-4, (m, n_sets, 3)), st_body_rate=rng.normal(0.0, 2.0, (m, 3)))


def _dense_jitter(lins) -> np.ndarray:
    """The jitter's undifferenced covariance per unit ``sigma_t^2``, sample by sample: ``R omega omega^T R^T``
    at each reference sample (inertial frame), shared by every pair of channel sets, none across samples."""
    rates = np.concatenate([lin.st_body_rate for lin in lins])
    attitudes = np.concatenate([lin.st_matrix for lin in lins])
    m, s = len(rates), lins[0].z.shape[1]
    out = np.zeros((m, s, 3, m, s, 3))
    for j in range(m):
        v = attitudes[j] @ rates[j]
        out[j, :, :, j, :, :] = np.outer(v, v)[None, :, None, :]
    return out.reshape(m * s * 3, m * s * 3)


def _filter_matrix(nz, m, width) -> np.ndarray:
    """The noise's Gauss-Markov filter T as a dense matrix: `markov.Filter.apply` on the identity."""
    return nz.filter.apply(np.eye(m * width).reshape(m, width, -1)).reshape(m * width, -1)


@pytest.mark.parametrize("n_sets", [1, 2])
@pytest.mark.parametrize("tau", [0.7, 5.0, 300.0])
def test_filtered_covariance_with_the_jitter_is_the_filter_applied_to_the_dense_covariance(tau, n_sets):
    """``T C T^T``, with C the dense covariance of white + Gauss-Markov + jitter + walk built sample by
    sample, is the banded filtered covariance, each variance on its own component."""
    lin = _tiny(n_sets=n_sets)
    nz = covariance.build(lin, BORESIGHT, tau, jitter=True)
    assert set(nz.components) == {"cross", "about", "gm_cross", "gm_about", "jitter", "walk"}
    t = _filter_matrix(nz, 6, 3 * n_sets)
    dense = dense_covariance(lin, VAR, tau) + VAR["jitter"] * _dense_jitter([lin])
    expected = t @ dense @ t.T
    # a turning attitude at tau = 300 dt makes the filter's entries large: round-off scales with |T| |C| |T'|
    scale = (np.abs(t) @ np.abs(dense) @ np.abs(t).T).max()
    np.testing.assert_allclose(band_to_dense(nz.covariance(VAR)), expected, rtol=1e-10, atol=1e-15 * scale)
    without = covariance.build(replace(lin, st_body_rate=None), BORESIGHT, tau)
    off = {k: v for k, v in VAR.items() if k != "jitter"}
    np.testing.assert_array_equal(nz.covariance({**off, "jitter": 0.0}), without.covariance(off))


def test_chained_maneuvers_take_each_ones_body_rate_through_the_filter_across_the_gap():
    """Two maneuvers chained (`segments.build`): the jitter component is ``T J T^T``, J block diagonal with
    each sample's ``R omega omega^T R^T`` of its own maneuver, T the chain's filter (the gap's phi)."""
    lins = [_tiny(m=4, seed=1), _tiny(m=5, seed=2)]
    nz = segments.build(lins, np.array([3.0]), BORESIGHT, 4.0, jitter=True)
    t, dense = _filter_matrix(nz, 9, 6), _dense_jitter(lins)
    scale = (np.abs(t) @ np.abs(dense) @ np.abs(t).T).max()
    np.testing.assert_allclose(band_to_dense(nz.components["jitter"]), t @ dense @ t.T, rtol=1e-12, atol=1e-15 * scale)


def test_the_noise_scales_of_both_are_the_correlated_five_then_the_jitter():
    """``[cross, about, arw, logit share, log tau_s, log sigma_t]``: sigma_t enters as its ratio to sigma_cross,
    the share and tau as themselves; the variances split the tracker's between white and Gauss-Markov and
    add sigma_t^2 (s^2)."""
    assert [s.key for s in covariance.noise_scales(True, True)] == [
        "sigma_cross_arcsec", "sigma_about_arcsec", "arw_deg_sqrt_h", "st_gm_fraction", "st_gm_tau_s", "st_jitter_ms"]
    log_sigma = np.log([1e-5, 4e-5, 1e-6, 1.0, 12.0, 4e-3])
    log_sigma[3] = np.log(0.25 / 0.75)  # a Gauss-Markov share of 1/4
    ratios = covariance.ratios_of(log_sigma)
    np.testing.assert_allclose(ratios, [np.log(4.0), np.log(0.1), np.log(1 / 3), np.log(12.0), np.log(400.0)])
    np.testing.assert_array_equal(covariance.absolute_of(log_sigma[0], ratios), log_sigma)
    assert covariance.correlation_time_of(ratios) == pytest.approx(12.0)
    var = covariance.variances(log_sigma)
    expected = {"cross": 0.75e-10, "about": 12e-10, "walk": 1e-12, "gm_cross": 0.25e-10, "gm_about": 4e-10, "jitter": 1.6e-5}
    assert var.keys() == expected.keys()
    for k, v in expected.items():
        assert var[k] == pytest.approx(v, rel=1e-12), k
    scales = covariance.stated_scales(log_sigma)
    assert scales["st_gm_fraction"] == pytest.approx(0.25) and scales["st_jitter_ms"] == pytest.approx(4.0)


@pytest.fixture(scope="module")
def both():
    """``tests/data/jitter_gm.yaml`` (5 ms of jitter, a 10-s Gauss-Markov part) through the point estimate
    of the model with both noise effects: the REML of six scales, then the WLS."""
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import point_estimate
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec
    from gyrocal.simulation import simulate

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    campaign, _ = simulate.simulate(simulate.load_scenario(DATA / "jitter_gm.yaml"))
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = covariance.noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    names = ["scale_factor", "misalignment", "bias", "st_correlated_noise", "st_jitter"]
    spec = ModelSpec.build("both", effects.resolve("both", names, {}), maneuvers[0].channels)
    return maneuvers, point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec)), cfg


def test_the_reml_of_both_recovers_the_simulated_jitter_and_correlation_time(both):
    """5 ms of jitter at 5 deg/s and a Gauss-Markov part of 10 / 40 arcsec over 10 s beside 5 / 20 arcsec of
    white noise: sigma_t within 20 % and tau within a factor 2.5, the Gauss-Markov share (0.8) within 0.1,
    the tracker's total sd (11.2 arcsec) within 20 %. The tolerances are the REML's spread over seeds 1-11
    of this campaign (317 samples): sigma_t 4.1-5.4 ms, tau 4.5-18.7 s; at this seed 5.2 ms and 10.1 s."""
    _, est, _ = both
    scales = covariance.stated_scales(est.log_sigma)
    assert list(scales) == [s.key for s in covariance.noise_scales(True, True)]
    assert 4.0 < scales["st_jitter_ms"] < 6.0, scales
    assert 10.0 / 2.5 < scales["st_gm_tau_s"] < 10.0 * 2.5, scales
    assert est.correlation_time_s == pytest.approx(scales["st_gm_tau_s"])
    assert abs(scales["st_gm_fraction"] - 0.8) < 0.1, scales
    assert scales["sigma_cross_arcsec"] == pytest.approx(np.hypot(5.0, 10.0), rel=0.2), scales


def test_the_posterior_of_both_tabulates_five_ratios_and_samples(both):
    """`posterior.prepare` and a short `posterior.run` on the model with both (a grid of 4 nodes a ratio and
    short chains, to keep it a few seconds: a smoke test, not a calibrated posterior): the priors are the
    correlated model's and the jitter's, in the layout's order; the grid spans five ratios; the labels end
    with the jitter's; the draws are finite, their sigma_t about the simulated 5 ms (median within 20 %)."""
    from gyrocal.inference.sampling import posterior
    from gyrocal.inference.sampling.priors import model_priors

    maneuvers, est, cfg = both
    priors = model_priors(est, cfg["priors"])
    np.testing.assert_array_equal(priors.log_sigma_sd[3:], [2.0, 2.0, 2.0])
    np.testing.assert_allclose(priors.log_sigma_center[3:], [0.0, np.log(30.0), np.log(1e-3)])
    ready = posterior.prepare(maneuvers, est, priors, {**cfg["grid"], "nodes": 4})
    assert ready.grid.shape == (4,) * 5 and ready.labels[-3:] == ["noise.st_gm_fraction", "noise.st_gm_tau_s",
                                                                   "noise.st_jitter_ms"]
    sampler = {**cfg["sampler"], "walkers": 32, "ensembles": 2, "burn_steps": 50, "initial_steps": 50,
               "chunk_steps": 25, "min_tau_multiple": 5, "max_steps": 400}
    chains = posterior.run(ready, sampler, 1).result.chains
    p = len(est.theta)
    assert chains.shape[-1] == p + 6 and np.isfinite(chains).all()
    assert np.median(np.exp(chains[..., p + 5])) == pytest.approx(5e-3, rel=0.2)


def test_a_grid_with_its_own_nodes_along_each_ratio_reproduces_cubic_polynomials_exactly():
    """Nodes per ratio (`benchmarks/jitter_grid.py` coarsens one ratio at a time): 6, 5 and 7 along three
    ratios, 210 nodes, a cubic interpolated to round-off inside, nothing outside."""
    from gyrocal.inference.sampling.noisegrid import RatioGrid

    grid = RatioGrid.__new__(RatioGrid)
    grid.nodes, grid.dims = (6, 5, 7), 3
    grid.start, grid.step = np.array([-1.0, 2.0, 0.5]), np.array([0.25, 0.5, 0.3])
    assert grid.shape == (6, 5, 7) and grid.size == 210
    axes = [grid.start[d] + grid.step[d] * np.arange(n) for d, n in enumerate(grid.shape)]
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def cubic(r):
        u, v, w = np.moveaxis(r, -1, 0)
        return 1 + u * v * w - w**3 + 0.5 * u**3 - u * w**2 + v**2

    points = grid.start + grid.step * np.array([[1.3, 2.7, 3.5], [3.9, 1.0, 5.0], [2.2, 2.9, 1.1]])
    weights, inside = grid.weights(points)
    assert inside.all()
    assert weights @ cubic(nodes).reshape(-1) == pytest.approx(cubic(points), rel=1e-12)
    assert not grid.weights(grid.start + grid.step * np.array([[1.0, 3.5, 2.0]]))[1].any()
