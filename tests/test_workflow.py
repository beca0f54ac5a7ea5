"""The Snakemake workflow end to end, on a user's campaign directory."""

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from gyrocal.pipeline.paths import CampaignPaths

import mutations
from conftest import DATA, ROOT

MODEL_FILES = ("point_estimate", "posterior", "summary", "fit", "sampler", "elpd_maneuvers", "elpd_blocks",
               "orthogonality", "calibration", "correction", "diagnostics")
SNAKEMAKE = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "workflow" / "Snakefile")]
SHORT_CHAINS = str(DATA / "short_chains.yaml")
"""The runs here test the workflow's wiring and numbers, not convergence."""
CONFIGS = [SHORT_CHAINS, str(DATA / "refused_variant.yaml")]
"""Short chains, and a variant the tiny campaign refuses beside the default ones."""
FAST_REFUSALS = ("gyro increments in degrees",)
"""The refusals the fast tier sees end a Snakemake run; every refusal's message is checked through
`gyrocal validate` in test_robustness, and the rest end a Snakemake run in the full tier."""


@pytest.fixture(scope="module")
def workflow_run(tiny, tmp_path_factory):
    """The whole workflow through Snakemake on the tiny campaign, as a user runs it."""
    work = tmp_path_factory.mktemp("workflow")
    run = subprocess.run(SNAKEMAKE + ["--cores", "2", "-d", str(work), "--configfile", *CONFIGS,
                                      "--config", f"telemetry={tiny[0]}"],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    return work


def test_user_campaign_runs_with_no_code_edit(workflow_run):
    results = workflow_run / "results" / "tiny"
    table = pd.read_csv(results / "baseline" / "calibration.csv")
    assert len(table) == 24 + 12   # the parameters, then sf_mean and sf_asym per channel
    assert json.loads((results / "baseline" / "correction.json").read_text())["sets"]
    classic = pd.read_csv(results / "classic.csv")
    assert len(classic) == 24 and not (results / "baseline" / "classic.csv").exists()
    assert not any("WARNING" in p.read_text() for p in (workflow_run / "logs").rglob("*.log")
                   if "g_sensitivity" not in p.parts)


def test_a_refused_variant_leaves_its_record_and_the_run_goes_on(workflow_run):
    results = workflow_run / "results" / "tiny"
    record = json.loads((results / "g_sensitivity" / "refused.json").read_text())
    assert (record["status"], record["step"]) == ("refused", "point_estimate") and "acc_x" in record["reason"]
    assert json.loads((results / "g_sensitivity" / "calibration.csv").read_text()) == record
    assert list(pd.read_csv(results / "model_comparison.csv")["model"]) == ["baseline", "bias_drift", "symmetric"]
    assert "effect g_sensitivity needs" in (results / "report.html").read_text()


def test_the_rules_write_every_file_the_paths_name(workflow_run):
    paths = CampaignPaths.under(workflow_run / "results" / "tiny")
    models = ["baseline", "bias_drift", "symmetric", "g_sensitivity"]
    for path in paths.outputs(models) + [getattr(paths.model(m), f) for m in models for f in MODEL_FILES]:
        assert Path(path).exists(), path


def test_the_runs_json_results_conform_to_their_schemas(workflow_run):
    from gyrocal.io.outputs import OUTPUT_SCHEMAS, output_errors
    checked = {}
    for path in sorted((workflow_run / "results" / "tiny").rglob("*.json")):
        if path.name in OUTPUT_SCHEMAS:
            assert output_errors(json.loads(path.read_text()), OUTPUT_SCHEMAS[path.name]) == [], path
            checked[path.name] = checked.get(path.name, 0) + 1
    # the verdict; four variants' diagnostics and sampler records, g_sensitivity's the refusal record, and the
    # loop's step (extended), skipped with no misfit to extend: its files hold its record
    assert checked == {"verdict.json": 1, "diagnostics.json": 5, "sampler.json": 5, "refused.json": 2}


def dry_run_with(tiny, work, tmp_path, override: str):
    """What ``snakemake -n`` would run after a finished run, with a config file overriding some
    settings: the jobs by rule (from its ``Job stats`` table) and all it said."""
    config = tmp_path / "override.yaml"
    config.write_text(override)
    run = subprocess.run(SNAKEMAKE + ["-n", "-d", str(work), "--configfile", *CONFIGS, str(config),
                                      "--config", f"telemetry={tiny[0]}"], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    said = run.stdout + run.stderr
    if "Job stats:" not in said:
        return {}, said
    jobs = {}
    for line in said[said.index("Job stats:"):].splitlines()[3:]:
        name, count = line.split()
        if name == "total":
            return jobs, said
        jobs[name] = int(count)
    raise AssertionError(f"no end to the Job stats table in: {said[-3000:]}")


def test_a_report_threshold_change_reruns_the_report_and_nothing_upstream(tiny, workflow_run, tmp_path):
    jobs, said = dry_run_with(tiny, workflow_run, tmp_path, "report:\n  max_ci_width_ppm: 150\n")
    assert jobs == {"report": 1, "all": 1}, said[-3000:]
    assert "Params have changed since last execution" in said


def test_a_sampler_setting_change_reruns_the_posterior_but_not_the_point_estimate(tiny, workflow_run, tmp_path):
    jobs, said = dry_run_with(tiny, workflow_run, tmp_path, "sampler:\n  chunk_steps: 150\n")
    # one posterior per model of the default config, and what reads it (the loop's step reads their
    # diagnostics); no point estimate, no preprocess
    assert jobs == {"posterior": 4, "diagnostics": 4, "extended": 1, "report": 1, "all": 1}, said[-3000:]


def test_an_unchanged_config_schedules_nothing(tiny, workflow_run, tmp_path):
    jobs, said = dry_run_with(tiny, workflow_run, tmp_path, "seed: 1\n")
    assert jobs == {}, said[-3000:]


GYROCAL = [sys.executable, "-m", "gyrocal.pipeline.cli"]


def test_gyrocal_run_sets_a_nested_setting_that_reaches_the_workflow(tiny, workflow_run):
    # report.physical_bound_ppm, nested: Snakemake's --config cannot set it; the report's params change
    run = subprocess.run(GYROCAL + ["run", "-n", "-d", str(workflow_run), "--set", "report.physical_bound_ppm=500",
                                    *[a for c in CONFIGS for a in ("--configfile", c)],
                                    "--config", f"telemetry={tiny[0]}"],
                         capture_output=True, text=True, check=False, cwd=ROOT)
    said = run.stdout + run.stderr
    assert run.returncode == 0, said[-3000:]
    assert "rule report:" in said and "Params have changed since last execution" in said
    assert "rule posterior:" not in said and "rule point_estimate:" not in said


@pytest.mark.parametrize("setting, message", [
    ("sampler.walkers=1", "setting sampler.walkers (from --set): 1 is less than the minimum of 8"),
    ("report.physical_bound_ppm=big", "setting report.physical_bound_ppm (from --set): 'big' is not of type 'number'"),
    ("sampler.walker=16", "setting sampler.walker (from --set): no such setting; sampler takes ['block_s',"),
])
def test_gyrocal_run_refuses_a_bad_setting_naming_its_key_before_any_job(setting, message, tmp_path):
    run = subprocess.run(GYROCAL + ["run", "--cores", "1", "-d", str(tmp_path), "--set", setting],
                         capture_output=True, text=True, check=False, cwd=ROOT)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert run.stderr.startswith(f"gyrocal run: error: {message}"), run.stderr
    assert not (tmp_path / ".snakemake").exists()  # Snakemake never started


def test_gyrocal_run_without_snakemake_says_to_install_the_workflow_extra(tmp_path):
    """The library installs without Snakemake (the ``workflow`` extra); ``gyrocal run`` then says so."""
    hidden = ("import sys; sys.modules['snakemake'] = None; from gyrocal.pipeline import cli; "
              "sys.argv = ['gyrocal', 'run', '-n']; sys.exit(cli.entry())")
    run = subprocess.run([sys.executable, "-c", hidden], capture_output=True, text=True, check=False, cwd=tmp_path)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert run.stderr.startswith("gyrocal run: error: gyrocal run needs Snakemake"), run.stderr
    assert 'pip install -e ".[workflow]"' in run.stderr


@pytest.mark.full  # 11 s: the rerun of posterior, diagnostics and report; the fast tier keeps the deleted-file refusal
def test_a_deleted_intermediate_file_is_redone_by_the_plain_rerun(tiny, workflow_run, tmp_path):
    work = tmp_path / "work"
    shutil.copytree(workflow_run, work, symlinks=True)  # copy2: the same times, so the copy is as complete
    results = work / "results" / "tiny" / "baseline"
    (results / "posterior.nc").unlink()
    run = subprocess.run(SNAKEMAKE + ["--cores", "2", "-d", str(work), "--configfile", *CONFIGS,
                                      "--config", f"telemetry={tiny[0]}"], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    for rule in ("posterior", "diagnostics", "report"):
        assert f"rule {rule}:" in run.stderr, run.stderr[-3000:]
    assert "rule point_estimate:" not in run.stderr
    original = workflow_run / "results" / "tiny"
    for name in ("baseline/posterior.nc", "baseline/calibration.csv", "baseline/diagnostics.json", "verdict.json"):
        assert (work / "results" / "tiny" / name).read_bytes() == (original / name).read_bytes(), name


def test_a_file_deleted_from_the_preprocess_folder_stops_the_rerun_saying_what_to_do(tiny, workflow_run, tmp_path):
    work = tmp_path / "work"
    shutil.copytree(workflow_run, work, symlinks=True)
    (work / "results" / "tiny" / "preprocess" / "yaw_pos.npz").unlink()
    dry = SNAKEMAKE + ["-n", "-d", str(work), "--configfile", *CONFIGS, "--config", f"telemetry={tiny[0]}"]
    run = subprocess.run(dry, capture_output=True, text=True, check=False)
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert ("gyrocal: results/tiny/preprocess/yaw_pos.npz is missing, and Snakemake takes the folder that held it "
            "for complete: delete the folder results/tiny/preprocess and run again") in run.stderr
    shutil.rmtree(work / "results" / "tiny" / "preprocess")  # as it says: every step from preprocess on is redone
    again = subprocess.run(dry, capture_output=True, text=True, check=False)
    jobs = again.stdout + again.stderr
    assert all(f"rule {r}:" in jobs for r in ("preprocess", "point_estimate", "posterior", "diagnostics", "report")), jobs


def test_bad_config_value_is_refused_with_a_clear_message(tmp_path):
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-n", "-d", str(tmp_path), "--config", "seed=-3"],
                         capture_output=True, text=True, check=False)
    assert run.returncode != 0
    said = run.stdout + run.stderr
    assert "-3 is less than the minimum of 0" in said and "['seed']" in said


def test_an_unknown_model_in_run_models_is_refused_naming_those_defined(tmp_path):
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-n", "-d", str(tmp_path), "--config", "run_models=[baseline,drift]"],
                         capture_output=True, text=True, check=False)
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert ("gyrocal: the config was refused:\nconfig: run_models names ['drift'], which models: does not define; "
            "defined: ['baseline', 'bias_drift', 'symmetric']") in run.stderr


def test_bad_telemetry_is_refused_naming_the_file(tiny, tmp_path):
    broken = tmp_path / "broken"
    shutil.copytree(tiny[0], broken)
    (broken / "campaign.yaml").write_text((broken / "campaign.yaml").read_text().replace("direction: +", "direction: up"))
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-n", "-d", str(tmp_path), "--config", f"telemetry={broken}"],
                         capture_output=True, text=True, check=False)
    assert run.returncode != 0
    said = run.stdout + run.stderr
    assert "campaign.yaml: maneuvers[0] (yaw_pos).direction" in said


@pytest.mark.parametrize("case", [pytest.param(c, marks=() if c in FAST_REFUSALS else pytest.mark.full)
                                  for c in sorted(mutations.REFUSED)])
def test_snakemake_ends_with_the_validators_message_and_no_traceback(case, tiny, tmp_path):
    from test_robustness import EXPECTED
    broken = tmp_path / "broken"
    mutations.corrupted_copy(tiny[0], broken, mutations.REFUSED[case])
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-d", str(tmp_path / "work"), "--config", f"telemetry={broken}"],
                         capture_output=True, text=True, check=False)
    assert run.returncode != 0
    assert "Traceback" not in run.stderr + run.stdout
    assert "gyrocal: the campaign was refused:" in run.stderr
    assert EXPECTED[case] in "\n".join(run.stderr.strip().splitlines()[-25:])


def test_a_refusal_shown_is_the_campaign_runs_own_not_a_newer_log_of_another(tiny, tmp_path):
    # the run shows its failed job's log (show-failed-logs), not the newest log under logs/: a refusal
    # left there by another campaign, written after this run's, is not shown
    broken, work = tmp_path / "broken", tmp_path / "work"
    mutations.corrupted_copy(tiny[0], broken, mutations.REFUSED["gyro increments in degrees"])
    stale = work / "logs" / "other" / "preprocess.log"
    stale.parent.mkdir(parents=True)
    stale.write_text("gyrocal: the campaign was refused:\nSTALE: campaign other's refusal\n")
    os.utime(stale, (time.time() + 3600, time.time() + 3600))
    run = subprocess.run(SNAKEMAKE + ["--cores", "1", "-d", str(work), "--config", f"telemetry={broken}"],
                         capture_output=True, text=True, check=False)
    said = run.stdout + run.stderr
    assert run.returncode != 0 and "Traceback" not in said
    assert "STALE" not in said and "logs/other" not in said
    from test_robustness import EXPECTED
    assert EXPECTED["gyro increments in degrees"] in said


def test_a_fleet_with_two_campaigns_of_one_name_is_refused(tiny, tmp_path):
    for name in ("one", "two"):
        shutil.copytree(tiny[0], tmp_path / "fleet" / name)
    run = subprocess.run(SNAKEMAKE + ["-n", "-d", str(tmp_path / "work"), "--config", f"campaigns={tmp_path / 'fleet'}"],
                         capture_output=True, text=True, check=False)
    assert run.returncode != 0 and "are both campaign 'tiny'" in run.stderr


def test_a_fleet_folder_that_does_not_exist_is_refused_without_a_traceback(tmp_path):
    run = subprocess.run(SNAKEMAKE + ["-n", "-d", str(tmp_path / "work"), "--config", f"campaigns={tmp_path / 'nowhere'}"],
                         capture_output=True, text=True, check=False)
    assert run.returncode != 0 and "Traceback" not in run.stderr + run.stdout
    assert f"campaigns={tmp_path / 'nowhere'} is not a directory" in run.stderr
