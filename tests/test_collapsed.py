"""The collapsed move: channel offsets drawn from their exact Gaussian conditional given the noise.

Checked against the log posterior itself: minus the conditional's log density it is flat in the
offsets (so only the noise's marginal is left in the acceptance), its finite-difference Hessian is
the conditional's precision, and the offsets the move draws have the conditional's mean and covariance.
"""

import numpy as np
from test_numerics import BORESIGHT, P, tiny_linearization

from gyrocal.inference.noise import covariance
from gyrocal.inference.sampling.noisegrid import RatioGrid
from gyrocal.inference.sampling.posterior import LogPosterior
from gyrocal.inference.sampling.priors import Priors
from gyrocal.inference.sampling.proposal import CollapsedProposal, ConditionalCache, StudentProposal

LOG_SIGMA = np.log([1e-4, 3e-4, 2e-6])


def tiny_posterior():
    nz = [covariance.build(tiny_linearization(seed), BORESIGHT) for seed in (0, 1)]
    grid = RatioGrid(nz, covariance.ratios_of(LOG_SIGMA), np.array([0.3, 0.3]), 7, 8.0)
    priors = Priors(mean=np.full(P, 0.02), sd=np.full(P, 0.05), bound=np.full(P, 10.0),
                    log_sigma_center=LOG_SIGMA, log_sigma_sd=np.ones(3))
    return LogPosterior(grid, np.full(P, 0.01), priors)


def log_normal(d, mean, chol):
    r = np.einsum("ji,wj->wi", chol, d - mean)
    return np.sum(np.log(np.diag(chol))) - 0.5 * np.sum(r**2, axis=1)


def test_log_posterior_minus_the_conditional_is_flat_in_the_offsets():
    logpost = tiny_posterior()
    noise_x = np.concatenate([LOG_SIGMA + [0.05, -0.1, 0.2]])[None]
    mean, chol, ok, _ = logpost.conditional(noise_x)
    assert ok.all()
    d = mean + np.random.default_rng(1).normal(0, 0.02, (20, P))
    rest = logpost(np.hstack([d, np.repeat(noise_x, 20, axis=0)])) - log_normal(d, mean[0], chol[0])
    assert np.ptp(rest) < 1e-7 * np.abs(rest).max()


def test_conditional_precision_is_the_log_posteriors_hessian_and_its_mean_the_mode():
    logpost = tiny_posterior()
    noise_x = LOG_SIGMA[None] + 0.02
    mean, chol, _, _ = logpost.conditional(noise_x)
    h, step, eye = np.zeros((P, P)), 1e-3, np.eye(P)
    f = lambda d: logpost(np.concatenate([d, noise_x[0]])[None])[0]
    for i in range(P):
        for j in range(P):
            h[i, j] = (f(mean[0] + step * (eye[i] + eye[j])) - f(mean[0] + step * (eye[i] - eye[j]))
                       - f(mean[0] - step * (eye[i] - eye[j])) + f(mean[0] - step * (eye[i] + eye[j]))) / (4 * step**2)
    np.testing.assert_allclose(-h, chol[0] @ chol[0].T, rtol=1e-5)
    grad = [(f(mean[0] + step * eye[i]) - f(mean[0] - step * eye[i])) / (2 * step) for i in range(P)]
    assert np.max(np.abs(grad)) < 1e-6 * np.max(np.abs(h))


def test_collapsed_move_draws_the_offsets_from_their_conditional():
    logpost = tiny_posterior()
    eta = LOG_SIGMA + [0.05, -0.1, 0.2]
    narrow = StudentProposal(eta, np.eye(3) * 1e-20)
    move = CollapsedProposal(ConditionalCache(logpost.conditional), P, narrow)
    x = np.tile(np.concatenate([np.zeros(P), eta]), (20000, 1))
    new, ratio = move(x, np.random.RandomState(2))
    mean, chol, _, _ = logpost.conditional(eta[None])
    cov = np.linalg.inv(chol[0] @ chol[0].T)
    sd = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(new[:, :P].mean(axis=0), mean[0], atol=4 * sd.max() / np.sqrt(20000))
    np.testing.assert_allclose(np.cov(new[:, :P].T), cov, atol=0.05 * sd.max() ** 2)
    # the ratio: the proposal's density of the old point over the new one's, noise and offsets
    expected = (narrow.log_density(x[:, P:]) - narrow.log_density(new[:, P:])
                + log_normal(x[:, :P], mean[0], chol[0]) - log_normal(new[:, :P], mean[0], chol[0]))
    np.testing.assert_allclose(ratio, expected, rtol=1e-6, atol=1e-6)


def test_collapsed_move_rejects_noise_where_the_conditional_has_no_precision():
    """Where the interpolated statistics are not positive definite (far off the grid, an extrapolation
    can be anything; here every node's gram negated) the move stays put: a rejected proposal."""
    logpost = tiny_posterior()
    logpost.priors.sd[:] = 1e12
    logpost.grid.values[:, :P * P] *= -1
    move = CollapsedProposal(ConditionalCache(logpost.conditional), P, StudentProposal(LOG_SIGMA, np.eye(3) * 1e-20))
    x = np.tile(np.concatenate([np.zeros(P), LOG_SIGMA]), (3, 1))
    assert not logpost.conditional(x[:, P:])[2].any()
    new, ratio = move(x, np.random.RandomState(0))
    assert np.all(new == x) and np.all(ratio == -np.inf)


def test_collapsed_move_reuses_the_last_calls_conditionals_to_the_bit():
    """A walker's own noise is usually the last call's proposal (accepted) or its own (kept): the move
    takes those conditionals from the last call, with the numbers a fresh computation gives."""
    logpost = tiny_posterior()
    noise_proposal = StudentProposal(LOG_SIGMA, np.eye(3) * 1e-4)
    x = np.tile(np.concatenate([np.zeros(P), LOG_SIGMA]), (8, 1))
    cached = CollapsedProposal(ConditionalCache(logpost.conditional), P, noise_proposal)
    first, _ = cached(x, np.random.RandomState(3))
    mixed = np.where(np.arange(8)[:, None] % 2 == 0, first, x)  # half accepted, half kept
    again, ratio = cached(mixed, np.random.RandomState(4))
    fresh_move = CollapsedProposal(ConditionalCache(logpost.conditional), P, noise_proposal)
    fresh, fresh_ratio = fresh_move(mixed, np.random.RandomState(4))
    assert np.array_equal(again, fresh) and np.array_equal(ratio, fresh_ratio)


def test_local_collapsed_move_steps_about_the_walkers_noise_and_leaves_the_proposals_density_out():
    """The local move's noise step is symmetric, so the ratio holds the offsets' conditionals alone."""
    logpost = tiny_posterior()
    noise_proposal = StudentProposal(LOG_SIGMA, np.eye(3) * 1e-4)
    x = np.tile(np.concatenate([np.zeros(P), LOG_SIGMA + [0.01, 0.0, -0.01]]), (500, 1))
    move = CollapsedProposal(ConditionalCache(logpost.conditional), P, noise_proposal, local_scale=0.5)
    new, ratio = move(x, np.random.RandomState(6))
    steps = (new[:, P:] - x[:, P:]) / 0.5
    scale = noise_proposal.chol @ noise_proposal.chol.T
    np.testing.assert_allclose(np.cov(steps.T), scale, atol=0.2 * scale.max())
    old_mean, old_chol, _, _ = logpost.conditional(x[:, P:])
    new_mean, new_chol, _, _ = logpost.conditional(new[:, P:])
    expected = [log_normal(x[i:i + 1, :P], old_mean[i], old_chol[i])[0]
                - log_normal(new[i:i + 1, :P], new_mean[i], new_chol[i])[0] for i in range(5)]
    np.testing.assert_allclose(ratio[:5], expected, rtol=1e-6, atol=1e-6)


def test_conditional_draws_are_the_mean_plus_the_inverse_transposed_factor_times_the_normals():
    """One solve gives the mean and the draws: ``(L L^T)^-1 (b + L z) = mean + L^-T z``."""
    logpost = tiny_posterior()
    noise_x = LOG_SIGMA[None] + np.array([[0.0, 0.0, 0.0], [0.1, -0.2, 0.3]])
    z = np.random.default_rng(7).standard_normal((2, P))
    mean, chol, _, draw = logpost.conditional(noise_x, z)
    expected = mean + np.stack([np.linalg.solve(chol[i].T, z[i]) for i in range(2)])
    np.testing.assert_allclose(draw, expected, rtol=1e-10, atol=1e-12)
    assert np.array_equal(logpost.conditional(noise_x)[3], mean)


def test_collapsed_moves_share_their_cache_so_only_walkers_moved_elsewhere_cost_a_conditional():
    """After the independence move, the local move finds every walker's own conditional (accepted or
    kept) in the shared cache; a walker another move (DE) shifted costs a fresh one."""
    logpost = tiny_posterior()
    rows = []
    shared = ConditionalCache(lambda eta, z=None: rows.append(len(eta)) or logpost.conditional(eta, z))
    noise_proposal = StudentProposal(LOG_SIGMA, np.eye(3) * 1e-4)
    x = np.tile(np.concatenate([np.zeros(P), LOG_SIGMA]), (8, 1))
    first, _ = CollapsedProposal(shared, P, noise_proposal)(x, np.random.RandomState(3))
    mixed = np.where(np.arange(8)[:, None] % 2 == 0, first, x)
    mixed[7, P] += 1e-3  # shifted by some other move
    CollapsedProposal(shared, P, noise_proposal, local_scale=0.5)(mixed, np.random.RandomState(4))
    assert rows == [16, 9]


def test_grid_statistics_taken_from_the_last_call_equal_fresh_interpolation():
    """Rows whose ratios repeat the last call's (the proposal's conditional, then its log posterior)
    are taken from it; the rest are interpolated: every row as a fresh grid gives it."""
    grid = tiny_posterior().grid
    rng = np.random.default_rng(8)
    first = covariance.ratios_of(LOG_SIGMA) + rng.normal(0, 0.1, (6, 2))
    second = np.vstack([first[:4], first[4:] + 0.05, first[:1]])
    grid.stats(first)
    again = grid.stats(second)
    grid._last = None
    fresh = grid.stats(second)
    for a, f in zip(again, fresh):
        np.testing.assert_allclose(a, f, rtol=1e-14, atol=0)
