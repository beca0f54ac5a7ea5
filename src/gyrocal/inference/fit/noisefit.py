"""The noise scales' restricted maximum likelihood (REML), the point estimate's first step.

With the channel parameters and the nuisance integrated out under flat priors, the
likelihood of the noise depends on ``sigma_cross^2`` in closed form and on the shape of
the covariance (`covariance.ratios_of`) through the banded statistics; the shape is found by
Nelder-Mead on the profile. Correlated star-tracker noise (`markov`) adds the Gauss-Markov
part's sd and correlation time, its filter rebuilt at each tau tried; the reference's timing jitter
adds its ``sigma_t``, with white noise or correlated, kept above `covariance.JITTER_FLOOR_S`.
"""

import numpy as np
from scipy.optimize import minimize

from gyrocal.inference.fit.likelihood import campaign_stats, maneuver_stats, total
from gyrocal.inference.noise import covariance, segments

__all__ = [
    "GM_LOGIT_BOUND", "GROUP_ITERATIONS", "SCAN_EVALUATIONS", "SCAN_MARGIN", "SIMPLEX_STEPS", "TAU_SCAN",
    "TAU_START_INTERVALS", "campaign_level", "correlation_time", "estimate_correlated_noise", "estimate_noise", "finite_profile",
    "profile_group_levels", "profile_reml", "st_step", "tau_start_s",
]


def correlation_time(lins) -> float:
    """Correlation time of the star-tracker noise from the residuals (s; 0 if white).

    For first-order Gauss-Markov noise with coefficient phi per sample, the first
    differences have lag-1 autocorrelation -(1 - phi)/2, and -1/2 when white; the slow
    signal and the gyro walk barely touch the differences.
    """
    num = den = 0.0
    steps = []
    for lin in lins:
        x = np.diff(lin.body_error[:, 0, :], axis=0)
        num += float(np.sum(x[1:] * x[:-1]))
        den += float(np.sum(x * x))
        steps.append(np.median(lin.st_dt[1:]))
    phi = 1.0 + 2.0 * num / den
    if phi <= 0.05:
        return 0.0
    return float(-np.median(steps) / np.log(min(phi, 0.999)))


def profile_reml(noises, ratios, groups=None):
    """REML of the noise with the cross-boresight variance profiled out in closed form.

    ``ratios`` are ``log(sigma_about / sigma_cross)`` and ``log(arw / sigma_cross)``
    (arw per sqrt(s)), with correlated noise ``logit st_gm_fraction`` and ``log tau``, with the timing
    jitter ``log(sigma_t / sigma_cross)`` (`covariance.ratios_of`); the covariance is ``sigma_cross^2``
    times one built from them.
    Returns the negative log-likelihood (up to a constant) and ``log sigma_cross``.
    Prior-only parameters have no column, so they are left out. With ``groups`` (each maneuver's
    noise group, `preprocess.noise_groups`) of more than one group, each group's level is
    profiled (`profile_group_levels`), and ``log sigma_cross`` is one per group.
    """
    var = covariance.unit_variances(ratios)
    if groups is not None and np.max(groups) > 0:
        parts = [maneuver_stats(nz, var) for nz in noises]
        return profile_group_levels([total([s for s, g in zip(parts, groups) if g == k])
                                     for k in range(int(np.max(groups)) + 1)])
    stats = campaign_stats(noises, var)
    informed = np.diag(stats.A) > 0
    factor = np.linalg.cholesky(stats.A[np.ix_(informed, informed)])
    explained = np.linalg.solve(factor, stats.b[informed])
    n = stats.n - int(informed.sum())
    scale = (stats.c - explained @ explained) / n
    negative = 0.5 * (n * np.log(scale) + stats.logdet + 2 * np.sum(np.log(np.diag(factor))))
    return negative, 0.5 * np.log(scale)


def finite_profile(noises, ratios, groups=None) -> float:
    """`profile_reml`'s negative log-likelihood, or inf where the filtered covariance is not positive
    definite in floating point: a Gauss-Markov part far longer than the maneuvers while the attitude
    turns about changing axes, whose 3x3 filter coefficients grow like rate x tau (`markov`)."""
    try:
        return profile_reml(noises, ratios, groups)[0]
    except np.linalg.LinAlgError:
        return np.inf


GROUP_ITERATIONS = 100
"""Fixed-point iterations of the groups' levels at most (they settle to 1e-10 in a few tens)."""


def profile_group_levels(parts):
    """REML with one noise level per group: the groups' unit-scale `likelihood.Stats` share the
    channel parameters, each group its own ``sigma_cross^2``. The levels are a fixed point (each the
    weighted residual of its group, over its share of the degrees of freedom, at the parameters'
    generalised least squares under the others); returns the negative restricted log-likelihood and
    each group's ``log sigma_cross``."""
    informed = np.diag(sum(s.A for s in parts)) > 0
    A = [s.A[np.ix_(informed, informed)] for s in parts]
    b = [s.b[informed] for s in parts]
    n = np.array([s.n for s in parts], dtype=float)
    dof = n - informed.sum() * n / n.sum()
    log_scale = np.zeros(len(parts))
    for _ in range(GROUP_ITERATIONS):
        w = np.exp(-log_scale)
        theta = np.linalg.solve(sum(wk * a for wk, a in zip(w, A)), sum(wk * bk for wk, bk in zip(w, b)))
        rss = np.array([s.c - 2 * bk @ theta + theta @ a @ theta for s, a, bk in zip(parts, A, b)])
        new = np.log(rss / dof)
        done = np.max(np.abs(new - log_scale)) < 1e-10
        log_scale = new
        if done:
            break
    w = np.exp(-log_scale)
    factor = np.linalg.cholesky(sum(wk * a for wk, a in zip(w, A)))
    negative = 0.5 * (np.sum(n * log_scale + rss * w) + sum(s.logdet for s in parts)
                      + 2 * np.sum(np.log(np.diag(factor))))
    return negative, 0.5 * log_scale


TAU_START_INTERVALS = 10.0
"""Where the residuals' differences show no correlation, the REML of correlated noise starts its
correlation time at this many star-tracker intervals."""


def tau_start_s(lins) -> float:
    """Where the REML's descent starts tau (s of the part's clock): the residuals' `correlation_time`, or
    `TAU_START_INTERVALS` clock steps where it finds none or the clock runs on the angle turned
    (`errormodel.gm_clock_steps`), whose steps vary with the motion as `correlation_time` presumes they do
    not (on a BROAD trial it gave 1e6 s, from which the descent ended with sigma_about at zero)."""
    on_angle = any(lin.gm_dt is not None for lin in lins)
    return (0.0 if on_angle else correlation_time(lins)) or TAU_START_INTERVALS * st_step(lins)


def st_step(lins) -> float:
    """The median step of the Gauss-Markov part's clock over the maneuvers (s): the star tracker's sampling
    interval, where the clock is time (`errormodel.Linearization.gm_steps`)."""
    return float(np.median(np.concatenate([lin.gm_steps[1:] for lin in lins])))


def campaign_level(log_cross, noises, groups):
    """The campaign's ``log sigma_cross`` and each group's offset from it (None for one group): the
    groups' levels averaged with their sample counts as weights."""
    log_cross = np.atleast_1d(log_cross)
    if len(log_cross) == 1:
        return float(log_cross[0]), None
    counts = np.bincount(groups, weights=[nz.n for nz in noises], minlength=len(log_cross))
    level = float(np.sum(counts * log_cross) / counts.sum())
    return level, log_cross - level


def _jitter_floor(ratios, log_cross0):
    """Where the timing jitter's ``sigma_t`` sits among ``ratios`` (`covariance.ratios_of`'s; None without
    one), and its floor there: `covariance.JITTER_FLOOR_S` over the start's ``sigma_cross``."""
    return covariance.ratio_position(ratios, covariance.JITTER_SCALE), np.log(covariance.JITTER_FLOOR_S) - log_cross0


def _floored(ratios, k, floor):
    """``ratios`` with the jitter's (at ``k``; None: none) kept above ``floor``, where the profile is flat."""
    if k is None:
        return ratios
    out = np.array(ratios, dtype=float)
    out[k] = max(out[k], floor)
    return out


def estimate_noise(noises, log_sigma0, groups=None):
    """Type-II maximum likelihood (REML) of ``log [sigma_cross, sigma_about, arw]`` (and the timing
    jitter's ``sigma_t``, kept above `covariance.JITTER_FLOOR_S`), and each noise group's offset of
    ``log sigma_cross`` (None for one group; `campaign_level`).

    The channel parameters and the nuisance are integrated out under flat priors.
    """
    log_sigma0 = np.asarray(log_sigma0, dtype=float)
    start = covariance.ratios_of(log_sigma0)
    k, floor = _jitter_floor(start, log_sigma0[0])
    opt = minimize(lambda r: profile_reml(noises, _floored(r, k, floor), groups)[0], start, method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-3})
    ratios = _floored(opt.x, k, floor)
    log_cross, offsets = campaign_level(profile_reml(noises, ratios, groups)[1], noises, groups)
    return covariance.absolute_of(log_cross, ratios), offsets


GM_LOGIT_BOUND = 8.0
"""The REML of correlated noise keeps ``|logit st_gm_fraction|`` within this (a share between
0.03 % and 99.97 %): beyond it either part is negligible, and the profile is flat."""


TAU_SCAN = 6
"""After its descent the REML of correlated noise checks this many correlation times, evenly in
``log tau`` across its bounds, each from an even split with the other ratios briefly refitted
(`SCAN_EVALUATIONS`). A descent from the residuals' correlation time can end on a plateau where the
Gauss-Markov part is negligible or as long as an offset (RepoIMU at 1 s: share 0.0003 at tau 356 s,
21.9 log-likelihood units below share 0.9997 at tau 0.98 s); where a point of the scan is better,
the descent starts again from it."""

SCAN_EVALUATIONS = 20
"""Profile evaluations per tau of the scan: the other three ratios refitted briefly, since at a
fixed split the profile of a far tau is dominated by ratios fitted to another one."""

SCAN_MARGIN = 0.5
"""A point of the scan must beat the descent's optimum by this much (log-likelihood) to restart it."""


SIMPLEX_STEPS = {"sigma_about_arcsec": 0.3, "arw_deg_sqrt_h": 0.3, "st_gm_fraction": 1.0, "st_gm_tau_s": 0.7,
                 "st_jitter_ms": 1.0}
"""The REML of correlated noise: its simplex's first step in each ratio (`covariance.ratios_of`): a factor
1.35 in the white scales' ratios, 2 in tau, e in the jitter's; 1 in the share's logit."""


def estimate_correlated_noise(lins, boresight, log_sigma0, tau0_s, groups=None, chained=None):
    """REML of ``[log sigma_cross, log sigma_about, log arw, logit st_gm_fraction, log tau_s]`` (and
    ``log sigma_t`` after them where ``log_sigma0`` holds the timing jitter's, kept above
    `covariance.JITTER_FLOOR_S`): star-tracker noise white plus first-order Gauss-Markov (`markov`), the
    filter rebuilt at each tau tried, from an even split; the simplex starts wide (a factor 1.35 in the
    ratios, 2 in tau, e in the jitter) and stops at 1 % (the posterior's grid refines it), and starts again
    from the best of a scan in tau (`TAU_SCAN`) that beats it. Tau is kept between half the star tracker's
    interval and ten times the longest maneuver. ``chained`` (`segments.Chains`): the
    error runs on between consecutive maneuvers of a group; None: the maneuvers apart. Returns the
    scales and the groups' offsets (`estimate_noise`)."""
    log_sigma0 = np.asarray(log_sigma0, dtype=float)
    jitter = covariance.position(log_sigma0, covariance.JITTER_SCALE) is not None
    white0 = covariance.ratios_of(log_sigma0)
    step = st_step(lins)
    longest = max(float(np.sum(lin.gm_steps)) for lin in lins)
    log_tau_bounds = np.log([0.5 * step, 10.0 * longest])
    chained = segments.Chains.apart(len(lins)) if chained is None else chained
    groups = chained.groups(groups)
    layout = covariance.noise_scales(True, jitter)[1:]  # the ratios'
    share, tau = layout.index(covariance.GM_FRACTION_SCALE), layout.index(covariance.GM_TAU_SCALE)
    given = {**dict(zip(covariance.scales_of(log_sigma0)[1:], white0)), covariance.GM_FRACTION_SCALE: 0.0,
             covariance.GM_TAU_SCALE: np.clip(np.log(tau0_s), *log_tau_bounds)}
    start = np.array([given[s] for s in layout])
    k, floor = _jitter_floor(start, log_sigma0[0])
    widths = np.array([SIMPLEX_STEPS[s.key] for s in layout])

    def structures(tau_s):
        return chained.noises(lins, boresight, tau_s, jitter)

    def negative(r):
        if abs(r[share]) > GM_LOGIT_BOUND or not log_tau_bounds[0] <= r[tau] <= log_tau_bounds[1]:
            return np.inf
        # one noise structure at a time: each is built, summed into the statistics and dropped (a
        # list of them all held 5 GB at 100x the default campaign; the same sums)
        return finite_profile(structures(float(np.exp(r[tau]))), _floored(r, k, floor), groups)

    def descend(x0):
        simplex = x0 + np.vstack([np.zeros(len(x0)), np.diag(widths)])
        return minimize(negative, x0, method="Nelder-Mead",
                        options={"xatol": 1e-2, "fatol": 1e-2, "initial_simplex": simplex})

    def at_tau(log_tau):
        """The other ratios briefly refitted at one tau, from the descent's and an even split."""
        others = np.delete(np.arange(len(layout)), tau)
        x0 = opt.x[others]
        x0[share] = 0.0
        simplex = x0 + np.vstack([np.zeros(len(x0)), np.diag(widths[others])])
        sub = minimize(lambda q: negative(np.insert(q, tau, log_tau)), simplex[0], method="Nelder-Mead",
                       options={"maxfev": SCAN_EVALUATIONS, "initial_simplex": simplex})
        return sub.fun, np.insert(sub.x, tau, log_tau)

    opt = descend(start)
    best_value, best = min((at_tau(t) for t in np.linspace(*log_tau_bounds, TAU_SCAN)), key=lambda v: v[0])
    if best_value < opt.fun - SCAN_MARGIN:  # the descent from ``best`` ends no worse than it
        opt = descend(best)
    ratios = _floored(opt.x, k, floor)
    noises = list(structures(float(np.exp(ratios[tau]))))
    log_cross, offsets = campaign_level(profile_reml(noises, ratios, groups)[1], noises, groups)
    return covariance.absolute_of(log_cross, ratios), offsets
