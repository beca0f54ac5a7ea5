"""The fleet summary gathers each campaign's reviewed model, whichever model that is."""

import matplotlib
import pandas as pd

from gyrocal.report import fleet

matplotlib.use("Agg")


def table(labels):
    return pd.DataFrame({"channel": ["dtg1_roll"] * len(labels), "parameter": labels, "unit": ["ppm"] * len(labels),
                         "mean": 1.0, "sd": 1.0, "ci95_low": -1.0, "ci95_high": 3.0})


def test_campaigns_reviewed_under_different_models_share_one_summary_and_figure():
    verdicts = [{"campaign": "a", "model": "bias_drift", "verdict": "GO"},
                {"campaign": "b", "model": "baseline", "verdict": "NO-GO"}]
    calibrations = {("a", "bias_drift"): table(["sf_pos", "bias_drift"]), ("b", "baseline"): table(["sf_pos"])}
    summary = fleet.summary(verdicts, calibrations)
    assert summary[["campaign", "model", "verdict", "parameter"]].values.tolist() == [
        ["a", "bias_drift", "GO", "sf_pos"], ["a", "bias_drift", "GO", "bias_drift"], ["b", "baseline", "NO-GO", "sf_pos"]]
    figure = fleet.figure(summary)
    assert [ax.get_title() for ax in figure.axes if ax.axison] == ["dtg1_roll.bias_drift (ppm)", "dtg1_roll.sf_pos (ppm)"]
