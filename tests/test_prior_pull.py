"""How far the drift's Student-t prior pulls a likelihood far out in it (issue 43), by quadrature of
the exact posterior of one parameter: the likelihood normal, the prior the one `BiasDrift` declares
(`gyrocal.model.priorfamily`). Where the likelihood is narrow against the prior's scale the data win;
where it is half the scale or wider, the pull is smaller than a normal prior's but not nil."""

import numpy as np
from scipy.stats import norm

from gyrocal.model import priorfamily
from gyrocal.model.effects import BiasDrift

DRIFT = BiasDrift.parameters[0]


def posterior(lik_mean, lik_sd, dof):
    """Mean and central 95 % interval of the drift (deg/h/h) given a normal likelihood and the prior
    of scale ``DRIFT.prior_sd`` in the family of ``dof`` degrees of freedom, on a fine grid."""
    theta = np.linspace(-8.0, 8.0, 160001)
    logp = norm.logpdf(lik_mean, theta, lik_sd) + priorfamily.log_density((theta / DRIFT.prior_sd)[:, None], [dof])
    p = np.exp(logp - logp.max())
    p /= p.sum()
    cdf = np.cumsum(p)
    return float(theta @ p), theta[np.searchsorted(cdf, 0.025)], theta[np.searchsorted(cdf, 0.975)]


def test_the_issue_s_ramp_is_covered_under_the_drift_prior_and_was_missed_under_a_normal_one():
    # issue 43: likelihood -2.10 +- 0.35 deg/h/h against a true -2.19 (by symmetry, +)
    _, lo, hi = posterior(2.10, 0.35, DRIFT.prior_dof)
    _, lo_n, hi_n = posterior(2.10, 0.35, np.inf)
    assert lo <= 2.19 <= hi and not lo_n <= 2.19 <= hi_n


def test_a_narrow_likelihood_four_scales_out_is_pulled_a_tenth_of_its_sd_a_quarter_of_a_normal_prior_s_pull():
    # 2.0 +- 0.05: 1.995 (0.10 sd); a normal prior of the same scale: 1.980 (0.40 sd)
    mean, _, _ = posterior(2.0, 0.05, DRIFT.prior_dof)
    mean_n, _, _ = posterior(2.0, 0.05, np.inf)
    assert DRIFT.prior_dof == 4.0 and DRIFT.prior_sd == 0.5
    assert (2.0 - mean) / 0.05 < 0.12 and (2.0 - mean) < 0.3 * (2.0 - mean_n)


def test_a_likelihood_half_the_scale_wide_is_still_pulled_about_half_its_sd():
    # the stated bias: 2.0 +- 0.25 (four scales out) comes out at 1.87, 0.5 of its sd toward zero,
    # where a normal prior would take it to 1.60 (1.6 sd): such intervals cover less than 95 %
    mean, lo, hi = posterior(2.0, 0.25, DRIFT.prior_dof)
    mean_n, _, _ = posterior(2.0, 0.25, np.inf)
    assert 0.4 < (2.0 - mean) / 0.25 < 0.65 and 1.5 < (2.0 - mean_n) / 0.25 < 1.7
    assert lo <= 2.0 <= hi
