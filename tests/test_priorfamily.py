"""The effects' Student-t prior (gyrocal.model.priorfamily) against scipy."""

import numpy as np
from scipy.stats import norm, t

from gyrocal.model import priorfamily


def test_log_density_matches_scipy_up_to_a_constant():
    z = np.array([[-3.0, 0.0], [0.5, 1.0], [4.0, -2.0], [0.0, 0.0]])
    dof = np.array([4.0, np.inf])
    ours = priorfamily.log_density(z, dof)
    ref = t.logpdf(z[:, 0], 4.0) + norm.logpdf(z[:, 1])
    assert np.allclose(ours - ours[-1], ref - ref[-1])


def test_tail_probability_is_the_family_s():
    assert np.isclose(priorfamily.tail_probability(3.0, 4.0), 2 * t.sf(3.0, 4.0))
    assert np.isclose(priorfamily.tail_probability(3.0, np.inf), 2 * norm.sf(3.0))


def test_proposal_sd_normal_unchanged_and_t_wide_far_out():
    sd = np.array([1.0, 1.0])
    out = priorfamily.proposal_sd(sd, np.array([4.0, 4.0]), np.array([4.0, np.inf]))
    assert out[1] == 1.0 and out[0] > 1.9
