"""The noise check judged with its uncertainty (issue 43, item 1): a fitted noise scale is a misfit
only where its 95 % interval excludes the stated value and lies wholly outside the tolerated band."""

import numpy as np
import pytest

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


def _angle_clock_posterior(cross_total, about_total, share):
    from gyrocal.inference.noise.parts import split_parts

    sampled = dict(STATED, sigma_cross_arcsec=cross_total, sigma_about_arcsec=about_total, st_gm_fraction=share)
    return {**sampled, **{k: float(v) for k, v in split_parts(sampled).items()}}


def test_a_noise_stated_at_rest_judges_the_white_part():
    """A reference error of 1000 arcsec across and 4000 about, 99.99 % of it Gauss-Markov: its white parts
    are 10 and 40 arcsec, the noise a recording at rest shows and campaign.yaml states (sigma_is: white), so
    the noise checks pass; stated as the total, as a data sheet states it, the totals are 100 times it."""
    posterior = _angle_clock_posterior(1000.0, 4000.0, 0.9999)
    assert posterior["st_white_cross_arcsec"] == pytest.approx(10.0)
    assert posterior["st_gm_cross_arcsec"] == pytest.approx(1000.0, rel=1e-4)
    on_angle = misfit_findings(3.0, 3.0, WHITE, RANKING, posterior, dict(STATED, sigma_is="white"), CFG)
    on_time = misfit_findings(3.0, 3.0, WHITE, RANKING, posterior, dict(STATED, sigma_is="total"), CFG)
    judged = {f.check: f for f in on_angle}
    assert judged["noise:sigma_cross_arcsec"].passed and judged["noise:sigma_about_arcsec"].passed
    assert judged["noise:sigma_cross_arcsec"].why.startswith("the data ask for sigma_cross_arcsec's white part "
                                                             "(st_white_cross_arcsec; ")
    assert not any(f.passed for f in on_time if f.check in ("noise:sigma_cross_arcsec", "noise:sigma_about_arcsec"))


def test_with_a_noise_stated_at_rest_the_level_counts_the_fitted_gauss_markov_part():
    """What the noise predicts for the residual: the stated white part and the walk, plus, where the stated
    noise is the white part, the Gauss-Markov part's stationary variance averaged over the axes
    ((2 x 300^2 + 600^2) / 3)."""
    from types import SimpleNamespace

    from gyrocal.criticism.diagnostics import motion_part_arcsec, noise_rms_arcsec

    stated = dict(STATED, boresight_body=[0.0, 0.0, 1.0], arw_deg_sqrt_h=1e-9)
    posterior = _angle_clock_posterior(300.0 / np.sqrt(0.99), 600.0 / np.sqrt(0.99), 0.99)
    maneuvers = [SimpleNamespace(st_time=np.array([0.0, 100.0]), gyro_time=np.array([0.0, 100.0]))]
    assert motion_part_arcsec(posterior, STATED) is None
    motion = motion_part_arcsec(posterior, dict(stated, sigma_is="white"))
    assert motion == pytest.approx([300.0, 600.0])
    white_only = noise_rms_arcsec(maneuvers, stated)
    assert white_only == pytest.approx(np.sqrt((2 * 10.0**2 + 40.0**2) / 3))
    assert noise_rms_arcsec(maneuvers, stated, motion) == pytest.approx(
        np.sqrt(white_only**2 + (2 * 300.0**2 + 600.0**2) / 3))


def test_the_noise_prior_holds_the_part_the_noise_is_stated_for():
    """The log-normal prior about the stated 10 arcsec: stated at rest (sigma_is: white) it peaks where the
    white part, sigma sqrt(1 - share), is 10, whatever the share; stated as the total, where the total is."""
    from gyrocal.inference.noise.covariance import log_sigma_of
    from gyrocal.inference.noise.parts import judged_log_sigma
    from gyrocal.inference.sampling.priors import Priors

    stated = dict(STATED, boresight_body=[0.0, 0.0, 1.0])
    center = log_sigma_of(stated, correlated=True)
    share = 0.96
    total = np.log(np.array([10.0, 40.0]) * np.pi / 648000.0) - 0.5 * np.log(1.0 - share)
    log_sigma = np.concatenate([total, center[2:3], [np.log(share / (1.0 - share))], center[4:]])
    on_angle = dict(stated, sigma_is="white")
    assert judged_log_sigma(log_sigma, on_angle)[:2] == pytest.approx(center[:2])
    assert judged_log_sigma(log_sigma, stated) == pytest.approx(log_sigma)
    priors = {k: Priors(np.zeros(1), np.ones(1), np.ones(1), center, np.ones(5), None, s) for k, s in
              (("angle", on_angle), ("time", stated))}
    share_prior = -0.5 * ((log_sigma[3] - center[3]) / 1.0) ** 2
    assert priors["angle"].noise_log_density(log_sigma[None])[0] == pytest.approx(share_prior)
    assert priors["time"].noise_log_density(log_sigma[None])[0] == pytest.approx(share_prior - np.log(5.0) ** 2)


def test_the_white_and_gauss_markov_parts_are_summarised_draw_by_draw():
    """The parts' mean and 95 % interval are those of sigma sqrt(1 - share) and sigma sqrt(share) over the
    draws, not products of the scales' summaries: their correlation is kept."""
    import arviz as az

    from gyrocal.inference.sampling.inferencedata import noise_split_summary

    rng = np.random.default_rng(5)
    sigma = rng.lognormal(np.log(100.0), 0.1, (4, 500))
    share = rng.uniform(0.8, 0.99, (4, 500))
    idata = az.from_dict(posterior={"sigma_cross_arcsec": sigma, "sigma_about_arcsec": 2 * sigma, "st_gm_fraction": share})
    table = noise_split_summary(idata, idata, {"r_hat_max": 1.01, "ess_bulk_min": 100}).set_index("label")
    parts = {"st_white_cross_arcsec": sigma * np.sqrt(1 - share), "st_gm_about_arcsec": 2 * sigma * np.sqrt(share)}
    for label, draws in parts.items():
        row = table.loc[f"noise.{label}"]
        assert row["mean"] == pytest.approx(draws.mean())
        assert (row["ci95_low"], row["ci95_high"]) == pytest.approx(tuple(np.quantile(draws, [0.025, 0.975])))
    no_share = az.from_dict(posterior={"sigma_cross_arcsec": sigma, "sigma_about_arcsec": sigma})
    assert noise_split_summary(no_share, no_share, {"r_hat_max": 1.01, "ess_bulk_min": 100}) is None


def test_a_walk_that_reml_gives_to_the_correlated_part_is_left_to_the_prior():
    """REML may put a gyro walk 1e-5 of the stated where a slow Gauss-Markov part takes its variance (BROAD's
    fast trial): no misfit, so sampling goes on. The same collapse in a white model (correlated residuals),
    every scale below (a campaign stated far noisier than its data), one far above, or a reference scale far
    below still stop."""
    from gyrocal.inference.sampling.refusals import taken_by_correlated_part

    ratio = np.array([0.9, 1.1, 1e-5])
    off = noise_beyond(ratio, ratio, NOISE_PLAUSIBLE)
    assert taken_by_correlated_part(True, ratio, off)
    assert not taken_by_correlated_part(False, ratio, off)
    assert not taken_by_correlated_part(True, np.array([1e-4, 1e-4, 1e-5]), np.array([True, True, True]))
    assert not taken_by_correlated_part(True, np.array([2000.0, 1.0, 1e-5]), np.array([True, False, True]))
    assert not taken_by_correlated_part(True, np.array([0.9, 1.1, 0.5]), np.array([False, False, False]))
    assert not taken_by_correlated_part(True, np.array([1e-5, 1.1, 0.9]), np.array([True, False, False]))  # not the walk
