"""A campaign's run as one sequence of steps, in the order the workflow's rules run them, each given
what its rule gives it: what the validation study and the tests call where Snakemake is not used.
The rules call the same step functions, one job each."""

from gyrocal.io import telemetry
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import (
    DiagnosticsSettings,
    ModelChoiceSettings,
    PointEstimateSettings,
    PosteriorSettings,
    ReportSettings,
)
from gyrocal.pipeline.steps import (
    calibrate,
    classic,
    compare_models,
    diagnostics,
    point_estimate,
    posterior,
    preprocess,
    report,
    validate,
)

__all__ = ["calibrate_campaign", "review_campaign", "run_campaign"]


def calibrate_campaign(campaign_dir, paths: CampaignPaths, cfg: dict, models, figures=True,
                       through="diagnostics") -> list:
    """Validate and preprocess one campaign, then each model up to its diagnostics
    (``through="posterior"``: up to its posterior). Returns the maneuver ids, in the campaign's order."""
    paths.mkdirs(models)
    campaign = telemetry.read_campaign(campaign_dir)
    validate.run(campaign_dir, paths, campaign, cfg["sampler"]["block_s"])
    ids = preprocess.run(campaign_dir, paths, figures, campaign=campaign)
    classic.run(paths, ids, cfg["noise"])
    for model in models:
        point_estimate.run(paths, ids, model, PointEstimateSettings.of(cfg, model))
        posterior.run(paths, ids, model, PosteriorSettings.of(cfg))
        if through == "posterior":
            continue
        calibrate.run(paths, ids, model)
        diagnostics.run(paths, ids, model, DiagnosticsSettings.of(cfg))
    return ids


def review_campaign(paths: CampaignPaths, ids, cfg: dict, models, truth_json=None, processes: int = 1):
    """Compare the models and write the pre-uplink review and its verdict."""
    compare_models.run(paths, models, ModelChoiceSettings.of(cfg))
    report.run(paths, ids, list(models), ReportSettings.of(cfg), truth_json, processes)


def run_campaign(campaign_dir, paths: CampaignPaths, cfg: dict, models, truth_json=None) -> list:
    """Every step of one campaign's run, as ``snakemake`` runs them. Returns the maneuver ids."""
    ids = calibrate_campaign(campaign_dir, paths, cfg, models)
    review_campaign(paths, ids, cfg, models, truth_json)
    return ids
