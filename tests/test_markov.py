"""The Gauss-Markov star-tracker noise (`gyrocal.inference.noise.markov`) against dense references."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_numerics import BORESIGHT, band_to_dense, dense_covariance, transform_matrix

from gyrocal.inference.errormodel import Linearization
from gyrocal.inference.fit import likelihood
from gyrocal.inference.noise import covariance, markov


def _tiny(m=7, n_sets=2, n_par=2, seed=3):
    rng = np.random.default_rng(seed)
    st_dt = rng.uniform(0.5, 2.0, m)
    R = Rotation.random(m, random_state=seed).as_matrix()
    z = rng.normal(size=(m, n_sets, 3))
    design = rng.normal(size=(m, n_sets, 3, n_par))
    bias = rng.normal(size=(m, n_sets, 3, 2 * n_sets))
    return Linearization("tiny", [("a",)] * n_sets, z, design, bias, R, st_dt, None, z.copy())


VAR = {"cross": 1.0, "about": 4.0, "walk": 0.3, "gm_cross": 2.5, "gm_about": 10.0}


@pytest.mark.parametrize("tau", [0.7, 5.0, 300.0])
def test_filtered_covariance_is_the_filter_applied_to_the_dense_covariance(tau):
    lin = _tiny()
    nz = covariance.build(lin, BORESIGHT, tau)
    t_dense = transform_matrix(nz, lin.z.shape[0], 3 * lin.z.shape[1])
    dense = dense_covariance(lin, VAR, tau)
    expected = t_dense @ dense @ t_dense.T
    # random attitudes at tau = 300 dt make the filter's entries ~600: round-off scales with |T| |C| |T'|
    scale = (np.abs(t_dense) @ np.abs(dense) @ np.abs(t_dense).T).max()
    np.testing.assert_allclose(band_to_dense(nz.covariance(VAR)), expected, rtol=1e-10, atol=1e-15 * scale)


def _coefficients(dt, tau, seed=0):
    """The filter's coefficients for random attitudes, and the ``R`` and ``phi`` they came from."""
    R = Rotation.random(len(dt), random_state=seed).as_matrix()
    a, b, phi = markov.coefficients(dt, tau, R)
    return a, b, phi, R


def test_filter_ends_the_memory_of_walk_and_gauss_markov_for_irregular_sampling_and_turning_attitude():
    dt = np.random.default_rng(0).uniform(0.2, 3.0, 12)
    a, b, phi, R = _coefficients(dt, 4.0)
    # the walk: I + A + B = 0; the GM in the tracker frame: (phi_j R_j + A_j R_(j-1)) phi_(j-1) + B_j R_(j-2) = 0
    np.testing.assert_allclose((np.eye(3) + a + b)[1:], 0, atol=1e-13)
    memory = (phi[2:, None, None] * R[2:] + a[2:] @ R[1:-1]) * phi[1:-1, None, None] + b[2:] @ R[:-2]
    np.testing.assert_allclose(memory, 0, atol=1e-12)


@pytest.mark.parametrize("tau, rtol", [(3.0, 1e-12), (1e5, 1e-8)])
def test_filter_at_a_held_attitude_is_the_scalar_second_order_filter(tau, rtol):
    """While the attitude holds, ``A_j = -(1 - phi_j phi_(j-1)) / (1 - phi_(j-1))``. At tau = 1e7 dt,
    ``1 - phi`` is 1e-7: the attitudes' own round-off (1e-16) over it bounds the agreement at 1e-9."""
    dt = np.array([1.0, 0.5, 2.0, 1.0, 0.1]) * (0.01 if tau > 10 else 1.0)
    held = np.repeat(Rotation.random(random_state=2).as_matrix()[None], 5, axis=0)
    a, _, phi = markov.coefficients(dt, tau, held)
    om = -np.expm1(-dt / tau)
    alpha = -(om[2:] + phi[2:] * om[1:-1]) / om[1:-1]
    np.testing.assert_allclose(a[2:], alpha[:, None, None] * np.eye(3), rtol=rtol, atol=rtol)
    np.testing.assert_allclose(a[1], -np.eye(3))


def test_filter_apply_transpose_inverse_and_columns_match_dense():
    m, n_sets = 5, 2
    a, b, _, _ = _coefficients(np.array([1.0, 0.5, 2.0, 1.0, 0.1]), 3.0, seed=4)
    filt = markov.Filter(a, b, n_sets)
    width = 3 * n_sets
    t = np.eye(m * width)
    for j in range(1, m):
        for lag, c in ((1, a), (2, b)):
            if j >= lag:
                for s in range(n_sets):
                    r, k = j * width + 3 * s, (j - lag) * width + 3 * s
                    t[r:r + 3, k:k + 3] = c[j]
    x = np.random.default_rng(1).normal(size=(m, width, 4))
    flat = x.reshape(m * width, 4)
    np.testing.assert_allclose(filt.apply(x).reshape(-1, 4), t @ flat, atol=1e-13)
    np.testing.assert_allclose(filt.apply(x.reshape(m, n_sets, 3, 4)).reshape(-1, 4), t @ flat, atol=1e-13)
    np.testing.assert_allclose(filt.transpose(x).reshape(-1, 4), t.T @ flat, atol=1e-13)
    np.testing.assert_allclose(filt.invert((t @ flat).reshape(x.shape)), x, atol=1e-11)
    for (start, stop), end in (((0, 4), 18), ((7, 13), 30), ((20, 30), 30)):
        np.testing.assert_allclose(filt.columns(start, stop), t[start:end, start:stop], atol=1e-15)
        assert np.count_nonzero(t[end:, start:stop]) == 0


def test_likelihood_statistics_equal_the_dense_generalised_least_squares():
    """The gram of the filtered series is the undifferenced series' under its dense covariance
    (the filter has determinant one), nuisance integrated out the same way."""
    lin = _tiny(m=9)
    tau = 6.0
    nz = covariance.build(lin, BORESIGHT, tau)
    stats = likelihood.maneuver_stats(nz, VAR)
    C = dense_covariance(lin, VAR, tau)
    n = C.shape[0]
    X = lin.design.reshape(n, -1)
    G = covariance.nuisance_design(lin).reshape(n, -1)
    y = lin.z.reshape(n)
    Ci = np.linalg.inv(C)
    P = Ci - Ci @ G @ np.linalg.solve(G.T @ Ci @ G, G.T @ Ci)
    np.testing.assert_allclose(stats.A, X.T @ P @ X, rtol=1e-8)
    np.testing.assert_allclose(stats.b, X.T @ P @ y, rtol=1e-8)
    np.testing.assert_allclose(stats.c, y @ P @ y, rtol=1e-8)
    logdet = np.linalg.slogdet(C)[1] + np.linalg.slogdet(G.T @ Ci @ G)[1]
    np.testing.assert_allclose(stats.logdet, logdet, rtol=1e-9)


def test_vanishing_gauss_markov_part_gives_the_white_likelihood():
    lin = _tiny(m=8)
    white = likelihood.maneuver_stats(covariance.build(lin, [0, 0, 1]), VAR)
    var = {**VAR, "gm_cross": 1e-14, "gm_about": 4e-14}
    for tau in (0.3, 30.0):
        gm = likelihood.maneuver_stats(covariance.build(lin, [0, 0, 1], tau), var)
        np.testing.assert_allclose(gm.A, white.A, rtol=1e-7)
        np.testing.assert_allclose(gm.logdet, white.logdet, rtol=1e-9)


def _simulated(tau_s, gm_arcsec, m=1200, n_man=4, seed=0):
    """Maneuvers whose errors are drawn process by process: white tracker noise (10/40 arcsec),
    a Gauss-Markov part in the tracker's frame, and each set's own gyro walk; a slow turn."""
    from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S

    rng = np.random.default_rng(seed)
    b = np.array([0.0, -0.5, np.sqrt(0.75)])
    shape = lambda c, a: c**2 * (np.eye(3) - np.outer(b, b)) + a**2 * np.outer(b, b)
    white_chol = np.linalg.cholesky(shape(10 * ARCSEC_RAD, 40 * ARCSEC_RAD))
    gm_chol = np.linalg.cholesky(shape(gm_arcsec * ARCSEC_RAD, 4 * gm_arcsec * ARCSEC_RAD))
    arw = 0.003 * DEG_SQRT_H_RAD_SQRT_S
    lins = []
    for k in range(n_man):
        st_dt = np.ones(m)
        R = Rotation.from_rotvec(np.outer(np.linspace(0, 1.5, m), np.eye(3)[k % 3])).as_matrix()
        phi = np.exp(-st_dt / tau_s)
        g = np.zeros((m, 3))
        g[0] = gm_chol @ rng.normal(size=3)
        for j in range(1, m):
            g[j] = phi[j] * g[j - 1] + np.sqrt(1 - phi[j] ** 2) * gm_chol @ rng.normal(size=3)
        st = np.einsum("jab,jb->ja", R, rng.normal(size=(m, 3)) @ white_chol.T + g)
        walk = np.cumsum(arw * rng.normal(size=(m, 2, 3)), axis=0)
        z = st[:, None, :] + walk
        design = np.zeros((m, 2, 3, 1))
        design[:, :, :, 0] = np.linspace(0, 1e-3, m)[:, None, None]
        bias = np.zeros((m, 2, 3, 6))
        for s in range(2):
            bias[:, s, :, 3 * s:3 * s + 3] = np.cumsum(st_dt)[:, None, None] * np.eye(3)
        lins.append(Linearization(f"m{k}", [("a",), ("b",)], z, design, bias, R, st_dt, None, z.copy()))
    return lins, b


@pytest.mark.full
@pytest.mark.parametrize("tau_s, gm_arcsec", [(3.0, 15.0), (30.0, 8.0)])
def test_reml_recovers_the_gauss_markov_sd_and_correlation_time(tau_s, gm_arcsec):
    from gyrocal.inference.fit import noisefit
    from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S

    lins, b = _simulated(tau_s, gm_arcsec)
    start = np.log([10 * ARCSEC_RAD, 40 * ARCSEC_RAD, 0.003 * DEG_SQRT_H_RAD_SQRT_S])
    log_sigma, _ = noisefit.estimate_correlated_noise(lins, b, start, 10.0)
    fitted = covariance.scales_in_units(log_sigma)
    assert fitted[0] == pytest.approx(np.hypot(10.0, gm_arcsec), rel=0.1)  # the tracker's total sd
    assert fitted[3] == pytest.approx(gm_arcsec**2 / (100 + gm_arcsec**2), abs=0.08)  # its Gauss-Markov share
    assert fitted[4] == pytest.approx(tau_s, rel=0.4)


def _slewing(m=300):
    """A tiny maneuver slewing 3 deg/s about x, then y, then z, one sample a second."""
    from test_numerics import tiny_linearization

    from gyrocal.inference import errormodel

    lin = tiny_linearization(seed=1, m=m)
    turn = [Rotation.from_rotvec(np.deg2rad(3.0) * np.eye(3)[(j // (m // 3)) % 3]) for j in range(1, m)]
    attitudes = [Rotation.identity()]
    for step in turn:
        attitudes.append(attitudes[-1] * step)
    lin.st_matrix = np.array([r.as_matrix() for r in attitudes])
    lin.st_dt = np.ones(m)
    lin.shared_walk = errormodel._shared_walk(2, lin.st_dt)
    return lin


def test_a_correlation_time_the_filter_cannot_hold_in_floating_point_is_out_of_the_remls_domain():
    """Slewing 3 deg/s about x, then y, then z, a Gauss-Markov part of tau 1e5 s makes the 3x3 filter's
    coefficients ~rate x tau: the banded Cholesky fails, and the REML's objective is inf there (the
    scan tries the longest tau it allows), where at tau 30 s it is finite."""
    from gyrocal.inference.fit import noisefit

    lin = _slewing()
    for tau, finite in ((30.0, True), (1e5, False)):
        ratios = np.array([np.log(4.0), np.log(0.03), 0.0, np.log(tau)])
        assert np.isfinite(noisefit.finite_profile([covariance.build(lin, BORESIGHT, tau)], ratios)) == finite


@pytest.mark.full
def test_reml_started_far_from_the_correlation_time_finds_it_by_its_scan():
    """Started at tau 100 s, 33 times the true 3 s, the descent alone ends on the plateau where a
    Gauss-Markov part that long is an offset the nuisance takes (tau 95 s, share 0.94); the scan in
    tau (`noisefit.TAU_SCAN`, the other ratios refitted at each) finds the true one."""
    from gyrocal.inference.fit import noisefit
    from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S

    lins, b = _simulated(3.0, 15.0, m=300, n_man=3)
    start = np.log([10 * ARCSEC_RAD, 40 * ARCSEC_RAD, 0.003 * DEG_SQRT_H_RAD_SQRT_S])
    fitted = covariance.scales_in_units(noisefit.estimate_correlated_noise(lins, b, start, 100.0)[0])
    assert fitted[4] == pytest.approx(3.0, rel=0.3)
    assert fitted[3] == pytest.approx(15.0**2 / (100 + 15.0**2), abs=0.08)


@pytest.mark.parametrize("tau", [0.0, 4.0])
def test_walk_between_gyro_samples_matches_the_interpolated_walk(tau):
    """Star-tracker samples inside gyro intervals see each interval's walk in part
    (`errormodel.walk_steps`): the filtered walk covariance is the dense one of that walk."""
    from gyrocal.inference.errormodel import walk_steps

    gyro_time = np.arange(0.0, 12.01, 0.4)
    st_time = np.array([0.9, 2.0, 3.1, 4.3, 5.05, 6.4, 7.7, 9.2])
    m = len(st_time)
    lin = _tiny(m=m, n_sets=1)
    lin.st_dt = np.diff(np.concatenate([[gyro_time[0]], st_time]))
    var, shared = walk_steps(gyro_time, st_time)
    lin.walk_var, lin.walk_lag1 = var, np.concatenate([[0.0], shared])
    dt = np.diff(gyro_time)
    k = np.searchsorted(gyro_time, st_time) - 1
    frac = (st_time - gyro_time[k]) / dt[k]
    seen = np.zeros((m, len(dt)))  # W_j = sum of the intervals before k_j, plus f_j of interval k_j
    for j in range(m):
        seen[j, :k[j]] = 1.0
        seen[j, k[j]] = frac[j]
    walk = seen @ np.diag(dt) @ seen.T
    dense = np.kron(walk, np.eye(3))
    nz = covariance.build(lin, [0, 0, 1], tau)
    t = transform_matrix(nz, m, 3)
    var_only = {"cross": 0.0, "about": 0.0, "walk": 1.0, "gm_cross": 0.0, "gm_about": 0.0}
    np.testing.assert_allclose(band_to_dense(nz.covariance(var_only)), t @ dense @ t.T, atol=1e-12)


def test_reml_profile_streams_the_maneuvers_to_the_same_bits():
    """The correlated REML and the grid's curvature build each maneuver's noise structure, sum it and
    drop it (memory of one maneuver, not all): the same profile, to the bit, as from a list."""
    from gyrocal.inference.fit import noisefit
    from gyrocal.inference.sampling.noisegrid import NoiseShapes

    lins = [_tiny(m=9, seed=s) for s in (3, 4, 5)]
    ratios = np.array([1.2, -3.0, 0.4, np.log(6.0)])
    listed = noisefit.profile_reml([covariance.build(lin, [0, 0, 1], 6.0) for lin in lins], ratios)
    streamed = noisefit.profile_reml((covariance.build(lin, [0, 0, 1], 6.0) for lin in lins), ratios)
    assert streamed == listed
    assert NoiseShapes(None, lins, [0, 0, 1]).profile(ratios) == listed[0]
    grouped = noisefit.profile_reml((covariance.build(lin, [0, 0, 1], 6.0) for lin in lins), ratios, np.array([0, 1, 1]))
    assert np.array_equal(grouped[1], noisefit.profile_reml(
        [covariance.build(lin, [0, 0, 1], 6.0) for lin in lins], ratios, np.array([0, 1, 1]))[1])


def test_the_ratio_grid_leaves_out_the_correlation_times_the_filter_cannot_hold():
    """The BROAD fast trial's extended model (tau 1973 s over 197 s, the grid over the prior) raised a raw
    LinAlgError from the grid's banded Cholesky. On the tiny slew the grid's top tau node (e^11.4 = 9e4 s)
    cannot be factored: it is left out, a point whose interpolation needs it is off the grid, the nodes
    that factor hold the exact statistics, and the profile there is inf, not an exception."""
    from gyrocal.inference.fit import likelihood
    from gyrocal.inference.sampling.noisegrid import NoiseShapes, RatioGrid

    lin = _slewing()
    shapes = NoiseShapes([], [lin], BORESIGHT)
    center = np.array([np.log(4.0), np.log(0.03), 0.0, np.log(30.0)])
    grid = RatioGrid(shapes, center, np.array([0.1, 0.1, 0.1, 2.0]), 5, 4.0)
    by_tau = grid.valid.reshape((5,) * 4)
    assert by_tau[..., :4].all() and not by_tau[..., 4].all()
    left_out = np.argwhere(~by_tau[1:4, 1:4, 1:4, 4])[0] + 1  # a node left out, its neighbours on the grid
    near = grid.start + grid.step * np.append(left_out, 3.5)  # needs it; two tau nodes down, its cubic does not
    A, b, c, logdet, inside = grid.stats(np.array([center, near, near - [0, 0, 0, 2 * grid.step[3]]]))
    assert inside.tolist() == [True, False, True]
    exact = likelihood.maneuver_stats(covariance.build(lin, BORESIGHT, 30.0), covariance.unit_variances(center))
    np.testing.assert_allclose(logdet[0], exact.logdet, rtol=1e-12)
    np.testing.assert_allclose(A[0], exact.A, rtol=1e-10)
    np.testing.assert_allclose([*b[0], c[0]], [*exact.b, exact.c], rtol=1e-10)
    assert shapes.profile(grid.start + grid.step * np.append(left_out, 4)) == np.inf


def test_the_gauss_markov_replicates_are_the_process_on_its_clock():
    """Drawn as the process (`predictive.gauss_markov_draws`): stationary from the first sample, each
    axis across the boresight with variance 4 and about it 9, consecutive samples correlated exp(-dt/tau)
    where the clock steps 1 s at tau 5 s, and held where the clock barely moves (steps of 1e-6 of tau,
    an angle clock at rest: 400 steps move it by about 0.085, its sd being 3), where the filter's inverse lost its precision."""
    from gyrocal.inference.sampling.predictive import gauss_markov_draws

    rng = np.random.default_rng(11)
    b = np.array([0.0, -0.5, np.sqrt(0.75)])
    draws = gauss_markov_draws(np.ones(400), 5.0, b, np.full(2000, 4.0), np.full(2000, 9.0), 2, rng)
    assert draws.shape == (2000, 400, 2, 3) and np.array_equal(draws[:, :, 0], draws[:, :, 1])
    g = draws[:, :, 0]
    about = g @ b
    across = g - about[..., None] * b
    assert np.var(about[:, [0, 399]]) == pytest.approx(9.0, rel=0.05)
    assert np.mean(np.sum(across[:, [0, 399]] ** 2, axis=-1)) / 2 == pytest.approx(4.0, rel=0.05)
    assert np.mean(about[:, 1:] * about[:, :-1]) / 9.0 == pytest.approx(np.exp(-1 / 5.0), abs=0.02)
    held = gauss_markov_draws(np.full(400, 1e-6), 1.0, b, np.full(50, 4.0), np.full(50, 9.0), 1, rng)[:, :, 0]
    assert np.max(np.abs(held - held[:, :1])) < 0.5 and np.var(held[:, -1] @ b) == pytest.approx(9.0, rel=0.5)
