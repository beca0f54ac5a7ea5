"""Rule ``report``: the pre-uplink review of a campaign and its verdict."""

from pathlib import Path
from types import SimpleNamespace

import arviz as az
import pandas as pd
import xarray as xr

from gyrocal.criticism import extension, modelchoice, priorconflict, verdict
from gyrocal.criticism.uplinked import uplinked_intervals
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.fit.operating import operating_map
from gyrocal.inference.sampling.priors import posterior_spec
from gyrocal.io.outputs import write_json, write_text
from gyrocal.model import effects
from gyrocal.pipeline.paths import GM_CLOCK, REFERENCE_INTERVAL, maneuver_files
from gyrocal.pipeline.settings import ReportSettings
from gyrocal.pipeline.steps.common import compared, load_maneuvers, read_json, refusals
from gyrocal.report import review

__all__ = ["run"]


def run(models, files, preprocessed, maneuver_ids, input_json, comparison_csv, out_html, out_verdict,
        settings: ReportSettings, truth_json=None, processes: int = 1, extensions=None):
    """``out_html`` (``report.html``): the pre-uplink review of a campaign (see `gyrocal.report.review`), and
    its verdict with the checks behind it in ``out_verdict`` (``verdict.json``), for scripts and fleets.

    ``files``: each model's files by their `ModelPaths` name, a list in the order of ``models`` each (the
    report rule's ``snakemake.input``, or `CampaignPaths.per_model`); ``preprocessed``: the preprocess
    step's folder, with the maneuvers ``maneuver_ids``; ``comparison_csv``: `compare_models`'s table;
    ``extensions``: each loop step's ``extension.json`` by its variant name (the rule ``extended``'s).

    The checks are `gyrocal.criticism.verdict`'s findings on the reviewed model (the one
    ``model_comparison.csv`` names); the report renders them. Every model's ``calibration.csv``
    is read for the model-sensitivity check; the variants refused or skipped are listed with their
    reasons. Its figures are drawn by ``processes`` processes.
    """
    cfg = settings.config
    models = list(models)
    refused = list(refusals(models, files.diagnostics).values())
    kept = compared(models, files.diagnostics)
    steps = [(m, read_json(path)) for m, path in (extensions or {}).items()]
    fitted = [(m, s) for m, s in steps if m in kept]
    table = pd.read_csv(comparison_csv)
    model = str(table.loc[table["reviewed"], "model"].iloc[0])
    reviewed = SimpleNamespace(**{name: getattr(files, name)[models.index(model)]
                                  for name in ("point_estimate", "posterior", "fit", "sampler", "correction", "diagnostics",
                                               "orthogonality")})
    calibrations = {m: pd.read_csv(files.calibration[models.index(m)]) for m in kept}
    maneuvers = load_maneuvers(maneuver_files(preprocessed, maneuver_ids))
    est = PointEstimate.load(reviewed.point_estimate, effects.known(list(cfg.get("plugins") or [])),
                             linearizations=False)
    info, diagnostics, sampler = read_json(input_json), read_json(reviewed.diagnostics), read_json(reviewed.sampler)
    shift_map = operating_map(maneuvers, est.spec, est.biases)  # the growth at the campaign's rates, uplinked
    effect = verdict.estimate_effect(maneuvers, est.spec, calibrations[model], est.biases, shift_map)
    used = posterior_spec(est.spec, cfg["priors"], cfg.get("prior_from"))
    conflict = priorconflict.conflict_check(priorconflict.conflict_table(used, est.theta, est.cov, calibrations[model]))
    # its posterior group alone (the predictive draws are 100 MB at 10x), in memory: forked processes draw
    with xr.open_dataset(reviewed.posterior, group="posterior", engine="h5netcdf") as group:
        posterior = az.InferenceData(posterior=group.load())
    flown = uplinked_intervals(posterior, est.spec, shift_map)
    findings = verdict.checks(model, calibrations, est.spec, sampler, diagnostics, table, effect, cfg, conflict,
                              info["gyro"].get("sensor_class"), flown)
    shown = {m for name, step in fitted for m in (step["base"], name) if m in kept}  # each step's model before and after
    loop = extension.before_after(fitted, {m: read_json(files.diagnostics[models.index(m)]) for m in shown},
                                  {m: pd.read_csv(files.fit[models.index(m)]) for m in shown}, table)
    disagreement = modelchoice.disagreement_table(modelchoice.typed(table), calibrations, verdict.informed_core(est.spec),
                                                  cfg["model_choice"]["agree_sd"],
                                                  verdict.width_limits(cfg["report"], est.spec))
    inputs = review.ReviewInputs(
        model=model, spec=used, maneuvers=maneuvers,
        tables=[pd.read_csv(p) for p in maneuver_files(preprocessed, maneuver_ids, "csv")],
        calibration=calibrations[model], fit=pd.read_csv(reviewed.fit), posterior=posterior, diagnostics=diagnostics,
        sampler=sampler, correction=read_json(reviewed.correction), correction_path=reviewed.correction,
        comparison=table, info=info, config=cfg, findings=findings, effect_table=effect,
        truth=read_json(truth_json)["parameters"] if truth_json else None, refused=refused,
        reference_interval=read_json(interval) if (interval := Path(preprocessed, REFERENCE_INTERVAL)).exists() else None,
        gm_clock=read_json(chosen) if (chosen := Path(preprocessed, GM_CLOCK)).exists() else None,
        loop=loop, loop_steps=[step for _, step in steps], disagreement=disagreement,
        orthogonality=pd.read_csv(reviewed.orthogonality), flown=flown)
    write_text(review.render(review.build_context(inputs, processes)), out_html)
    write_json(verdict.verdict(info["campaign"], model, findings), out_verdict)
