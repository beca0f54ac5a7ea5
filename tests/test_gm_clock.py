"""The simulator's Gauss-Markov reference error on a clock that runs on the angle turned as well as on
time (``star_tracker.gm_clock_s_per_rad``): the recursion with a step of its own per sample, and the
error it gives at rest and in motion."""

import copy

import numpy as np
import pytest

from gyrocal.simulation.simulate import gauss_markov, load_scenario, star_tracker_noise

from conftest import DATA


def by_loop(white, decay):
    """x[k] = phi_k x[k-1] + sqrt(1 - phi_k^2) w[k], phi_k = exp(-decay[k]), x[0] = w[0]: the recursion."""
    x = np.empty_like(white)
    x[0] = white[0]
    for k in range(1, len(white)):
        phi = np.exp(-min(decay[k], 50.0))
        x[k] = phi * x[k - 1] + np.sqrt(1.0 - phi**2) * white[k]
    return x


def test_per_sample_steps_are_the_recursion_and_equal_steps_are_the_filter():
    rng = np.random.default_rng(4)
    white = rng.normal(size=(3000, 3))
    steps = rng.uniform(0.0, 5.0, 3000)
    np.testing.assert_allclose(gauss_markov(white, steps, 7.0), by_loop(white, steps / 7.0), rtol=0, atol=1e-12)
    huge = rng.uniform(0.0, 500.0, 3000)   # steps of many correlation times: the blocks restart the sum
    np.testing.assert_allclose(gauss_markov(white, huge, 1.0), by_loop(white, huge), rtol=0, atol=1e-12)
    np.testing.assert_allclose(gauss_markov(white, np.full(3000, 2.0), 30.0), gauss_markov(white, 2.0, 30.0),
                               rtol=0, atol=1e-12)


def test_on_the_angle_clock_the_error_holds_at_rest_and_changes_as_the_body_turns():
    """A Gauss-Markov part over tau 10 s with 100 s a radian: at rest (no turn) consecutive 1-s samples
    correlate as exp(-0.1), turning 0.1 rad a sample as exp(-1.1); on time alone both as exp(-0.1)."""
    st = {"sigma_cross_arcsec": 1e-6, "sigma_about_arcsec": 1e-6, "boresight_body": [0.0, 0.0, 1.0],
          "gm_sigma_cross_arcsec": 20.0, "gm_sigma_about_arcsec": 20.0, "gm_tau_s": 10.0, "gm_clock_s_per_rad": 100.0}
    n = 40000
    turned = np.where(np.arange(n) < n // 2, 0.0, 0.1)

    def lag1(noise, part):
        x = noise[part, 0]
        return np.corrcoef(x[1:], x[:-1])[0, 1]

    rest, moving = slice(1, n // 2), slice(n // 2 + 1, n)
    on_angle = star_tracker_noise(n, 1.0, st, 0.0, np.random.default_rng(5), turned_rad=turned)
    assert lag1(on_angle, rest) == pytest.approx(np.exp(-0.1), abs=0.01)
    assert lag1(on_angle, moving) == pytest.approx(np.exp(-1.1), abs=0.02)
    on_time = star_tracker_noise(n, 1.0, {**st, "gm_clock_s_per_rad": 0.0}, 0.0, np.random.default_rng(5),
                                 turned_rad=turned)
    assert lag1(on_time, moving) == pytest.approx(np.exp(-0.1), abs=0.01)
    assert np.std(on_angle[:, 0]) == pytest.approx(np.deg2rad(20.0 / 3600.0), rel=0.05)


@pytest.fixture(scope="module")
def tiny_scenario():
    return load_scenario(DATA / "tiny.yaml")


def test_a_scenario_with_the_clock_at_zero_simulates_the_same_bytes_and_truth_records_a_clock(tiny_scenario):
    """The key at 0 changes nothing (the same reference samples to the bit); set, with a Gauss-Markov part,
    it moves the reference and ``truth.json`` records it; a 1-D series keeps its shape."""
    from gyrocal.simulation import simulate

    base = simulate.simulate(tiny_scenario)[0]
    zero = copy.deepcopy(tiny_scenario)
    zero["star_tracker"]["gm_clock_s_per_rad"] = 0.0
    np.testing.assert_array_equal(simulate.simulate(zero)[0].st_quat, base.st_quat)
    clocked = copy.deepcopy(tiny_scenario)
    clocked["star_tracker"].update(gm_sigma_cross_arcsec=5.0, gm_sigma_about_arcsec=20.0, gm_tau_s=300.0,
                                   gm_clock_s_per_rad=300.0)
    campaign, truth = simulate.simulate(clocked)
    assert truth["noise"]["gm_clock_s_per_rad"] == 300.0
    assert not np.array_equal(campaign.st_quat, base.st_quat)
    assert gauss_markov(np.ones(5), np.ones(5), 1.0).shape == (5,)
