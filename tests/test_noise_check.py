"""The noise check judged with its uncertainty (issue 43, item 1): a fitted noise scale is a misfit
only where its 95 % interval excludes the stated value and lies wholly outside the tolerated band."""

import numpy as np

from gyrocal.criticism.diagnostics import misfit_findings
from gyrocal.inference.sampling.refusals import NOISE_PLAUSIBLE, noise_beyond

CFG = {"rms_ratio_max": 1.1, "noise_ratio_max": 1.25, "whiteness_z_max": 5.0, "structure_log10_p_min": -6.0}
STATED = {"sigma_cross_arcsec": 10.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003}
WHITE = {"lag1": 0.0, "z": 0.0}
RANKING = [{"kind": "effect", "name": "bias_drift", "chi2_drop": 1.0, "df": 3, "log10_p": -0.2}]


def _noise_check(arw_ratio, interval=None):
    fitted = dict(STATED, arw_deg_sqrt_h=0.003 * arw_ratio)
    ci = None if interval is None else {"arw_deg_sqrt_h": [0.003 * interval[0], 0.003 * interval[1]]}
    findings = misfit_findings(3.0, 3.0, WHITE, RANKING, fitted, STATED, CFG, ci)
    return next(f for f in findings if f.check == "noise:arw_deg_sqrt_h")


def test_an_arw_of_079_with_sd_008_of_the_stated_is_not_a_misfit():
    check = _noise_check(0.79, (0.79 - 1.96 * 0.08, 0.79 + 1.96 * 0.08))
    assert check.passed
    assert "95 % interval 0.63 to 0.95" in check.why


def test_an_arw_whose_interval_lies_below_the_band_is_a_misfit():
    check = _noise_check(0.70, (0.66, 0.74))
    assert not check.passed
    assert np.isclose(check.figure, 1 / 0.74)


def test_an_interval_that_holds_the_stated_value_passes_however_far_its_point():
    assert _noise_check(1.6, (0.95, 2.6)).passed
    assert not _noise_check(1.6, (1.3, 1.9)).passed


def test_without_an_interval_the_point_is_judged_against_the_band():
    assert _noise_check(0.81).passed
    assert not _noise_check(0.79).passed


def test_the_refusal_before_sampling_uses_the_same_rule_at_a_factor_of_a_thousand():
    ratios = np.array([1.0 / 2000, 0.5, 999.0, 1001.0])
    assert noise_beyond(ratios, ratios, NOISE_PLAUSIBLE).tolist() == [True, False, False, True]
