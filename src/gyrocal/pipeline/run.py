"""A campaign's run as one sequence of steps, in the order the workflow's rules run them, each given
what its rule gives it: what the validation study and the tests call where Snakemake is not used.
The rules call the same step functions, one job each."""

from pathlib import Path

from gyrocal.criticism.extension import extension_names
from gyrocal.inference import interval
from gyrocal.io import telemetry
from gyrocal.pipeline.paths import CALIBRATION_FILES, STEP_FILES, CampaignPaths
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
    validate.run(campaign_dir, paths.input_json, campaign, cfg["sampler"]["block_s"])
    ids = preprocess.run(campaign_dir, paths.input_json, paths.preprocess, figures, campaign=campaign,
                         reference_interval_s=cfg.get("reference_interval_s", interval.AUTO), noise=cfg["noise"])
    classic.run(paths.maneuvers(ids), paths.input_json, paths.classic, cfg["noise"])
    calibrate_models(paths, ids, cfg, models, through, strict)
    return ids


def calibrate_models(paths: CampaignPaths, ids, cfg: dict, models, through="diagnostics", strict=False):
    """Each model up to its diagnostics (``through="posterior"``: up to its posterior; ``"point_estimate"``:
    up to its point estimate), on a campaign
    already preprocessed. A refused variant gets its refusal record and the others go on, as in the
    workflow (`common.variant_step`); ``strict``: its refusal is raised (the study's runs)."""
    paths.mkdirs(models)
    npz = paths.maneuvers(ids)

    for model in models:
        out = paths.model(model)

        def variant_step(step, run, model=model, out=out):
            if strict:
                return run()
            written = [f for f in STEP_FILES[step] if through != "posterior" or f not in CALIBRATION_FILES]
            return common.variant_step(out.refusal, model, step, run, [getattr(out, f) for f in written])

        variant_step("point_estimate", lambda model=model, out=out: point_estimate.run(
            npz, paths.input_json, out.point_estimate, model, PointEstimateSettings.of(cfg, model)))
        if through == "point_estimate":
            continue

        def sample(out=out):
            settings = PosteriorSettings.of(cfg)
            posterior.run(npz, out.point_estimate, out, settings)
            if through != "posterior":
                calibrate.run(npz, out.point_estimate, out.summary, out.calibration, out.correction, settings.plugins)

        variant_step("posterior", sample)
        if through != "posterior":
            variant_step("diagnostics", lambda out=out: diagnostics.run(
                npz, out.point_estimate, out.fit, out.summary, out.diagnostics, DiagnosticsSettings.of(cfg)))


def extend_models(paths: CampaignPaths, ids, cfg: dict, models) -> list:
    """The model-criticism loop after the variants ``models`` (`gyrocal.pipeline.steps.extend`, one
    step per name up to the config's ``loop.depth``), as the workflow's rule ``extended`` runs it:
    each fitted where the model before misfits and a library effect explains it, else skipped with
    the reason. Returns the loop's variant names, to compare after ``models``."""
    settings = ExtendSettings.of(cfg)
    names = extension_names(settings.loop["depth"])
    paths.mkdirs(names)
    for k, name in enumerate(names):
        bases = list(models) if k == 0 else [names[k - 1]]
        out = paths.model(name)
        extend.run(name, bases, paths.per_model(bases), paths.maneuvers(ids), paths.input_json, out, out.refusal,
                   settings)
    return names


def review_campaign(paths: CampaignPaths, ids, cfg: dict, models=None, truth_json=None, processes: int = 1):
    """Compare the models and write the pre-uplink review and its verdict."""
    models = list(models_to_run(cfg) if models is None else models)
    files = paths.per_model(models)
    extensions = {m: paths.model(m).extension for m in models if Path(paths.model(m).extension).is_file()}
    compare_models.run(models, files, paths.comparison, paths.comparison_figure, ModelChoiceSettings.of(cfg))
    report.run(models, files, paths.preprocess, ids, paths.input_json, paths.comparison, paths.report, paths.verdict,
               ReportSettings.of(cfg), truth_json, processes, extensions)


def run_campaign(campaign_dir, paths: CampaignPaths, cfg: dict, models=None, truth_json=None, figures=True) -> list:
    """Every step of one campaign's run, as ``snakemake`` runs them: ``models`` None, the config's
    `models_to_run` and the loop after them (`extend_models`); the variants ``models`` alone where
    given; ``figures`` false: the preprocess step draws no maneuver figure files (the report draws its
    own). Returns the maneuver ids."""
    ids = calibrate_campaign(campaign_dir, paths, cfg, models, figures)
    if models is None:
        models = models_to_run(cfg)
        models = list(models) + extend_models(paths, ids, cfg, models)
    review_campaign(paths, ids, cfg, models, truth_json)
    return ids
