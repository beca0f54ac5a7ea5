"""Rule ``report``: the pre-uplink review of a campaign and its verdict."""

from pathlib import Path

import arviz as az
import pandas as pd
import xarray as xr

from gyrocal.criticism import extension, modelchoice, priorconflict, verdict
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.sampling.posterior import posterior_spec
from gyrocal.io.outputs import write_json, write_text
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import ReportSettings
from gyrocal.pipeline.steps.common import compared, load_maneuvers, read_json, refusals
from gyrocal.report import review

__all__ = ["run"]


def run(paths: CampaignPaths, maneuver_ids, models, settings: ReportSettings, truth_json=None, processes: int = 1):
    """``report.html``: the pre-uplink review of a campaign (see `gyrocal.report.review`), and its verdict
    with the checks behind it in ``verdict.json``, for scripts and fleets.

    The checks are `gyrocal.criticism.verdict`'s findings on the reviewed model (the one
    ``model_comparison.csv`` names); the report renders them. Every model's ``calibration.csv``
    is read for the model-sensitivity check; the variants refused or skipped are listed with their
    reasons. Its figures are drawn by ``processes`` processes.
    """
    cfg = settings.config
    refused = list(refusals(paths, models).values())
    steps = [(m, read_json(paths.model(m).extension)) for m in models if Path(paths.model(m).extension).is_file()]
    models = compared(paths, models)
    fitted = [(m, s) for m, s in steps if m in models]
    table = pd.read_csv(paths.comparison)
    model = str(table.loc[table["reviewed"], "model"].iloc[0])
    files = paths.model(model)
    calibrations = {m: pd.read_csv(paths.model(m).calibration) for m in models}
    maneuvers = load_maneuvers(paths.maneuvers(maneuver_ids))
    est = PointEstimate.load(files.point_estimate, linearizations=False)
    info, diagnostics, sampler = read_json(paths.input_json), read_json(files.diagnostics), read_json(files.sampler)
    effect = verdict.estimate_effect(maneuvers, est.spec, calibrations[model], est.biases)
    used = posterior_spec(est.spec, cfg["priors"], cfg.get("prior_from"))
    conflict = priorconflict.conflict_check(priorconflict.conflict_table(used, est.theta, est.cov, calibrations[model]))
    findings = verdict.checks(model, calibrations, est.spec, sampler, diagnostics, table, effect, cfg, conflict,
                              info["gyro"].get("sensor_class"))
    # its posterior group alone (the predictive draws are 100 MB at 10x), in memory: forked processes draw
    with xr.open_dataset(files.posterior, group="posterior", engine="h5netcdf") as group:
        posterior = az.InferenceData(posterior=group.load())
    shown = {m for name, step in fitted for m in (step["base"], name)}  # each fitted step's model before and after
    loop = extension.before_after(fitted, {m: read_json(paths.model(m).diagnostics) for m in shown},
                                  {m: pd.read_csv(paths.model(m).fit) for m in shown}, table)
    disagreement = modelchoice.disagreement_table(modelchoice.typed(table), calibrations, verdict.informed_core(est.spec),
                                                  cfg["model_choice"]["agree_sd"],
                                                  verdict.width_limits(cfg["report"], est.spec))
    inputs = review.ReviewInputs(
        model=model, spec=used, maneuvers=maneuvers,
        tables=[pd.read_csv(p) for p in paths.maneuvers(maneuver_ids, "csv")],
        calibration=calibrations[model], fit=pd.read_csv(files.fit), posterior=posterior, diagnostics=diagnostics,
        sampler=sampler, correction=read_json(files.correction), correction_path=files.correction,
        comparison=table, info=info, config=cfg, findings=findings, effect_table=effect,
        truth=read_json(truth_json)["parameters"] if truth_json else None, refused=refused,
        reference_interval=read_json(paths.reference_interval) if Path(paths.reference_interval).exists() else None,
        loop=loop, loop_steps=[step for _, step in steps], disagreement=disagreement)
    write_text(review.render(review.build_context(inputs, processes)), paths.report)
    write_json(verdict.verdict(info["campaign"], model, findings), paths.verdict)
