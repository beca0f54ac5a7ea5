"""The numerical core against dense, obvious references on a tiny maneuver (30 samples).

Each structured computation (banded covariance, leave-block-out densities, grid
interpolation, score-test drop) is checked against the same quantity computed with
full matrices, straight from its definition; the WLS's trust region against
`scipy.optimize.least_squares` and numpy's dense least squares on problems with known answers.
"""

import numpy as np
import pytest
from scipy import sparse
from scipy.linalg import cholesky_banded
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from gyrocal.criticism import diagnostics
from gyrocal.inference import errormodel
from gyrocal.inference.fit.estimate import trust_region
from gyrocal.inference.fit.likelihood import Stats, campaign_stats
from gyrocal.inference.fit.trustregion import TERMINATION_MESSAGES
from gyrocal.inference.noise import covariance, selectedinverse
from gyrocal.inference.noise.covariance import variances
from gyrocal.inference.sampling import predictive
from gyrocal.inference.sampling.noisegrid import RatioGrid
from gyrocal.inference.sampling.posterior import start_covariance
from gyrocal.inference.sampling.proposal import StudentProposal

M, SETS, P, CHANNELS = 30, 2, 4, 3
BORESIGHT = [0.3, 0.0, 0.954]


def tiny_linearization(seed=0, m=M):
    """A synthetic maneuver: turning attitudes, uneven star-tracker steps, random designs."""
    rng = np.random.default_rng(seed)
    st_dt = rng.uniform(0.8, 1.2, m)
    st_matrix = Rotation.from_rotvec(np.outer(np.cumsum(st_dt), [0.01, 0.02, 0.05]) + [0.3, -0.2, 1.0]).as_matrix()
    return errormodel.Linearization(
        maneuver=f"tiny{seed}", sets=[("a", "b", "c"), ("d", "e", "f")],
        z=rng.normal(0, 1e-4, (m, SETS, 3)), design=rng.normal(0, 1e-3, (m, SETS, 3, P)),
        bias_design=rng.normal(0, 1.0, (m, SETS, 3, CHANNELS)), st_matrix=st_matrix, st_dt=st_dt,
        shared_walk=errormodel._shared_walk(SETS, st_dt), body_error=rng.normal(0, 1e-4, (m, SETS, 3)))


def dense_covariance(lin, var, tau=0.0):
    """Undifferenced covariance of the stacked inertial errors, from the definitions: one
    star-tracker error shared by the sets (anisotropic about the boresight, rotated to
    inertial; with tau > 0 plus a Gauss-Markov part in the tracker's frame, ``R_j g_j`` with
    ``g_j = phi_j g_(j-1) + eta_j``, stationary) plus each set's own cumulative gyro walk."""
    m, s = lin.z.shape[:2]
    b = np.asarray(BORESIGHT) / np.linalg.norm(BORESIGHT)
    body = var["cross"] * (np.eye(3) - np.outer(b, b)) + var["about"] * np.outer(b, b)
    gm = var.get("gm_cross", 0.0) * (np.eye(3) - np.outer(b, b)) + var.get("gm_about", 0.0) * np.outer(b, b)
    phi = np.exp(-lin.st_dt / tau) if tau > 0 else np.zeros(m)
    phi[0] = 0.0
    t = np.cumsum(lin.st_dt)
    cov = np.zeros((m, s, 3, m, s, 3))
    for j in range(m):
        for k in range(m):
            block = (j == k) * lin.st_matrix[j] @ body @ lin.st_matrix[j].T
            if tau > 0:
                reach = np.prod(phi[min(j, k) + 1:max(j, k) + 1])
                block = block + reach * lin.st_matrix[j] @ gm @ lin.st_matrix[k].T
            cov[j, :, :, k, :, :] += block[None, :, None, :]
            for u in range(s):
                cov[j, u, :, k, u, :] += var["walk"] * t[min(j, k)] * np.eye(3)
    return cov.reshape(m * s * 3, m * s * 3)


def transform_matrix(nz, m, width):
    """The noise's transform T as a dense matrix: first differences, or its Gauss-Markov filter."""
    if nz.filter is None:
        return difference_matrix(m, width)
    return nz.filter.apply(np.eye(m * width).reshape(m, width, -1)).reshape(m * width, -1)


def difference_matrix(m, width):
    """T of the first-difference transform over time blocks of ``width`` rows (first kept)."""
    t = np.eye(m * width)
    t[width:] -= np.eye(m * width)[:-width]
    return t


def band_to_dense(ab):
    n = ab.shape[1]
    out = np.zeros((n, n))
    for d in range(ab.shape[0]):
        idx = np.arange(n - d)
        out[idx + d, idx] = ab[d, idx]
        out[idx, idx + d] = ab[d, idx]
    return out


VAR = {"cross": 2.0e-10, "about": 3.5e-9, "walk": 4.0e-12, "gm_cross": 6.0e-10, "gm_about": 1.05e-8}


@pytest.mark.parametrize("tau", [0.0, 2.5])
def test_banded_covariance_equals_the_dense_differenced_covariance(tau):
    lin = tiny_linearization()
    nz = covariance.build(lin, BORESIGHT, tau)
    t = transform_matrix(nz, M, 3 * SETS)
    expected = t @ dense_covariance(lin, VAR, tau) @ t.T
    got = band_to_dense(nz.covariance(VAR))
    assert np.abs(got - expected).max() < 1e-12 * np.abs(expected).max()


@pytest.mark.parametrize("tau", [0.0, 2.5])
def test_banded_cholesky_gram_and_logdet_equal_dense_solves(tau):
    lin = tiny_linearization(1)
    nz = covariance.build(lin, BORESIGHT, tau)
    gram, logdet = nz.gram(VAR)
    t = transform_matrix(nz, M, 3 * SETS)
    c = t @ dense_covariance(lin, VAR, tau) @ t.T
    assert gram == pytest.approx(nz.rhs.T @ np.linalg.solve(c, nz.rhs), rel=1e-8, abs=1e-12 * np.abs(gram).max())
    assert logdet == pytest.approx(np.linalg.slogdet(c)[1], rel=1e-12)


def integrated_loglik(r, cov, g):
    """log of N(r; G beta, cov) integrated over beta under a flat prior (dense)."""
    chol = np.linalg.cholesky(cov)
    wr, wg = np.linalg.solve(chol, r), np.linalg.solve(chol, g)
    gram = wg.T @ wg
    quad = wr @ wr - wr @ wg @ np.linalg.solve(gram, wg.T @ wr)
    return (-0.5 * (len(r) - g.shape[1]) * np.log(2 * np.pi) - np.sum(np.log(np.diag(chol)))
            - 0.5 * np.linalg.slogdet(gram)[1] - 0.5 * quad)


@pytest.mark.parametrize("tau, block_s", [(0.0, 8.0), (2.5, 8.0), (0.0, 1.0), (2.5, 1.5), (0.5, 2.0), (40.0, 3.0)])
def test_leave_block_out_loglik_equals_brute_force_conditional_densities(tau, block_s):
    """log p(block | rest) = log p(all) - log p(rest), each with the nuisance integrated out;
    with Gauss-Markov star-tracker noise (its filter), and with blocks shorter than the band."""
    lin = tiny_linearization(2)
    nz = covariance.build(lin, BORESIGHT, tau)
    ratios = np.array([0.9, -1.8]) if tau == 0 else np.array([0.9, -1.8, 0.6, np.log(tau)])
    wm = predictive.WhitenedManeuver(nz, ratios)
    rng = np.random.default_rng(3)
    dtheta = rng.normal(0, 0.02, (3, P))
    scale = rng.uniform(0.5, 2.0, 3) * 1e-8
    blocks = predictive.block_index(lin, np.cumsum(lin.st_dt), block_s)
    got = predictive.leave_block_out_loglik(lin, wm, dtheta, scale, blocks)
    unit = dense_covariance(lin, covariance.unit_variances(ratios), tau)
    g = covariance.nuisance_design(lin).reshape(len(unit), -1)
    for d in range(len(dtheta)):
        r = lin.z.reshape(-1) - lin.design.reshape(len(unit), P) @ dtheta[d]
        cov = scale[d] * unit
        full = integrated_loglik(r, cov, g)
        for b in range(blocks.max() + 1):
            rest = blocks != b
            expected = full - integrated_loglik(r[rest], cov[np.ix_(rest, rest)], g[rest])
            assert got[d, b] == pytest.approx(expected, rel=1e-7, abs=1e-6)


@pytest.mark.parametrize("sizes", [[7, 9, 7, 3], [4, 12, 2, 9, 5], [30]])
def test_selected_inverse_windows_equal_the_dense_inverse(sizes):
    """Takahashi's recursion gives C^-1 over each block and the next, short blocks merged."""
    rng = np.random.default_rng(len(sizes))
    n, bandwidth = sum(sizes), 5
    a = rng.normal(size=(n, n)) * (np.abs(np.subtract.outer(np.arange(n), np.arange(n))) <= bandwidth // 2)
    c = a @ a.T + n * np.eye(n)
    chol = cholesky_banded(np.array([np.concatenate([np.diag(c, -d), np.zeros(d)]) for d in range(bandwidth + 1)]),
                           lower=True)
    edges = selectedinverse.recursion_bounds(np.concatenate([[0], np.cumsum(sizes)]), bandwidth)
    assert np.all(np.diff(edges)[:-1] >= bandwidth)
    seen = []
    for start, z in selectedinverse.inverse_windows(chol, edges):
        stop = start + len(z)
        assert z == pytest.approx(np.linalg.inv(c)[start:stop, start:stop], rel=1e-10, abs=1e-14)
        seen.append(start)
    assert seen == list(edges[-2::-1])


def test_smoothed_columns_equal_a_centred_moving_average_over_five_reference_intervals():
    """Gyro at 0.2 s, star tracker at 0.6 s: a centred mean over 15 samples, the edges mirrored
    (d c b a | a b c d), so the maneuver's sum is kept and a step's running total changes
    only within half a window of the step."""
    rng = np.random.default_rng(4)
    k = 60
    columns = rng.normal(size=(k, 3, 2))
    columns[20:40] += 5.0
    dt = np.full(k, 0.2)
    out = errormodel.smoothed_columns(columns, dt, np.arange(0.6, 12.0, 0.6))
    padded = np.concatenate([columns[6::-1], columns, columns[:-8:-1]])
    dense = np.array([padded[i:i + 15].mean(axis=0) for i in range(k)])
    assert out == pytest.approx(dense, abs=1e-12)
    assert out.sum(axis=0) == pytest.approx(columns.sum(axis=0), abs=1e-10)
    step = np.zeros((k, 1))
    step[20:40] = 1.0
    moved = np.cumsum(errormodel.smoothed_columns(step, dt, np.arange(0.6, 12.0, 0.6)), axis=0) - np.cumsum(step, axis=0)
    assert np.abs(moved[:13]).max() < 1e-12 and np.abs(moved[26:33]).max() < 1e-12 and np.abs(moved[46:]).max() < 1e-12
    assert moved[20, 0] == pytest.approx(1.4)


def test_ratio_grid_reproduces_cubic_polynomials_exactly():
    grid = RatioGrid.__new__(RatioGrid)
    grid.nodes, grid.dims, grid.start, grid.step = 9, 2, np.array([-1.0, 2.0]), np.array([0.25, 0.5])
    i, j = np.meshgrid(np.arange(9), np.arange(9), indexing="ij")
    x, y = grid.start[0] + grid.step[0] * i, grid.start[1] + grid.step[1] * j

    def cubic(u, v):
        return 1 + 2 * u - u**2 * v + 0.5 * u**3 - v**3 + u * v

    values = cubic(x, y).ravel()
    points = np.array([[-0.37, 2.61], [-0.5, 3.0], [0.12, 4.7], [0.6, 3.33]])
    weights, inside = grid.weights(points)
    assert inside.all()
    assert weights @ values == pytest.approx(cubic(points[:, 0], points[:, 1]), rel=1e-12)
    assert not grid.weights(np.array([[-1.0, 2.0], [5.0, 3.0]]))[1].any()


def test_four_dimensional_ratio_grid_reproduces_cubic_polynomials_exactly():
    """The grid of correlated noise (four ratios, tau among them) interpolates a cubic exactly."""
    grid = RatioGrid.__new__(RatioGrid)
    grid.nodes, grid.dims = 6, 4
    grid.start, grid.step = np.array([-1.0, 2.0, 0.0, 1.0]), np.array([0.25, 0.5, 0.4, 0.3])
    nodes = grid.start + grid.step * np.stack(np.meshgrid(*[np.arange(6)] * 4, indexing="ij"), axis=-1)

    def cubic(r):
        u, v, w, x = np.moveaxis(r, -1, 0)
        return 1 + u * v * w - w**3 + 0.5 * x**3 - u * x**2 + v * w * x

    points = grid.start + grid.step * np.array([[1.3, 2.7, 3.5, 1.1], [2.0, 1.0, 3.9, 3.6]])
    weights, inside = grid.weights(points)
    assert inside.all()
    assert weights @ cubic(nodes).reshape(-1) == pytest.approx(cubic(points), rel=1e-12)


def test_ratio_grid_over_a_flat_profile_stays_where_the_covariance_can_be_factored():
    """Where the ratios' profile is flat the grid spans their prior (sd 2.12 with noise_log_sd
    1.5): +-8 sd would put a node at e^17 times the star tracker's noise, where the banded
    Cholesky of this maneuver fails from e^10 (a RepoIMU trial crashed there); the grid stops at
    e^8 either way."""
    nz = covariance.build(tiny_linearization(), BORESIGHT)
    with pytest.raises(np.linalg.LinAlgError):
        nz.factor(variances([0.0, 10.0, -10.0]))
    center = np.array([-2.5, -1.7])
    grid = RatioGrid([nz], center, np.full(2, 2.12), 7, 8.0)
    assert grid.start == pytest.approx(center - 8.0) and grid.step == pytest.approx(np.full(2, 16.0 / 6))
    narrow = RatioGrid([nz], center, np.full(2, 0.1), 7, 8.0)
    assert narrow.start == pytest.approx(center - 0.8) and np.isfinite(narrow.values).all()


def test_posterior_start_lands_on_a_grid_whose_span_is_capped():
    """A Gauss-Markov share and tau the data hardly tell (REML profile sd 17 and 34 on RepoIMU at
    1 s): the grid's span is capped at e^8, and the start draws spread as far as the grid does,
    not as the profile: most land inside it (with the profile's sd, 2 % did and the run stopped)."""
    nz = covariance.build(tiny_linearization(), BORESIGHT)
    center = np.array([-2.5, -1.7])
    grid = RatioGrid([nz], center, np.array([17.0, 34.0]), 7, 8.0)
    assert grid.sd == pytest.approx([1.0, 1.0])
    rng = np.random.default_rng(3)

    def inside_share(ratio_sd):
        mean = np.concatenate([[0.0, -6.0], -6.0 + center])
        start = StudentProposal(mean, start_covariance(np.eye(1) * 1e-6, 100, ratio_sd), dof=5.0, inflate=2.0)
        draws = start.draw(rng.standard_normal((4000, 4)), rng.chisquare(5.0, 4000))
        return grid.weights(covariance.ratios_of(draws[:, 1:]))[1].mean()

    assert inside_share(grid.sd) > 0.85
    assert inside_share(np.array([17.0, 34.0])) < 0.1


def test_ratio_grid_interpolation_converges_at_fourth_order_to_the_direct_statistics():
    """Off-grid statistics against `campaign_stats` evaluated there: halving the step cuts the
    error about 16-fold (cubic Lagrange); at 21 nodes over +-3 sd it is below 3e-6."""
    noises = [covariance.build(tiny_linearization(s), BORESIGHT) for s in (4, 5)]
    center, sd = np.array([1.2, -3.0]), np.array([0.08, 0.15])
    points = center + sd * np.array([[0.31, -0.47], [-1.13, 0.77], [1.9, 1.4]])
    direct = [campaign_stats(noises, variances([0.0, r[0], r[1]])) for r in points]

    def worst_error(nodes):
        A, b, c, logdet, inside = RatioGrid(noises, center, sd, nodes, half_width_sd=3.0).stats(points)
        assert inside.all()
        return max(max(np.abs(A[k] - d.A).max() / np.abs(d.A).max(), np.abs(b[k] - d.b).max() / np.abs(d.b).max(),
                       abs(c[k] - d.c) / abs(d.c), abs(logdet[k] - d.logdet) / abs(d.logdet))
                   for k, d in enumerate(direct))

    coarse, fine = worst_error(11), worst_error(21)
    assert fine < 3e-6
    assert coarse / fine > 8


def least_squares_rss(x, y):
    beta = np.linalg.lstsq(x, y, rcond=None)[0]
    return float(np.sum((y - x @ beta) ** 2))


def test_score_test_drop_equals_the_drop_of_a_dense_least_squares_refit():
    rng = np.random.default_rng(6)
    n, m, k = 200, 5, 3
    x = rng.normal(size=(n, m + k))
    y = x[:, :m] @ rng.normal(size=m) + 0.3 * x[:, m:] @ rng.normal(size=k) + rng.normal(size=n)
    stats = Stats(x.T @ x, x.T @ y, float(y @ y), 0.0, n)
    drop = diagnostics.conditional_drop(stats, np.arange(m), np.arange(m, m + k))
    assert drop == pytest.approx(least_squares_rss(x[:, :m], y) - least_squares_rss(x, y), rel=1e-9)
    one = diagnostics.conditional_drop(stats, np.arange(m), [m + 1])
    with_one = np.column_stack([x[:, :m], x[:, m + 1]])
    assert one == pytest.approx(least_squares_rss(x[:, :m], y) - least_squares_rss(with_one, y), rel=1e-9)


def test_score_test_ignores_a_candidate_the_model_already_spans_and_tests_a_partly_collinear_one():
    """A direction 99.9999 % explained by the model's columns would only amplify model error,
    so it scores nothing; one that is 80 % explained is tested as a dense refit says."""
    rng = np.random.default_rng(7)
    n, m = 200, 4
    base = rng.normal(size=(n, m))
    along = base @ rng.normal(size=m)
    spanned = along + 1e-3 * np.linalg.norm(along) / np.sqrt(n) * rng.normal(size=n)
    partly = along + 0.5 * np.linalg.norm(along) / np.sqrt(n) * rng.normal(size=n)
    y = rng.normal(size=n) + 2 * partly + 2 * spanned
    x = np.column_stack([base, spanned, partly])
    stats = Stats(x.T @ x, x.T @ y, float(y @ y), 0.0, n)
    assert diagnostics.conditional_drop(stats, np.arange(m), [m]) == 0.0
    assert least_squares_rss(base, y) - least_squares_rss(x[:, :m + 1], y) > 0
    expected = least_squares_rss(base, y) - least_squares_rss(np.column_stack([base, partly]), y)
    assert diagnostics.conditional_drop(stats, np.arange(m), [m + 1]) == pytest.approx(expected, rel=1e-9)


def test_leave_one_maneuver_out_evidence_equals_dense_gaussian_refits():
    """log p(y_m | y_-m) from the summed statistics against the dense marginal of the data
    (parameters integrated over their prior, nuisance over a flat prior), with and without m."""
    from gyrocal.inference.fit.likelihood import leave_one_out_log_evidence, maneuver_stats
    noises = [covariance.build(tiny_linearization(s, m=12), BORESIGHT) for s in (8, 9, 10)]
    prior_mean, prior_sd = np.array([0.01, -0.02, 0.0, 0.03]), np.array([0.05, 0.1, 0.02, 0.08])
    got = leave_one_out_log_evidence([maneuver_stats(nz, VAR) for nz in noises], prior_mean, prior_sd)

    def dense_log_marginal(keep):
        covs = [band_to_dense(noises[k].covariance(VAR)) for k in keep]
        x = np.vstack([noises[k].rhs[:, :P] for k in keep])
        d = np.concatenate([noises[k].rhs[:, -1] for k in keep])
        sizes = [len(c) for c in covs]
        cov = np.zeros((sum(sizes), sum(sizes)))
        g = np.zeros((sum(sizes), sum(noises[k].n_nuisance for k in keep)))
        row = col = 0
        for k, c in zip(keep, covs):
            cov[row:row + len(c), row:row + len(c)] = c
            nuisance = noises[k].rhs[:, P:P + noises[k].n_nuisance]
            g[row:row + len(c), col:col + nuisance.shape[1]] = nuisance
            row, col = row + len(c), col + nuisance.shape[1]
        return integrated_loglik(d - x @ prior_mean, cov + x @ np.diag(prior_sd**2) @ x.T, g)

    full = dense_log_marginal([0, 1, 2])
    for m in range(3):
        expected = full - dense_log_marginal([k for k in range(3) if k != m])
        assert got[m] == pytest.approx(expected, rel=1e-8, abs=1e-6)


@pytest.mark.parametrize("df", [2, 6, 12])
@pytest.mark.parametrize("x", [200.0, 1400.0, 1600.0, 5000.0, 1e5])
def test_chi2_log_sf_stays_finite_and_exact_where_scipy_underflows(x, df):
    """Against the closed form for even df: P(chi2_2k > x) = exp(-x/2) sum_{i<k} (x/2)^i / i!."""
    from scipy.special import gammaln, logsumexp

    from gyrocal.criticism.diagnostics import chi2_log_sf
    i = np.arange(df // 2)
    exact = -x / 2 + logsumexp(i * np.log(x / 2) - gammaln(i + 1))
    assert chi2_log_sf(x, df) == pytest.approx(exact, rel=1e-9)


def test_autocorrelation_times_equal_emcee_integrated_time_one_series_at_a_time():
    import emcee

    from gyrocal.inference.sampling.ensemble import _autocorr_times, _sokal_window

    rng = np.random.default_rng(3)
    noise_draws = rng.standard_normal((200, 6, 3))
    chain = np.zeros_like(noise_draws)
    for t in range(1, len(chain)):
        chain[t] = np.array([0.2, 0.6, 0.9]) * chain[t - 1] + noise_draws[t]
    reference = emcee.autocorr.integrated_time(chain, quiet=True)
    np.testing.assert_allclose(_autocorr_times(chain), reference, rtol=1e-12)
    assert reference[0] < reference[1] < reference[2]
    chain[:, 2, 1] = 3.7  # one walker stuck: that parameter's time is undefined, and only that one
    times = _autocorr_times(chain)
    assert np.isnan(times[1]) and np.isfinite(times[[0, 2]]).all()
    taus = np.array([[1.0, 1.2, 1.3, 1.3, 1.3], [1.0, 3.0, 6.0, 9.0, 12.0]])  # the second's window never closes
    np.testing.assert_array_equal(_sokal_window(taus, 2.0), [3, 0])  # emcee's auto_window: [3, 0]
    np.testing.assert_array_equal(_sokal_window(taus, 5.0), [0, 0])  # ... and [0, 0]


def test_fitted_noise_proposal_is_the_draws_mean_and_covariance_and_refuses_scales_that_never_moved():
    from gyrocal.inference.sampling.proposal import SamplingError, fitted_noise_proposal

    draws = np.random.default_rng(5).standard_normal((4000, 3)) @ np.array([[1, 0, 0], [0.5, 2, 0], [0, 1, 0.1]])
    proposal = fitted_noise_proposal(draws, inflate=1.0)
    np.testing.assert_allclose(proposal.mean, draws.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(proposal.chol @ proposal.chol.T, np.cov(draws.T), rtol=1e-10)
    draws[:, 1] = 0.3
    with pytest.raises(SamplingError, match="did not move during burn-in"):
        fitted_noise_proposal(draws)
    draws[:, 1] = 2 * draws[:, 0]
    with pytest.raises(SamplingError, match="singular"):
        fitted_noise_proposal(draws)


def _exponential(t, y):
    """``a exp(-k t) + c - y`` and its Jacobian (sparse, as the WLS gives it)."""
    def fun(p):
        return p[0] * np.exp(-p[1] * t) + p[2] - y

    def jac(p):
        e = np.exp(-p[1] * t)
        return sparse.csr_array(np.column_stack([e, -p[0] * t * e, np.ones_like(t)]))
    return fun, jac


def _scipy_trf(fun, jac, x0, tol, lsmr_tol=1e-12):
    """`least_squares` with the options `trust_region` reproduces."""
    return least_squares(fun, x0, jac=jac, method="trf", x_scale="jac", tr_solver="lsmr", ftol=tol, xtol=tol,
                         gtol=1e-10, max_nfev=100, tr_options={"regularize": False, "atol": lsmr_tol, "btol": lsmr_tol})


def test_trust_region_solves_a_linear_least_squares_problem_as_a_dense_solve():
    """Badly scaled columns (1e-2 to 1e2), an inconsistent right-hand side: numpy's lstsq's answer."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(40, 5)) * [1.0, 100.0, 0.01, 10.0, 1.0]
    b = rng.normal(size=40)
    x, cost, nfev, status, J = trust_region(lambda x: A @ x - b, lambda x: sparse.csr_array(A), np.zeros(5),
                                            ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=50, lsmr_tol=1e-14)
    reference = np.linalg.lstsq(A, b, rcond=None)[0]
    np.testing.assert_allclose(x, reference, rtol=1e-9)
    assert cost == pytest.approx(0.5 * np.sum((A @ reference - b) ** 2), rel=1e-12)
    assert status in (1, 2, 3, 4) and nfev < 50
    np.testing.assert_array_equal(J.toarray(), A)


def test_trust_region_takes_least_squares_steps_to_the_bit_and_fits_an_exponential():
    """Noise-free ``2 exp(-0.7 t) + 0.3`` from a start far off: the known answer, and the very steps of
    scipy's trf with the same options (what `wls` relies on); also levenberg-marquardt's answer."""
    t = np.linspace(0.0, 5.0, 30)
    fun, jac = _exponential(t, 2.0 * np.exp(-0.7 * t) + 0.3)
    x0 = np.array([1.0, 0.2, 0.0])
    x, cost, nfev, status, _ = trust_region(fun, jac, x0, ftol=1e-10, xtol=1e-10, gtol=1e-10, max_nfev=100,
                                            lsmr_tol=1e-12)
    np.testing.assert_allclose(x, [2.0, 0.7, 0.3], rtol=1e-10)
    scipy_trf = _scipy_trf(fun, jac, x0, 1e-10)
    np.testing.assert_array_equal(x, scipy_trf.x)
    assert (cost, nfev, status) == (scipy_trf.cost, scipy_trf.nfev, scipy_trf.status)
    assert TERMINATION_MESSAGES[status] == scipy_trf.message
    lm = least_squares(fun, x0, jac=lambda p: jac(p).toarray(), method="lm", ftol=1e-15, xtol=1e-15, gtol=1e-15)
    np.testing.assert_allclose(x, lm.x, rtol=1e-10)


def test_trust_region_with_noise_stops_where_scipy_does_and_at_its_optimum():
    """With noise the optimum is no longer the truth: trust_region's is least_squares' (trf, to the bit;
    lm, to the tolerance)."""
    t = np.linspace(0.0, 5.0, 30)
    y = 2.0 * np.exp(-0.7 * t) + 0.3 + np.random.default_rng(0).normal(0, 0.05, t.size)
    fun, jac = _exponential(t, y)
    x0 = np.array([1.0, 0.2, 0.0])
    ours = trust_region(fun, jac, x0, ftol=1e-10, xtol=1e-10, gtol=1e-10, max_nfev=100, lsmr_tol=1e-12)
    scipy_trf = _scipy_trf(fun, jac, x0, 1e-10)
    np.testing.assert_array_equal(ours[0], scipy_trf.x)
    lm = least_squares(fun, x0, jac=lambda p: jac(p).toarray(), method="lm", ftol=1e-15, xtol=1e-15, gtol=1e-15)
    np.testing.assert_allclose(ours[0], lm.x, rtol=1e-7)
    assert ours[1] == pytest.approx(lm.cost, rel=1e-12)
    assert ours[1:4] == (scipy_trf.cost, scipy_trf.nfev, scipy_trf.status)
