"""Rule ``extended``: one step of the model-criticism loop (`gyrocal.criticism.extension`), a model
variant fitted in the same run where the reviewed model misfits and a library effect explains it."""

import logging

from gyrocal.criticism.extension import Extension, extension_names, next_effect
from gyrocal.io.outputs import write_json
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import DiagnosticsSettings, ExtendSettings, PointEstimateSettings, PosteriorSettings
from gyrocal.pipeline.steps import common

__all__ = ["decide", "run"]

log = logging.getLogger("gyrocal")


def decide(paths: CampaignPaths, models, name: str, settings: ExtendSettings) -> Extension:
    """What the step ``name`` (`extension_names`) fits: the first extends the model the comparison of
    the variants ``models`` reviews, each later one the step before it, where that was fitted."""
    names = extension_names(settings.loop["depth"])
    k = names.index(name)
    if k == 0:
        from gyrocal.pipeline.steps import compare_models

        table = compare_models.table(paths, models, settings.model_choice["reject_se"])
        base = str(table.loc[table["reviewed"], "model"].iloc[0])
    else:
        base = names[k - 1]
        record = common.read_refusal(paths, base)
        if record is not None:
            return Extension(base, "", [], f"the loop stopped at {base}: {record['reason']}")
    doc = common.read_json(paths.model(base).diagnostics)
    return next_effect(base, doc["effects"], doc, settings.diagnostics["diagnostics"]["structure_log10_p_min"])


def run(paths: CampaignPaths, maneuver_ids, models, name: str, settings: ExtendSettings, placeholders=False):
    """Decide the step (`decide`; ``extension.json``), then, where it extends, the variant's point
    estimate, posterior, calibration and diagnostics as their own rules run them; where it does not,
    the variant is skipped with the reason (its ``refused.json``), at the cost of reading the
    diagnostics. ``placeholders`` (the workflow's rule, which declares them): a skipped or refused
    step's files and the later steps' hold the record instead. Returns the decision."""
    files = paths.model(name)
    paths.mkdirs([name])
    step = decide(paths, models, name, settings)
    write_json(step.as_dict(), files.extension)
    log.info("loop step %s: %s", name, step.why)
    if not step.fitted:  # before the model steps' imports (the sampler's, arviz's): a skip costs next to nothing
        common.variant_step(paths, name, "point_estimate", lambda: common.skip(f"not fitted: {step.why}"),
                            _placeholders(files) if placeholders else [])
        return step
    from gyrocal.pipeline.steps import calibrate, diagnostics, point_estimate, posterior

    pe = PointEstimateSettings(effects=step.effects, **settings.point_estimate)

    diag_out = [files.diagnostics] if placeholders else []
    post_out = _placeholders(files)[1:] if placeholders else []
    if common.variant_step(paths, name, "point_estimate", lambda: point_estimate.run(paths, maneuver_ids, name, pe),
                           _placeholders(files) if placeholders else []) is not None:
        return step

    def sample():
        posterior.run(paths, maneuver_ids, name, PosteriorSettings(**settings.posterior))
        calibrate.run(paths, maneuver_ids, name)

    if common.variant_step(paths, name, "posterior", sample, post_out) is not None:
        return step
    common.variant_step(paths, name, "diagnostics",
                        lambda: diagnostics.run(paths, maneuver_ids, name, DiagnosticsSettings(**settings.diagnostics)),
                        diag_out)
    return step


def _placeholders(files) -> list:
    """The variant's files after ``extension.json``, in the order its steps write them: what a skipped
    or refused step leaves its record in, from that step on."""
    return [files.point_estimate, files.posterior, files.summary, files.fit, files.sampler, files.elpd_maneuvers,
            files.elpd_blocks, files.calibration, files.correction, files.diagnostics]
