"""The paths of a run and the settings of each step, written once (gyrocal.pipeline.paths, .settings)."""

import copy

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


def test_a_campaigns_outputs_are_the_contracts_files_in_the_order_of_the_models():
    paths = CampaignPaths.under("out/mom")
    assert paths.outputs(["baseline", "bias_drift"]) == [
        "out/mom/input.json", "out/mom/preprocess",
        "out/mom/baseline/calibration.csv", "out/mom/baseline/correction.json", "out/mom/baseline/diagnostics.json",
        "out/mom/bias_drift/calibration.csv", "out/mom/bias_drift/correction.json",
        "out/mom/bias_drift/diagnostics.json",
        "out/mom/classic.csv", "out/mom/model_comparison.csv", "out/mom/report.html", "out/mom/verdict.json"]


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
