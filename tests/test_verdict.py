"""The GO/NO-GO verdict as a pure function of findings, and its checks' figures (gyrocal.criticism.verdict)."""

import pandas as pd
import pytest

from gyrocal.criticism import modelchoice, verdict
from gyrocal.finding import Finding, Status
from gyrocal.model.channels import Channel
from gyrocal.model.spec import baseline

SPEC = baseline((Channel("dtg1_roll", 1, "roll"),))
"""One roll channel: sf_pos, sf_neg (ppm), mis_pitch, mis_yaw (arcsec)."""
CFG = {"convergence": {"r_hat_max": 1.01, "ess_bulk_min": 400},
       "report": {"max_ci_width_ppm": 200, "max_ci_width_arcsec": 30,
                  "physical_bound_ppm": 20000, "physical_bound_arcsec": 3600},
       "model_choice": {"agree_sd": 3.0}, "diagnostics": {"structure_log10_p_min": -6.0}}
SAMPLER = {"converged": True}


def calibration(mean=(-1700.0, -1000.0, 20.0, -5.0), width=(100.0, 100.0, 25.0, 10.0), r_hat=1.001):
    """A ``calibration.csv`` of the one channel: each term's mean and 95 % interval width."""
    mean, width = pd.Series(mean, dtype=float), pd.Series(width, dtype=float)
    return pd.DataFrame({"channel": "dtg1_roll", "parameter": [p.name for p in SPEC.parameters],
                         "unit": SPEC.units, "point": mean, "mean": mean, "sd": width / 3.92,
                         "ci95_low": mean - width / 2, "ci95_high": mean + width / 2,
                         "r_hat": r_hat, "ess_bulk": 1000.0, "prior_only": False})


def effect_table(before=(100.0, 50.0), after=(10.0, 40.0)):
    return pd.DataFrame({"maneuver": ["roll_pos", "roll_neg"], "set": "dtg1_roll", "in loop": True,
                         "before norm": before, "after norm": after})


def test_one_failing_finding_makes_no_go_and_its_why_is_recorded():
    findings = [Finding.judged("converged", True, "fine"),
                Finding.judged("no misfit", False, "misfit: level: too high", figure=1.4, threshold=1.1),
                Finding("mounting", Status.WARN, "estimated from the data")]
    doc = verdict.verdict("mom", "baseline", findings)
    assert doc == {"campaign": "mom", "model": "baseline", "verdict": "NO-GO",
                   "checks": [{"check": "converged", "passed": True, "why": "fine"},
                              {"check": "no misfit", "passed": False, "why": "misfit: level: too high"},
                              {"check": "mounting", "passed": True, "why": "estimated from the data"}]}


def test_all_passing_findings_make_go_whatever_their_figures_say():
    """The verdict reads each finding's judgement, nothing else: the same findings, the same verdict."""
    findings = (Finding.judged("a", True, "fine", figure=5.0, threshold=1.0), Finding.judged("b", True, "fine too"))
    assert verdict.verdict("c", "m", findings)["verdict"] == "GO"
    assert verdict.verdict("c", "m", findings) == verdict.verdict("c", "m", list(findings))


def test_the_widest_interval_relative_to_its_limit_is_the_figure():
    check = verdict.interval_check(calibration(), SPEC, CFG["report"])
    assert check.passed and (check.figure, check.threshold, check.unit) == (25.0, 30.0, "arcsec")
    assert check.where == "dtg1_roll.mis_pitch" and not check.action
    check = verdict.interval_check(calibration(width=(250.0, 100.0, 25.0, 10.0)), SPEC, CFG["report"])
    assert not check.passed and (check.figure, check.threshold, check.unit) == (250.0, 200.0, "ppm")
    assert check.why == "too wide: dtg1_roll.sf_pos (250.0 ppm)" and check.action


def test_a_rate_dependent_scale_factor_is_judged_at_the_campaigns_rates_as_uplinked():
    """Intercepts 2000 ppm wide, as one rate leaves them, pass where the scale factors at the flown
    rates are 120 ppm wide; a flown interval over the limit fails, named with its width."""
    wide = calibration(width=(2000.0, 2000.0, 25.0, 10.0))
    flown = pd.DataFrame({"channel": "dtg1_roll", "parameter": ["sf_pos", "sf_neg"], "unit": "ppm",
                          "mean": [10.0, 20.0], "sd": [30.6, 30.6], "ci95_low": [-50.0, -40.0], "ci95_high": [70.0, 80.0]})
    assert not verdict.interval_check(wide, SPEC, CFG["report"]).passed
    check = verdict.interval_check(wide, SPEC, CFG["report"], flown)
    assert check.passed and "at the campaign's rates" in check.why
    assert (check.figure, check.where) == (25.0, "dtg1_roll.mis_pitch")
    check = verdict.interval_check(wide, SPEC, CFG["report"], flown.assign(ci95_high=[70.0, 230.0]))
    assert not check.passed and check.why.endswith("dtg1_roll.sf_neg (270.0 ppm)")
    assert verdict.interval_check(wide, SPEC, CFG["report"], flown.iloc[:0]).passed is False


def test_convergence_and_bounds_name_their_worst_term_against_the_threshold():
    table = calibration(mean=(-25000.0, -1000.0, 20.0, -5.0))
    table.loc[2, "r_hat"] = 1.02
    converged = verdict.convergence_check(table, SPEC, SAMPLER, CFG["convergence"])
    assert not converged.passed and (converged.figure, converged.threshold) == (1.02, 1.01)
    assert converged.where == "dtg1_roll.mis_pitch" and "sampler.max_steps" in converged.action
    bounds = verdict.bounds_check(table, SPEC, verdict.physical_bounds(CFG["report"], None))
    assert not bounds.passed and (bounds.figure, bounds.threshold, bounds.unit) == (25000.0, 20000.0, "ppm")
    assert bounds.why == "outside: dtg1_roll.sf_pos = -25000 ppm"


def test_the_physical_bounds_are_the_campaigns_sensor_class_unless_the_config_sets_them():
    """A MEMS triad's 3 % scale factor is physical (its class's bound is 5 %), a DTG's is not (2 %)."""
    table = calibration(mean=(-30000.0, -1000.0, 20.0, -5.0))
    unset = {"physical_bound_ppm": None, "physical_bound_arcsec": None}
    assert verdict.physical_bounds(unset, None) == {"ppm": 20000.0, "arcsec": 3600.0}
    assert verdict.physical_bounds(unset, "mems") == {"ppm": 50000.0, "arcsec": 3600.0}
    dtg = verdict.bounds_check(table, SPEC, verdict.physical_bounds(unset, "dtg"))
    assert not dtg.passed and (dtg.figure, dtg.threshold) == (30000.0, 20000.0)
    mems = verdict.bounds_check(table, SPEC, verdict.physical_bounds(unset, "mems"))
    assert mems.passed and (mems.figure, mems.threshold) == (30000.0, 50000.0)
    assert mems.why == "every estimate is within 50000 ppm / 3600 arcsec"
    rlg = verdict.bounds_check(calibration(mean=(-6000.0, -1000.0, 20.0, -5.0)), SPEC, verdict.physical_bounds(unset, "rlg"))
    assert not rlg.passed and rlg.threshold == 5000.0
    stated = verdict.bounds_check(table, SPEC, verdict.physical_bounds({**unset, "physical_bound_ppm": 25000}, "mems"))
    assert not stated.passed and stated.threshold == 25000.0


def test_the_correction_check_judges_the_worst_ratio_of_the_error_after_to_before():
    check = verdict.correction_check(effect_table())
    assert check.passed and check.figure == pytest.approx(0.8) and check.threshold == 1.0
    assert check.where == "roll_neg with dtg1_roll"
    check = verdict.correction_check(effect_table(after=(10.0, 60.0)))
    assert not check.passed and check.figure == pytest.approx(1.2)
    assert check.why == "not reduced on: roll_neg with dtg1_roll (50.0 -> 60.0 arcsec)"


def test_a_prior_only_term_fails_naming_it_and_its_channel():
    spec = SPEC.with_prior_only({"dtg1_roll.sf_neg": "no -roll maneuver"})
    check = verdict.informed_check(spec)
    assert not check.passed and check.where == "dtg1_roll"
    assert check.why == ("prior-only (the posterior is the prior): dtg1_roll.sf_neg (no -roll maneuver). "
                         "No correction for dtg1_roll")


def test_every_check_in_the_order_of_verdict_json():
    comparison = pd.DataFrame({"model": ["baseline"], "effects": ["scale_factor+misalignment+bias"],
                               "plausible": [True], "loo_rejected": [False], "rejected_by": [float("nan")],
                               "elpd_lomo": [0.0]})
    diagnostics = {"misfit": False, "checks": [{"check": "level", "passed": True, "why": "ok"}], "ranking": []}
    findings = verdict.checks("baseline", {"baseline": calibration()}, SPEC, SAMPLER, diagnostics, comparison,
                              effect_table(), CFG)
    assert [f.check for f in findings] == [
        "converged", "no misfit", "every parameter informed by the data", "intervals narrow enough",
        "within physical bounds", "correction reduces the error", "a plausible model",
        "the answer does not hang on the model"]
    assert verdict.verdict("mom", "baseline", findings)["verdict"] == "GO"
    assert modelchoice.typed(comparison)["rejected_by"].iloc[0] == ""


def misfit_diagnostics(log10_ps):
    names = ["bias_drift", "rate_sign", "st_latency", "acceleration"]
    return {"misfit": True, "checks": [{"check": "level", "passed": False, "why": "residual RMS too high"}],
            "ranking": [{"kind": "effect", "name": n, "log10_p": p} for n, p in zip(names, log10_ps)]}


def test_an_explanation_is_called_best_only_where_its_test_is_significant():
    significant = verdict.misfit_check(misfit_diagnostics([-9.0, -2.0]), -6.0)
    assert "Best explanation: effect bias_drift (log10 p = -9.0, significant below -6)" in significant.why
    assert significant.action == "add a variant with bias_drift (models:)"
    weak = verdict.misfit_check(misfit_diagnostics([-3.2, -2.1, -1.0, -0.5]), -6.0)
    assert "best" not in weak.why.lower() and "bias_drift (models:)" not in weak.action
    assert weak.why.endswith("No effect or signature explains the misfit significantly (log10 p below -6); the "
                             "top-ranked: effect bias_drift (log10 p = -3.2), effect rate_sign (log10 p = -2.1), "
                             "effect st_latency (log10 p = -1.0)")


def test_a_gauss_markov_model_whose_misfit_the_jitter_explains_best_is_advised_to_add_it():
    """The timing jitter joins correlated reference noise (their white parts filter alike, `markov`): the
    advice is the same with st_correlated_noise in the model as without it."""
    diagnostics = misfit_diagnostics([-9.0])
    diagnostics["ranking"][0]["name"] = "st_jitter"
    for present in (["st_correlated_noise"], []):
        diagnostics["effects"] = ["scale_factor", "misalignment", "bias", *present]
        check = verdict.misfit_check(diagnostics, -6.0)
        assert check.why.endswith("Best explanation: effect st_jitter (log10 p = -9.0, significant below -6)")
        assert check.action == "add a variant with st_jitter (models:)"
