"""Maneuvers chained where the star tracker's Gauss-Markov error runs on between them.

The chained likelihood is checked against the dense one straight from the definitions: white
star-tracker noise, one Gauss-Markov error running through the gap, and each maneuver's own gyro
walk starting afresh, with each maneuver's nuisance integrated out under a flat prior.
"""

import numpy as np
import pytest
from test_numerics import BORESIGHT, VAR, P, integrated_loglik, tiny_linearization

from gyrocal.inference import errormodel
from gyrocal.inference.fit.likelihood import campaign_stats, maneuver_stats
from gyrocal.inference.noise import covariance, segments


def one_set(lin):
    """``lin`` with its first channel set alone."""
    return errormodel.Linearization(
        maneuver=lin.maneuver, sets=lin.sets[:1], z=lin.z[:, :1], design=lin.design[:, :1],
        bias_design=lin.bias_design[:, :1], st_matrix=lin.st_matrix, st_dt=lin.st_dt,
        shared_walk=errormodel._shared_walk(1, lin.st_dt), body_error=lin.body_error[:, :1])


def dense_chain_covariance(lins, gaps, var, tau):
    """The raw chained series' covariance: white noise per sample and one Gauss-Markov error through
    every sample and gap (both shared by the sets, anisotropic about the boresight, the Gauss-Markov
    error in the tracker's frame, both rotated to inertial),
    plus each set's walk, cumulative within its own maneuver and independent between maneuvers."""
    s = lins[0].z.shape[1]
    b = np.asarray(BORESIGHT) / np.linalg.norm(BORESIGHT)
    across, along = np.eye(3) - np.outer(b, b), np.outer(b, b)
    white = var["cross"] * across + var["about"] * along
    gm = var["gm_cross"] * across + var["gm_about"] * along
    dt = np.concatenate([lin.st_dt for lin in lins])
    starts = np.cumsum([0] + [len(lin.z) for lin in lins])
    dt[starts[1:-1]] = gaps
    phi = np.exp(-dt / tau)
    phi[0] = 0.0
    rot = np.concatenate([lin.st_matrix for lin in lins])
    owner = np.repeat(np.arange(len(lins)), np.diff(starts))
    walked = np.concatenate([np.cumsum(lin.st_dt) for lin in lins])
    m = len(dt)
    cov = np.zeros((m, s, 3, m, s, 3))
    for j in range(m):
        for k in range(m):
            block = (j == k) * rot[j] @ white @ rot[j].T
            block = block + np.prod(phi[min(j, k) + 1:max(j, k) + 1]) * rot[j] @ gm @ rot[k].T
            cov[j, :, :, k, :, :] += block[None, :, None, :]
            if owner[j] == owner[k]:
                for u in range(s):
                    cov[j, u, :, k, u, :] += var["walk"] * walked[min(j, k)] * np.eye(3)
    return cov.reshape(m * s * 3, m * s * 3)


def chain_nuisance(lins):
    """Each maneuver's own nuisance columns: the first's initial attitude error and biases, the later
    ones' offset per set and biases."""
    s = lins[0].z.shape[1]
    blocks = []
    for k, lin in enumerate(lins):
        nuis = covariance.nuisance_design(lin)
        if k:
            offsets = np.zeros(lin.z.shape[:2] + (3, 3 * s))
            for u in range(s):
                offsets[:, u, :, 3 * u:3 * u + 3] = np.eye(3)
            nuis = np.concatenate([offsets, nuis[..., 3:]], axis=3)
        blocks.append(nuis.reshape(-1, nuis.shape[-1]))
    rows, cols = sum(len(x) for x in blocks), sum(x.shape[1] for x in blocks)
    out, r, c = np.zeros((rows, cols)), 0, 0
    for x in blocks:
        out[r:r + len(x), c:c + x.shape[1]] = x
        r, c = r + len(x), c + x.shape[1]
    return out


@pytest.mark.parametrize("sets, gap_s, tau_s", [(2, 3.0, 2.5), (1, 0.7, 6.0), (2, 40.0, 15.0)])
def test_chained_likelihood_equals_the_dense_one_with_the_gauss_markov_error_running_on(sets, gap_s, tau_s):
    lins = [tiny_linearization(0, 14), tiny_linearization(1, 11), tiny_linearization(2, 9)]
    if sets == 1:
        lins = [one_set(lin) for lin in lins]
    gaps = np.array([gap_s, 2 * gap_s])
    stats = maneuver_stats(segments.build(lins, gaps, BORESIGHT, tau_s), VAR)
    cov = dense_chain_covariance(lins, gaps, VAR, tau_s)
    g = chain_nuisance(lins)
    x = np.concatenate([lin.design.reshape(-1, P) for lin in lins])
    z = np.concatenate([lin.z.reshape(-1) for lin in lins])
    dtheta = np.random.default_rng(4).normal(0, 0.02, (3, P))
    expected = [integrated_loglik(z - x @ d, cov, g) for d in dtheta]
    np.testing.assert_allclose(stats.loglik(dtheta), expected, rtol=1e-9)


def test_with_one_set_and_the_error_forgotten_across_the_gap_the_chain_is_its_maneuvers_apart():
    """One channel set and a gap of many correlation times: the chain's statistics are the sum of its
    maneuvers' (a set's offset is then the initial attitude error, and nothing runs on)."""
    lins = [one_set(tiny_linearization(seed, 12)) for seed in (0, 1)]
    chained = maneuver_stats(segments.build(lins, np.array([1e4]), BORESIGHT, 2.0), VAR)
    apart = campaign_stats([covariance.build(lin, BORESIGHT, 2.0) for lin in lins], VAR)
    np.testing.assert_allclose(chained.A, apart.A, rtol=1e-8)
    np.testing.assert_allclose(chained.b, apart.b, rtol=1e-8)
    assert chained.c == pytest.approx(apart.c, rel=1e-8)
    assert chained.logdet == pytest.approx(apart.logdet, rel=1e-10)
    assert chained.n == apart.n


class _Maneuver:
    def __init__(self, start, group, name="m"):
        self.st_time, self.noise_group, self.id = np.array([start, start + 10.0]), group, name


def test_chains_are_each_noise_groups_maneuvers_in_time_order_with_their_gaps():
    flown = [_Maneuver(50, "a"), _Maneuver(0, "a"), _Maneuver(5, "b"), _Maneuver(30, "a"), _Maneuver(100, "b")]
    chained = segments.chains(flown)
    assert chained == [[1, 3, 0], [2, 4]]
    np.testing.assert_allclose(segments.gaps_s(flown, chained[0]), [20.0, 10.0])
    np.testing.assert_allclose(segments.gaps_s(flown, chained[1]), [85.0])


def test_a_long_run_of_maneuvers_is_cut_at_its_longest_gaps_into_chains_of_at_most_max_chain():
    starts = [0, 20, 40, 200, 220, 240, 260, 900, 920]  # gaps 10, 10, 150, 10, 10, 10, 630, 10
    flown = [_Maneuver(t, "a") for t in starts]
    assert segments.chains(flown, max_members=4) == [[0, 1, 2], [3, 4, 5, 6], [7, 8]]
    assert segments.chains(flown, max_members=9) == [list(range(9))]
    evenly = segments.chains([_Maneuver(30 * i, "b") for i in range(20)])
    assert sorted(m for c in evenly for m in c) == list(range(20)) and max(len(c) for c in evenly) == segments.MAX_CHAIN


def test_maneuvers_that_overlap_in_time_are_refused_by_name():
    flown = [_Maneuver(0, "a", "first"), _Maneuver(5, "a", "second")]
    with pytest.raises(ValueError, match="first and second of noise group 'a' overlap"):
        segments.chains(flown)
