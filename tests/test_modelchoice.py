"""Which model is reviewed, and when the answer hangs on the model (gyrocal.criticism.modelchoice)."""

import numpy as np
import pandas as pd
import pytest

from gyrocal.criticism import modelchoice

LABELS = ["dtg2_yaw.sf_pos", "dtg2_yaw.sf_neg"]


def comparison(rows):
    """A comparison table from (model, effects, misfit, pointwise leave-one-maneuver-out)."""
    table = pd.DataFrame([{"model": m, "effects": e, "misfit": f, "elpd_lomo": float(np.sum(p)),
                           "lomo_pointwise": np.asarray(p, dtype=float)} for m, e, f, p in rows])
    return modelchoice.classify(table, reject_se=4.0)


def calibration(sf_pos, sf_neg, sd=10.0):
    mean = np.array([sf_pos, sf_neg], dtype=float)
    return pd.DataFrame({"channel": ["dtg2_yaw", "dtg2_yaw"], "parameter": ["sf_pos", "sf_neg"],
                         "unit": ["ppm", "ppm"], "mean": mean, "sd": [sd, sd],
                         "ci95_low": mean - 1.96 * sd, "ci95_high": mean + 1.96 * sd})


LIMITS = {"ppm": 200.0}


BASE = "scale_factor+misalignment+bias"


def test_a_misfitting_variant_and_one_loo_clearly_rejects_are_not_plausible():
    table = comparison([("baseline", BASE, True, [0, 0, 0, 0]),
                        ("drift", BASE + "+bias_drift", False, [30, 31, 29, 30]),
                        ("latency", BASE + "+st_latency", False, [0.5, 0.2, 0.1, -0.3])])
    assert list(table["plausible"]) == [False, True, False]
    assert table.loc[0, "rejected_by"].startswith("misfit; leave-one-maneuver-out: elpd -120.0 below drift")
    assert table.loc[2, "rejected_by"].startswith("leave-one-maneuver-out: elpd -119.5 below drift")
    assert modelchoice.reviewed_model(table) == "drift"


def test_a_difference_within_the_paired_se_rejects_nothing():
    """-6 nats with a paired se of about 10: not clearly worse."""
    table = comparison([("a", BASE, False, [10, -10, 10, -10]), ("b", BASE + "+bias_drift", False, [4, -4, 4, -10])])
    assert table["plausible"].all()
    assert modelchoice.reviewed_model(table) == "a"


def block_table(misfit_b: bool) -> pd.DataFrame:
    """b trails a by 12 nats over six maneuvers (1.3 se) and by 20 over a hundred blocks (20 se)."""
    blocks_b = np.full(100, -0.2) + 0.01 * np.cos(np.arange(100))
    return pd.DataFrame([{"model": "a", "effects": BASE, "misfit": False, "elpd_lomo": 0.0,
                          "lomo_pointwise": np.zeros(6), "loo_pointwise": np.zeros(100)},
                         {"model": "b", "effects": BASE, "misfit": misfit_b, "elpd_lomo": -12.0,
                          "lomo_pointwise": np.array([-10.0, -2.0, 0.0, 0.0, 0.0, 0.0]), "loo_pointwise": blocks_b}])


def test_the_blocks_confirm_a_misfit_but_do_not_reject_a_variant_that_fits():
    """A small, sharp block deficit is what parameters the data cannot inform cost a variant
    that fits: rejecting it would hide the model uncertainty the review must show."""
    fits = modelchoice.classify(block_table(misfit_b=False), reject_se=4.0)
    assert fits["plausible"].all() and not fits["loo_rejected"].any()
    misfits = modelchoice.classify(block_table(misfit_b=True), reject_se=4.0)
    assert list(misfits["loo_rejected"]) == [False, True]
    assert misfits.loc[1, "rejected_by"] == "misfit; block PSIS-LOO: elpd -20.0 below a (20.0 se)"


def test_with_no_plausible_variant_the_best_elpd_is_reviewed_and_the_check_fails():
    table = comparison([("baseline", BASE, True, [0, 0, 0]), ("drift", BASE + "+bias_drift", True, [5, 5, 5])])
    assert modelchoice.reviewed_model(table) == "drift"
    check = modelchoice.plausibility_check(table)
    assert not check.passed and "baseline (misfit" in check.why and "drift (misfit)" in check.why


def test_plausible_variants_that_disagree_beyond_their_intervals_give_no_go_naming_both_and_the_term():
    table = comparison([("drift", BASE + "+bias_drift", False, [1, 1, 1]),
                        ("latency", BASE + "+st_latency", False, [1, 1.2, 0.9])])
    calibrations = {"drift": calibration(-1712.0, -1000.0), "latency": calibration(-112.0, -1010.0)}
    check = modelchoice.sensitivity_check(table, calibrations, LABELS, 3.0, LIMITS)
    assert not check.passed
    assert check.why.startswith("the data cannot tell drift from latency: dtg2_yaw.sf_pos differs by 1,600.0 ppm "
                                   "(113.1 sd). What would separate them:")
    assert "dtg2_yaw.sf_neg" not in check.why
    assert check.figure == pytest.approx(113.1, abs=0.05) and (check.threshold, check.unit) == (3.0, "sd")
    assert check.where == "dtg2_yaw.sf_pos, drift against latency" and check.action
    assert "bias_drift: longer inertial holds" in check.why and "st_latency: shorter, sharper ramps" in check.why


def test_plausible_variants_that_agree_within_their_intervals_pass():
    table = comparison([("a", BASE, False, [1, 1]), ("b", BASE + "+bias_drift", False, [1, 1])])
    check = modelchoice.sensitivity_check(table, {"a": calibration(-1712, -1000), "b": calibration(-1700, -1015)},
                                          LABELS, 3.0, LIMITS)
    assert check.passed and "agree on every channel-model term within 3.0 combined sd" in check.why


def test_a_variant_loo_rejects_cannot_block_a_go():
    table = comparison([("a", BASE, False, [9, 9, 9]), ("b", BASE + "+bias_drift", False, [-30, -30, -30])])
    check = modelchoice.sensitivity_check(table, {"a": calibration(0, 0), "b": calibration(5000, 5000)}, LABELS, 3.0,
                                          LIMITS)
    assert check.passed and "LOO rejects every variant but a" in check.why


def test_a_misfitting_variant_that_predicts_as_well_and_disagrees_blocks_a_go():
    """Its misfit says the others lack something too: the answer hangs on the model."""
    table = comparison([("a", BASE, False, [9, 9, 9]), ("b", BASE + "+bias_drift", True, [9, 10, 9])])
    assert list(table["plausible"]) == [True, False] and modelchoice.reviewed_model(table) == "a"
    check = modelchoice.sensitivity_check(table, {"a": calibration(0, 0), "b": calibration(5000, 0)}, LABELS, 3.0,
                                          LIMITS)
    assert not check.passed and check.why.startswith("the data cannot tell a from b: dtg2_yaw.sf_pos differs")


def test_a_variant_the_data_cannot_rule_out_under_which_a_term_is_unknown_blocks_a_go():
    """The means agree, but under the nonlinearity the scale factor is known only to 2000 ppm."""
    table = comparison([("baseline", BASE, False, [9, 9, 9]), ("nonlin", BASE + "+sf_nonlinearity", False, [9, 8.8, 9])])
    check = modelchoice.sensitivity_check(table, {"baseline": calibration(-1700, -1000),
                                                  "nonlin": calibration(-1650, -1000, sd=510.0)}, LABELS, 3.0, LIMITS)
    assert not check.passed
    assert check.why.startswith("the data cannot tell baseline from nonlin: dtg2_yaw.sf_pos, dtg2_yaw.sf_neg under "
                                "nonlin known only within 1,999 ppm (95 %; limit 200)")
    assert "sf_nonlinearity: a second rotation rate in each direction" in check.why


def test_stacking_weights_favour_the_better_predictor_and_split_between_equals():
    assert modelchoice.stacking_weights([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]) == pytest.approx([0.5, 0.5], abs=1e-6)
    w = modelchoice.stacking_weights([[-1.0, -1.0, -1.0, -1.0], [0.0, 0.0, 0.0, 0.0]])
    assert w[1] > 0.999
    # each model predicts half the points better: the mixture takes both
    w = modelchoice.stacking_weights([[0.0, -5.0, 0.0, -5.0], [-5.0, 0.0, -5.0, 0.0]])
    assert w == pytest.approx([0.5, 0.5], abs=1e-4)


def test_a_pair_that_both_disagrees_and_leaves_a_term_unknown_is_one_sentence_with_no_empty_clause():
    """The reviewed variant second in the table: the pair came up once from the disagreement and once
    from the width, and the second time it had nothing to say ("cannot tell a from b: .")."""
    table = comparison([("a", BASE, False, [9, 9, 9]), ("b", BASE + "+bias_drift", False, [9.5, 9.5, 9.5])])
    assert modelchoice.reviewed_model(table) == "b"
    check = modelchoice.sensitivity_check(table, {"a": calibration(5000, 0, sd=510.0), "b": calibration(0, 0)},
                                          LABELS, 3.0, LIMITS)
    assert not check.passed and ": ." not in check.why and check.why.count("cannot tell") == 1
    assert check.why.startswith("the data cannot tell a from b: dtg2_yaw.sf_pos differs by 5,000.0 ppm (9.8 sd); "
                                "dtg2_yaw.sf_pos, dtg2_yaw.sf_neg under a known only within 1,999 ppm")


def symmetric_calibration(sf, sd=10.0):
    return pd.DataFrame({"channel": ["dtg2_yaw"], "parameter": ["sf"], "unit": ["ppm"], "mean": [float(sf)],
                         "sd": [sd], "ci95_low": [sf - 1.96 * sd], "ci95_high": [sf + 1.96 * sd]})


SYMMETRIC = "scale_factor_symmetric+misalignment+bias"


def test_the_symmetric_model_is_compared_branch_by_branch_with_the_per_direction_one():
    """Its one sf is both branches: it agrees with sf_pos -1290, sf_neg -1312 and not with -1712, -1000."""
    table = comparison([("baseline", BASE, False, [9, 9, 9]), ("symmetric", SYMMETRIC, False, [9.2, 9.2, 9.2])])
    assert modelchoice.reviewed_model(table) == "symmetric"
    agree = modelchoice.sensitivity_check(table, {"baseline": calibration(-1290, -1312),
                                                  "symmetric": symmetric_calibration(-1300)}, ["dtg2_yaw.sf"], 3.0, LIMITS)
    assert agree.passed
    differ = modelchoice.sensitivity_check(table, {"baseline": calibration(-1712, -1000),
                                                   "symmetric": symmetric_calibration(-1300)}, ["dtg2_yaw.sf"], 3.0,
                                           LIMITS)
    assert not differ.passed and "dtg2_yaw.sf_pos differs by 412.0 ppm" in differ.why
    assert "scale_factor: more and longer rotations each way" in differ.why and "scale_factor_symmetric:" not in differ.why


def test_the_reason_is_one_sentence_naming_the_reviewed_variant_and_the_rule_without_elpd():
    table = comparison([("baseline", BASE, False, [9, 9, 9]), ("symmetric", SYMMETRIC, False, [9.2, 9.2, 9.2]),
                        ("drift", BASE + "+bias_drift", True, [1, 1, 1])])
    why = modelchoice.reviewed_reason(table)
    assert why == ("symmetric is reviewed: of the plausible variants (baseline, symmetric), it predicts the left-out "
                   "maneuvers best")
    assert not any(ch.isdigit() for ch in why) and why.count(". ") == 0
    one = comparison([("a", BASE, False, [9, 9]), ("b", SYMMETRIC, True, [2, 2])])
    assert modelchoice.reviewed_reason(one).startswith("a is reviewed: the only plausible variant of the 2 compared")
    none = comparison([("a", BASE, True, [1, 1]), ("b", SYMMETRIC, True, [2, 2])])
    assert modelchoice.reviewed_reason(none).startswith("b is reviewed, though no variant is plausible")


def test_the_disagreement_table_has_a_row_per_pair_and_term_and_each_advice_once():
    table = comparison([("drift", BASE + "+bias_drift", False, [1, 1, 1]),
                        ("latency", BASE + "+st_latency", False, [1, 1.2, 0.9]),
                        ("nonlin", BASE + "+sf_nonlinearity", False, [1, 1.1, 1])])
    calibrations = {"drift": calibration(-1712.0, -1000.0), "latency": calibration(-112.0, -1010.0),
                    "nonlin": calibration(-1712.0, -1900.0)}
    rows = modelchoice.disagreement_table(table, calibrations, LABELS, 3.0, LIMITS)
    assert list(rows.columns) == ["models", "term", "difference", "difference (sd)", "what would separate them"]
    pairs = list(zip(rows["models"], rows["term"]))
    assert len(pairs) == len(set(pairs)) == 4   # latency against both on sf_pos, nonlin against both on sf_neg
    assert rows["difference (sd)"].is_monotonic_decreasing and rows["difference (sd)"].min() > 3.0
    advice = rows["what would separate them"]
    assert advice.iloc[0] and advice[advice != ""].is_unique and (advice != "").sum() == 3
    agree = modelchoice.disagreement_table(table, {m: calibration(-1712.0, -1000.0) for m in calibrations}, LABELS,
                                           3.0, LIMITS)
    assert agree.empty


def test_terms_too_wide_under_a_variant_are_one_row_per_unit_not_one_per_term():
    """Twelve terms too wide under one variant were twelve rows; now one per unit, with the count and the range."""
    labels = [f"dtg{i}_yaw.{p}" for i in (1, 2, 3) for p in ("sf_pos", "sf_neg", "mis_roll", "mis_pitch")]
    wide = {f"{label}": (900.0 + 10 * k if ".sf" in label else 80.0 + k) for k, label in enumerate(labels)}

    def cal(scale):
        rows = [{"channel": lab.split(".")[0], "parameter": lab.split(".")[1],
                 "unit": "ppm" if ".sf" in lab else "arcsec", "mean": 0.0, "sd": w * scale / 3.92,
                 "ci95_low": -w * scale / 2, "ci95_high": w * scale / 2} for lab, w in wide.items()]
        return pd.DataFrame(rows)

    table = comparison([("a", BASE, False, [9, 9, 9]), ("b", BASE + "+bias_drift", False, [9, 8.9, 9])])
    rows = modelchoice.disagreement_table(table, {"a": cal(0.01), "b": cal(1.0)}, labels, 3.0,
                                          {"ppm": 200.0, "arcsec": 30.0})
    assert list(rows["term"]) == ["6 terms: dtg1_yaw.sf_pos, dtg1_yaw.sf_neg, dtg2_yaw.sf_pos, ...",
                                  "6 terms: dtg1_yaw.mis_roll, dtg1_yaw.mis_pitch, dtg2_yaw.mis_roll, ..."]
    assert rows["difference"].iloc[0] == "under b known only within 900-990 ppm (95 %; limit 200)"
    assert rows["difference"].iloc[1] == "under b known only within 82-91 arcsec (95 %; limit 30)"
    assert list(rows["what would separate them"] != "") == [True, False]
