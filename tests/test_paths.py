"""The paths of a run and the settings of each step, written once (gyrocal.pipeline.paths, .settings)."""

import copy
from pathlib import Path

from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import (
    SECTIONS,
    DiagnosticsSettings,
    ModelChoiceSettings,
    PointEstimateSettings,
    PosteriorSettings,
    ReportSettings,
    canonical,
)


def test_snakemake_wildcards_pass_through_the_paths_unchanged():
    paths = CampaignPaths("results/{campaign}")
    assert paths.model("{model}").calibration == "results/{campaign}/{model}/calibration.csv"
    assert paths.maneuvers(["{maneuver}"], "png") == ["results/{campaign}/preprocess/{maneuver}.png"]


def test_a_campaigns_outputs_are_every_file_its_rules_declare_in_the_order_of_the_models():
    paths = CampaignPaths.under("out/mom")
    each = ["point_estimate.npz", "posterior.nc", "posterior_summary.csv", "fit.csv", "sampler.json",
            "elpd_maneuvers.csv", "elpd_blocks.csv", "orthogonality.csv", "calibration.csv", "correction.json",
            "diagnostics.json"]
    assert paths.outputs(["baseline", "bias_drift"]) == [
        "out/mom/input.json", "out/mom/preprocess",
        *[f"out/mom/baseline/{f}" for f in each], *[f"out/mom/bias_drift/{f}" for f in each],
        "out/mom/classic.csv", "out/mom/model_comparison.csv", "out/mom/model_comparison.png",
        "out/mom/report.html", "out/mom/verdict.json"]


def test_a_file_missing_from_an_existing_step_folder_is_named_with_its_folder(tmp_path):
    paths = CampaignPaths.under(tmp_path)
    assert paths.missing_in_folders(["yaw_pos"], simulated=True) == []  # no folder yet: nothing is missing
    Path(paths.preprocess).mkdir()
    for ext in ("npz", "csv", "png"):
        Path(paths.preprocess, f"yaw_pos.{ext}").write_text("x")
    assert paths.missing_in_folders(["yaw_pos"], simulated=True) == []
    Path(paths.preprocess, "yaw_pos.npz").unlink()
    Path(paths.simulated).mkdir(parents=True)
    assert paths.missing_in_folders(["yaw_pos"], simulated=False) == [(f"{tmp_path}/preprocess/yaw_pos.npz", paths.preprocess)]
    assert paths.missing_in_folders(["yaw_pos"], simulated=True)[0] == (f"{tmp_path}/simulated/campaign/campaign.yaml",
                                                                       paths.simulated)


def test_each_step_takes_only_the_config_sections_it_reads(config):
    posterior = PosteriorSettings.of(config)
    assert posterior.sampler == canonical(config["sampler"]) and posterior.seed == config["seed"]
    assert posterior.prior_from is None  # the config's "" means none
    changed = copy.deepcopy(config)
    changed["report"]["max_ci_width_ppm"] = 1.0
    changed["diagnostics"]["rms_ratio_max"] = 9.0
    assert PosteriorSettings.of(changed) == posterior
    assert PointEstimateSettings.of(changed, "baseline") == PointEstimateSettings.of(config, "baseline")
    assert DiagnosticsSettings.of(changed) != DiagnosticsSettings.of(config)
    assert ReportSettings.of(changed) != ReportSettings.of(config)
    assert ModelChoiceSettings.of(config).reject_se == config["model_choice"]["reject_se"]
    assert set(SECTIONS["posterior"]) <= set(config)


def test_the_order_of_a_config_files_keys_does_not_change_a_steps_settings(config):
    reordered = {k: (dict(reversed(v.items())) if isinstance(v, dict) else v) for k, v in reversed(config.items())}
    assert repr(PosteriorSettings.of(reordered)) == repr(PosteriorSettings.of(config))
    assert repr(ReportSettings.of(reordered)) == repr(ReportSettings.of(config))
