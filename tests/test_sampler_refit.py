"""The sampler refits a noise proposal that a short burn-in placed badly (gyrocal.inference.sampling.ensemble):
on a posterior whose answer is known, it converges with the refit and is stopped without it."""

import numpy as np
import pytest

from gyrocal.inference.sampling import ensemble
from gyrocal.inference.sampling.budget import SamplingStopped

CFG = {"walkers": 16, "ensembles": 2, "burn_steps": 20, "chunk_steps": 50, "min_tau_multiple": 50,
       "max_steps": 3000, "initial_steps": 150}
"""A burn-in of 20 steps: too short to fit the noise proposal from a start far off and 50 times too narrow."""


class Gaussian:
    """One channel offset, standard normal whatever the noise, and two noise slots N((3, -2), I):
    a posterior with the sampler's interface (`posterior.LogPosterior`), its answer known."""

    n_params = 1
    mean = np.array([3.0, -2.0])

    def conditional(self, noise_x, z=None):
        w = len(noise_x)
        zero = np.zeros((w, 1))
        return zero, np.ones((w, 1, 1)), np.ones(w, dtype=bool), zero + (0.0 if z is None else z)

    def __call__(self, x):
        x = np.atleast_2d(x)
        return -0.5 * x[:, 0] ** 2 - 0.5 * np.sum((x[:, 1:] - self.mean) ** 2, axis=1)


def run(seed=3):
    return ensemble.run_ensembles(Gaussian(), np.array([0.0, 2.5, -1.5]), 0.0004 * np.eye(3), CFG, seed=seed)


def test_a_noise_proposal_a_short_burn_in_placed_badly_is_refitted_and_the_chain_converges():
    result = run()
    assert result.converged_length and result.refits == 1
    assert result.burn == CFG["burn_steps"] + ensemble.REFIT_MIN_STEPS  # the production before the refit discarded
    noise = result.chains[..., 1:].reshape(-1, 2)
    np.testing.assert_allclose(noise.mean(axis=0), Gaussian.mean, atol=0.1)
    np.testing.assert_allclose(noise.std(axis=0), [1.0, 1.0], atol=0.1)
    assert result.tau.max() < ensemble.REFIT_TAU_STEPS


def test_without_the_refit_the_same_chain_is_stopped_for_its_budget(monkeypatch):
    monkeypatch.setattr(ensemble, "MAX_REFITS", 0)
    with pytest.raises(SamplingStopped, match=r"beyond sampler\.max_steps = 3000"):
        run()


def test_the_same_seed_gives_the_same_refitted_chains():
    np.testing.assert_array_equal(run().chains, run().chains)
