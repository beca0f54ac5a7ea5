"""A campaign's run as one sequence of steps, in the order the workflow's rules run them, each given
what its rule gives it: what the validation study and the tests call where Snakemake is not used.
The rules call the same step functions, one job each."""

from gyrocal.criticism.extension import extension_names
from gyrocal.inference import interval
from gyrocal.io import telemetry
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import (
    DiagnosticsSettings,
    ExtendSettings,
    ModelChoiceSettings,
    PointEstimateSettings,
    PosteriorSettings,
    ReportSettings,
    models_to_run,
)
from gyrocal.pipeline.steps import (
    calibrate,
    classic,
    common,
    compare_models,
    diagnostics,
    extend,
    point_estimate,
    posterior,
    preprocess,
    report,
    validate,
)

__all__ = ["calibrate_campaign", "calibrate_models", "extend_models", "review_campaign", "run_campaign"]


def calibrate_campaign(campaign_dir, paths: CampaignPaths, cfg: dict, models=None, figures=True,
                       through="diagnostics", strict=False) -> list:
    """Validate and preprocess one campaign, then each model (`calibrate_models`; ``through``:
    ``"posterior"`` stops after its posterior, ``"point_estimate"`` after its point estimate, what
    `gyrocal joint` reads); ``models`` None: the config's (`models_to_run`). Returns the maneuver
    ids, in the campaign's order."""
    models = models_to_run(cfg) if models is None else models
    paths.mkdirs(models)
    campaign = telemetry.read_campaign(campaign_dir)
    validate.run(campaign_dir, paths, campaign, cfg["sampler"]["block_s"])
    ids = preprocess.run(campaign_dir, paths, figures, campaign=campaign,
                         reference_interval_s=cfg.get("reference_interval_s", interval.AUTO), noise=cfg["noise"])
    classic.run(paths, ids, cfg["noise"])
    calibrate_models(paths, ids, cfg, models, through, strict)
    return ids


def calibrate_models(paths: CampaignPaths, ids, cfg: dict, models, through="diagnostics", strict=False):
    """Each model up to its diagnostics (``through="posterior"``: up to its posterior; ``"point_estimate"``:
    up to its point estimate), on a campaign
    already preprocessed. A refused variant gets its refusal record and the others go on, as in the
    workflow (`common.variant_step`); ``strict``: its refusal is raised (the study's runs)."""
    paths.mkdirs(models)

    def variant_step(model, step, run):
        return run() if strict else common.variant_step(paths, model, step, run)

    for model in models:
        variant_step(model, "point_estimate",
                     lambda model=model: point_estimate.run(paths, ids, model, PointEstimateSettings.of(cfg, model)))
        if through == "point_estimate":
            continue

        def sample(model=model):
            posterior.run(paths, ids, model, PosteriorSettings.of(cfg))
            if through != "posterior":
                calibrate.run(paths, ids, model)

        variant_step(model, "posterior", sample)
        if through != "posterior":
            variant_step(model, "diagnostics",
                         lambda model=model: diagnostics.run(paths, ids, model, DiagnosticsSettings.of(cfg)))


def extend_models(paths: CampaignPaths, ids, cfg: dict, models) -> list:
    """The model-criticism loop after the variants ``models`` (`gyrocal.pipeline.steps.extend`, one
    step per name up to the config's ``loop.depth``), as the workflow's rule ``extended`` runs it:
    each fitted where the model before misfits and a library effect explains it, else skipped with
    the reason. Returns the loop's variant names, to compare after ``models``."""
    names = extension_names(ExtendSettings.of(cfg).loop["depth"])
    for name in names:
        extend.run(paths, ids, list(models), name, ExtendSettings.of(cfg))
    return names


def review_campaign(paths: CampaignPaths, ids, cfg: dict, models=None, truth_json=None, processes: int = 1):
    """Compare the models and write the pre-uplink review and its verdict."""
    models = models_to_run(cfg) if models is None else models
    compare_models.run(paths, models, ModelChoiceSettings.of(cfg))
    report.run(paths, ids, list(models), ReportSettings.of(cfg), truth_json, processes)


def run_campaign(campaign_dir, paths: CampaignPaths, cfg: dict, models=None, truth_json=None) -> list:
    """Every step of one campaign's run, as ``snakemake`` runs them: ``models`` None, the config's
    `models_to_run` and the loop after them (`extend_models`); the variants ``models`` alone where
    given. Returns the maneuver ids."""
    ids = calibrate_campaign(campaign_dir, paths, cfg, models)
    if models is None:
        models = models_to_run(cfg)
        models = list(models) + extend_models(paths, ids, cfg, models)
    review_campaign(paths, ids, cfg, models, truth_json)
    return ids
