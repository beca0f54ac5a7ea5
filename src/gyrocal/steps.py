"""The workflow's steps as functions of paths: what the thin Snakemake scripts call.

Each step reads the files its rule declares, calls the physics and statistics modules
and writes its outputs whole or not at all (`outputs`). Each takes only the config
sections it uses, so a change elsewhere in the config does not rerun it.
"""

import json
import logging
import sys
import warnings
from contextlib import contextmanager
from dataclasses import asdict

import arviz as az
import pandas as pd
from scipy.spatial.transform import Rotation

from . import (
    __version__,
    classic,
    comparison,
    consistency,
    diagnostics,
    effects,
    fleet,
    inferencedata,
    plots,
    posterior,
    preprocess,
    spec,
    telemetry,
)
from . import report as review
from .calibration import calibration_table, posterior_mean_params
from .correction import campaign_correction
from .estimate import EstimateError, PointEstimate, check_noise, check_physical, point_estimate
from .noise import stated_scales
from .outputs import atomic, write_csv, write_json, write_text, write_with
from .spec import ModelSpec

log = logging.getLogger("gyrocal")


def start(log_path):
    """Set up a workflow step's process: gyrocal's log and Python's warnings go to the step's
    log file, and figures render headless (Agg)."""
    import matplotlib
    matplotlib.use("Agg")
    logging.basicConfig(filename=log_path, level=logging.INFO, force=True,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    logging.captureWarnings(True)
    # arviz 0.23's matplotlib backend calls an API matplotlib 3.11 deprecates; not ours to fix.
    warnings.filterwarnings("ignore", message="Passing a dict or None as alias_mapping", category=DeprecationWarning)


REFUSED = "gyrocal: the campaign was refused:"
"""How a step's message about bad input begins, in its log and on the console."""


@contextmanager
def refusal():
    """Turn bad input (`telemetry.TelemetryError`, `estimate.EstimateError`) into its message on
    stderr and in the step's log, and exit 1: a user reads what is wrong, not a traceback."""
    try:
        yield
    except (telemetry.TelemetryError, EstimateError) as exc:
        log.error("%s\n%s", REFUSED, exc)
        sys.exit(f"{REFUSED}\n{exc}")


def known_effects(plugin_paths) -> dict:
    """The library's effects and the plugins' (each plugin file loaded once), by name."""
    return {**effects.LIBRARY, **effects.load_plugins(plugin_paths or [])}


def noise_knowledge(info: dict, defaults: dict) -> dict:
    """The star-tracker and gyro noise knowledge: campaign.yaml (as recorded in
    ``input.json``) first, then the config's ``noise`` section."""
    keys = ("sigma_cross_arcsec", "sigma_about_arcsec", "boresight_body", "arw_deg_sqrt_h")
    stated = {**info["star_tracker"], **info["gyro"]}
    return {k: stated.get(k, defaults[k]) for k in keys}


def load_maneuvers(npz_paths) -> list:
    return [preprocess.ManeuverData.load(p) for p in npz_paths]


def read_json(path):
    with open(path) as handle:
        return json.load(handle)


def validate(campaign_dir, out_json):
    """Read the campaign and check its format and physics (`consistency`); record what was
    read, the warnings, the star-tracker outliers to leave out, its noise knowledge and
    the files' checksums."""
    campaign, findings = consistency.read_checked(campaign_dir)
    log.info("%s", consistency.summary(campaign, findings))
    write_json({
        "campaign": campaign.name,
        "gyrocal_version": __version__,
        "channels": campaign.channel_names,
        "extras": list(campaign.extras()),
        "maneuvers": [m.id for m in campaign.maneuvers],
        "rows": {"gyro": len(campaign.gyro_time), "star_tracker": len(campaign.st_time),
                 "star_tracker_invalid": int((campaign.st_valid == 0).sum()),
                 "star_tracker_outliers": len(findings.outliers),
                 "star_tracker_renormalised": campaign.st_renormalised},
        "warnings": findings.warnings,
        "star_tracker_outliers": [asdict(o) for o in findings.outliers],
        "mounting": findings.mounting,
        "star_tracker": campaign.star_tracker,
        "gyro": campaign.gyro,
        "checksums_sha256": telemetry.checksums(campaign_dir),
    }, out_json)


def run_preprocess(campaign_dir, input_json, maneuver_id, out_npz, out_csv, out_png):
    """Slice one maneuver, leaving out the star-tracker outliers that validation listed;
    propagate every channel set nominally, save table and figure."""
    info = read_json(input_json)
    campaign = telemetry.read_campaign(campaign_dir)
    if info["mounting"]:
        campaign = consistency.aligned(campaign, Rotation.from_quat(info["mounting"]["quat"]))
    outliers = [o["time_s"] for o in info["star_tracker_outliers"]]
    data = preprocess.slice_maneuver(campaign, maneuver_id, outliers)
    table = preprocess.error_table(data)
    write_with(data.save, out_npz)
    write_csv(table, out_csv)
    m = campaign.maneuver(maneuver_id)
    fig = plots.maneuver_figure(table, f"{campaign.name}: {m.id} ({m.turn}), nominal parameters")
    write_with(lambda handle: plots.save(fig, handle), out_png)


def run_classic(npz_paths, out_csv):
    """The paper's method over every maneuver, once per campaign."""
    maneuvers = load_maneuvers(npz_paths)
    write_csv(classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels)), out_csv)


def run_point_estimate(npz_paths, input_json, classic_csv, model, model_effects, noise_cfg, plugin_paths,
                       out_npz):
    """The full-trajectory WLS of one model, started from the classic estimate; saved
    with the model's specification and the noise knowledge it used."""
    maneuvers = load_maneuvers(npz_paths)
    fx = effects.resolve(model, model_effects, effects.load_plugins(plugin_paths or []))
    model_spec = ModelSpec.build(model, fx, maneuvers[0].channels)
    stated = noise_knowledge(read_json(input_json), noise_cfg)
    theta0 = classic.classic_vector(pd.read_csv(classic_csv), model_spec)
    est = point_estimate(maneuvers, model_spec, stated, theta0, noise_cfg["estimate_scales"])
    for p in est.spec.parameters:
        if p.prior_only:
            log.warning("%s is prior-only: %s", p.label, p.prior_only)
    if model_spec.correlated_noise:
        log.info("star-tracker noise correlation time: %.2f s", est.correlation_time_s)
    log.info("WLS: %s (%d evaluations); noise %s", est.message, est.nfev,
             stated_scales(est.log_sigma))
    write_with(est.save, out_npz)


def model_priors(est: PointEstimate, priors_cfg: dict, prior_from=None) -> posterior.Priors:
    """The spec's declared priors, overridden by the config and by an earlier campaign's
    ``calibration.csv`` (``prior_from``)."""
    earlier = pd.read_csv(prior_from) if prior_from else None
    spec = est.spec.with_priors(priors_cfg, earlier, str(prior_from))
    return posterior.Priors.from_spec(spec, est.stated_noise, priors_cfg["noise_log_sd"])


def run_posterior(npz_paths, point_npz, plugin_paths, priors_cfg, prior_from, sampler_cfg, grid_cfg,
                  convergence_cfg, seed, out_nc, out_summary, out_fit, out_sampler, out_elpd):
    """Sample the posterior, check convergence, save InferenceData, summary, model fit and the
    exact leave-one-maneuver-out predictive densities."""
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(point_npz, known_effects(plugin_paths))
    priors = model_priors(est, priors_cfg, prior_from)
    check_noise(maneuvers, est)
    check_physical(maneuvers, est, priors.bound)
    post = posterior.sample(maneuvers, est, priors, sampler_cfg, grid_cfg, seed)
    idata, summary, fit, record = inferencedata.assemble(post, maneuvers, sampler_cfg, convergence_cfg, seed)
    with atomic(out_nc) as tmp:
        idata.to_netcdf(str(tmp))
    write_csv(summary, out_summary)
    write_csv(fit, out_fit)
    write_json(record, out_sampler)
    elpd = posterior.leave_one_maneuver_out(post, priors)
    write_csv(pd.DataFrame({"maneuver": [d.id for d in maneuvers], "elpd": elpd}), out_elpd)


def run_calibrate(point_npz, summary_csv, npz_paths, out_csv, out_correction):
    """``calibration.csv`` per the contract and the correction file for every channel set."""
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(point_npz)
    table = calibration_table(est.spec, est.theta, pd.read_csv(summary_csv).set_index("label"))
    write_csv(table, out_csv)
    doc = campaign_correction(posterior_mean_params(est.spec, table), maneuvers, "posterior mean")
    doc["gyrocal_version"] = __version__
    write_json(doc, out_correction)


def run_diagnostics(npz_paths, point_npz, summary_csv, fit_csv, plugin_paths, thresholds, out_json):
    """``diagnostics.json`` per docs/interface.md section 5: misfit verdict and ranking."""
    maneuvers = load_maneuvers(npz_paths)
    known = known_effects(plugin_paths)
    est = PointEstimate.load(point_npz, known)
    plugins = [e for name, e in known.items() if name not in effects.LIBRARY]
    doc = diagnostics.diagnose(maneuvers, est, pd.read_csv(fit_csv), pd.read_csv(summary_csv).set_index("label"),
                               thresholds, plugins)
    write_json(doc, out_json)


def run_compare(models, posterior_paths, diagnostics_paths, summary_paths, elpd_paths, choice_cfg, out_csv, out_png):
    """``model_comparison.csv``: residual RMS, PSIS-LOO and exact leave-one-maneuver-out per
    variant, what moved, which variants are plausible and which one is reviewed."""
    table = comparison.compare(models, [az.from_netcdf(p) for p in posterior_paths],
                               [read_json(p) for p in diagnostics_paths],
                               [pd.read_csv(p).set_index("label") for p in summary_paths],
                               [pd.read_csv(p)["elpd"].to_numpy() for p in elpd_paths], choice_cfg["reject_se"])
    write_csv(table, out_csv)
    fig = plots.comparison_figure(table)
    write_with(lambda handle: plots.save(fig, handle), out_png)


def run_report(models, model_files, npz_paths, table_paths, input_json, comparison_csv, truth_json, cfg,
               out_html, out_verdict):
    """``report.html``: the pre-uplink review of a campaign (see `gyrocal.report`), and its verdict
    with the checks behind it in ``verdict.json``, for scripts and fleets.

    ``model_files`` maps each name of `outputs.MODEL_FILES` to its paths, one per model in
    the order of ``models``; the reviewed model's are read.
    """
    table = pd.read_csv(comparison_csv)
    model = str(table.loc[table["reviewed"], "model"].iloc[0])
    files = {name: paths[models.index(model)] for name, paths in model_files.items()}
    calibrations = {m: pd.read_csv(p) for m, p in zip(models, model_files["calibration"])}
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(files["point"])
    ctx = review.build_context(
        model, maneuvers, [pd.read_csv(p) for p in table_paths], est, read_json(files["diagnostics"]),
        read_json(files["sampler"]), read_json(files["correction"]), files["correction"], pd.read_csv(files["fit"]),
        az.from_netcdf(str(files["posterior"])), table, read_json(input_json),
        read_json(truth_json)["parameters"] if truth_json else None, cfg, calibrations)
    write_text(review.render(ctx), out_html)
    write_json(review.verdict(ctx), out_verdict)


def run_fleet(verdict_paths, out_csv, out_png):
    """``results/fleet/``: every campaign's reviewed model and verdict in one table and figure."""
    verdicts = [read_json(p) for p in verdict_paths]
    calibrations = {(v["campaign"], v["model"]): pd.read_csv(fleet.calibration_path(p, v["model"]))
                    for v, p in zip(verdicts, verdict_paths)}
    table = fleet.summary(verdicts, calibrations)
    write_csv(table, out_csv)
    fig = fleet.figure(table)
    write_with(lambda handle: plots.save(fig, handle), out_png)
