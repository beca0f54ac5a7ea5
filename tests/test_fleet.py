"""A fleet: its campaigns run as independent jobs with the single run's numbers, and the summary
gathers each campaign's reviewed model, whichever model that is."""

import json
import shutil
import subprocess
from pathlib import Path

import matplotlib
import pandas as pd
from test_workflow import SHORT_CHAINS, SNAKEMAKE

from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.run import calibrate_campaign
from gyrocal.report import fleet

matplotlib.use("Agg")

NAMES = ("sat_a", "sat_b")
"""Two campaigns of one fleet (the Slurm test, test_slurm.py, runs three)."""


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


def test_a_fleet_runs_as_independent_campaigns_with_the_single_runs_numbers(tiny, short_chains, tmp_path):
    """Through Snakemake, and against the same campaign calibrated by the step functions in this
    process (`gyrocal.pipeline.run`): the rules and the library give the same numbers (the baseline
    alone, the one model compared: the variants add time, not wiring)."""
    fleet_dir = tmp_path / "fleet"
    for name in NAMES:
        shutil.copytree(tiny[0], fleet_dir / name)
        meta = fleet_dir / name / "campaign.yaml"
        meta.write_text(meta.read_text().replace("name: tiny", f"name: {name}"))
    work = tmp_path / "work"
    run = subprocess.run(SNAKEMAKE + ["--cores", "2", "-d", str(work), "--configfile", SHORT_CHAINS,
                                      "--config", f"campaigns={fleet_dir}", "run_models=[baseline]"],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    single = CampaignPaths.under(tmp_path / "single")
    calibrate_campaign(tiny[0], single, short_chains, ["baseline"])
    for name in NAMES:
        assert (work / "results" / name / "baseline/calibration.csv").read_text() == \
            Path(single.model("baseline").calibration).read_text()
        assert json.loads((work / "results" / name / "verdict.json").read_text())["verdict"] in ("GO", "NO-GO")
    summary = pd.read_csv(work / "results/fleet/summary.csv")
    assert sorted(summary["campaign"].unique()) == list(NAMES)
    assert len(summary) >= 2 * 24 and len(summary) % 2 == 0
    assert (work / "results/fleet/summary.png").read_bytes()[:4] == b"\x89PNG"
