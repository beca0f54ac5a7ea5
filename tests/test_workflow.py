"""The Snakemake workflow end to end, on a user's campaign directory."""

import json
import shutil
import subprocess
import sys

import pandas as pd

from conftest import ROOT

SNAKEMAKE = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile")]


def test_lint_is_clean():
    run = subprocess.run(SNAKEMAKE + ["--lint"], cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "Congratulations, your workflow is in a good condition!" in run.stdout + run.stderr


def test_user_campaign_runs_with_no_code_edit(tiny, tmp_path):
    run = subprocess.run(SNAKEMAKE + ["--cores", "2", "-d", str(tmp_path), "--config", f"telemetry={tiny[0]}"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    results = tmp_path / "results" / "tiny" / "baseline"
    table = pd.read_csv(results / "calibration.csv")
    assert len(table) == 24
    assert json.loads((results / "correction.json").read_text())["sets"]
    assert not any("WARNING" in p.read_text() for p in (tmp_path / "logs").rglob("*.log"))


def test_bad_config_value_is_refused_with_a_clear_message(tmp_path):
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-n", "-d", str(tmp_path), "--config", "seed=-3"],
                         capture_output=True, text=True)
    assert run.returncode != 0
    said = run.stdout + run.stderr
    assert "-3 is less than the minimum of 0" in said and "['seed']" in said


def test_bad_telemetry_is_refused_naming_the_file(tiny, tmp_path):
    broken = tmp_path / "broken"
    shutil.copytree(tiny[0], broken)
    (broken / "campaign.yaml").write_text((broken / "campaign.yaml").read_text().replace("direction: +", "direction: up"))
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-n", "-d", str(tmp_path), "--config", f"telemetry={broken}"],
                         capture_output=True, text=True)
    assert run.returncode != 0
    said = run.stdout + run.stderr
    assert "campaign.yaml: maneuvers[0] (yaw_pos).direction" in said
