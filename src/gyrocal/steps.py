"""The workflow's steps as functions of paths: what the thin Snakemake scripts call.

Each step reads its inputs, calls the physics and statistics modules and writes its
outputs whole or not at all (a temporary file is renamed into place).
"""

import json
import logging
import os
from contextlib import contextmanager
from pathlib import Path

import warnings

# arviz 0.x announces its 1.x refactor on import; gyrocal pins arviz<1 (pyproject.toml).
warnings.filterwarnings("ignore", message="\\s*ArviZ is undergoing a major refactor", category=FutureWarning)
import arviz as az  # noqa: E402
import numpy as np
import pandas as pd
import xarray as xr
import yaml

from . import __version__
from . import channels as ch
from . import correction, diagnostics, effects, estimate, plots, posterior, predictive, preprocess, telemetry
from .units import AXES, PPM, arcsec_to_rad, rad_to_arcsec

log = logging.getLogger("gyrocal")


def log_to(path):
    """Send gyrocal's log and Python warnings of a workflow step to its log file."""
    logging.basicConfig(filename=path, level=logging.INFO, force=True,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    logging.captureWarnings(True)


@contextmanager
def atomic(path):
    """Yield a temporary path beside ``path``; rename it into place on success only."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_json(obj, path):
    with atomic(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, sort_keys=False, default=float))


def write_csv(frame: pd.DataFrame, path):
    with atomic(path) as tmp:
        frame.to_csv(tmp, index=False)


def noise_settings(meta: dict, cfg: dict) -> dict:
    """The star-tracker and gyro noise knowledge: campaign.yaml first, then the config."""
    st, gy, defaults = meta["star_tracker"], meta["gyro"], cfg["noise"]
    return {
        "sigma_cross_arcsec": st.get("sigma_cross_arcsec", defaults["sigma_cross_arcsec"]),
        "sigma_about_arcsec": st.get("sigma_about_arcsec", defaults["sigma_about_arcsec"]),
        "boresight_body": st.get("boresight_body", defaults["boresight_body"]),
        "arw_deg_sqrt_h": gy.get("arw_deg_sqrt_h", defaults["arw_deg_sqrt_h"]),
    }


def validate(campaign_dir, out_json):
    """Read and check the campaign; record what was read and the files' checksums."""
    campaign = telemetry.read_campaign(campaign_dir)
    log.info("%s", telemetry.summary(campaign))
    write_json({
        "campaign": campaign.name,
        "gyrocal_version": __version__,
        "channels": campaign.channel_names,
        "extras": list(campaign.extras()),
        "maneuvers": [m.id for m in campaign.maneuvers],
        "rows": {"gyro": len(campaign.gyro_time), "star_tracker": len(campaign.st_time),
                 "star_tracker_invalid": int((campaign.st_valid == 0).sum())},
        "checksums_sha256": telemetry.checksums(campaign_dir),
    }, out_json)


def run_preprocess(campaign_dir, maneuver_id, out_npz, out_csv, out_png):
    """Slice one maneuver, propagate every channel set nominally, save table and figure."""
    campaign = telemetry.read_campaign(campaign_dir)
    data = preprocess.slice_maneuver(campaign, maneuver_id)
    table = preprocess.error_table(data)
    with atomic(out_npz) as tmp:
        with open(tmp, "wb") as handle:
            data.save(handle)
    write_csv(table, out_csv)
    m = campaign.maneuver(maneuver_id)
    fig = plots.maneuver_figure(table, f"{campaign.name}: {m.id} ({m.direction}{m.axis}), nominal parameters")
    with atomic(out_png) as tmp:
        plots.save(fig, tmp)


def load_maneuvers(npz_paths) -> list:
    return [preprocess.ManeuverData.load(p) for p in npz_paths]


def model_effects(cfg, model: str) -> list:
    """The effect objects of a model variant declared in the config (plugins included)."""
    if model not in cfg["models"]:
        raise ValueError(f"model {model!r} is not declared under models: in the config ({list(cfg['models'])})")
    return effects.resolve(model, cfg["models"][model], effects.load_plugins(cfg.get("plugins") or []))


def model_extras(cfg, model, channels) -> list:
    return effects.extra_parameters(model_effects(cfg, model), channels)


def run_point_estimate(npz_paths, campaign_dir, cfg, model, out_npz, out_classic):
    """The paper's classic estimate and the full-trajectory WLS, both written out."""
    maneuvers = load_maneuvers(npz_paths)
    meta = telemetry.read_meta(campaign_dir)
    channels = maneuvers[0].channels
    extras = model_extras(cfg, model, channels)
    settings = noise_settings(meta, cfg)
    classic = estimate.classic_campaign(maneuvers)
    classic["unit"] = [ch.PARAMETER_UNITS[p] for p in classic["parameter"]]
    classic["value"] = np.where(classic["unit"] == "ppm", classic["value"] / PPM,
                                rad_to_arcsec(classic["value"]))
    log_sigma0 = np.log([arcsec_to_rad(settings["sigma_cross_arcsec"]),
                         arcsec_to_rad(settings["sigma_about_arcsec"]),
                         np.deg2rad(settings["arw_deg_sqrt_h"]) / 60.0])
    correlated = any(e.noise for e in model_effects(cfg, model))
    est = estimate.point_estimate(maneuvers, channels, settings["boresight_body"], log_sigma0,
                                  cfg["noise"]["estimate_scales"], extras, correlated)
    if correlated:
        log.info("star-tracker noise correlation time: %.2f s", est.correlation_time_s)
    log.info("WLS: %s (%d evaluations); noise %s", est.message, est.nfev, _noise_contract(est.log_sigma))
    with atomic(out_npz) as tmp:
        with open(tmp, "wb") as handle:
            np.savez(handle, theta=est.theta, cov=est.cov, biases=est.biases, chi0=est.chi0,
                     log_sigma=est.log_sigma, cost=est.cost, nfev=est.nfev, message=est.message,
                     correlation_time_s=est.correlation_time_s,
                     labels=ch.parameter_labels(channels) + [e.label for e in extras],
                     maneuvers=[d.id for d in maneuvers],
                     settings=json.dumps(settings))
    write_csv(classic[["channel", "parameter", "unit", "value", "n"]], out_classic)


def load_point_estimate(path, channels, extras=()) -> tuple:
    z = np.load(path, allow_pickle=False)
    labels = ch.parameter_labels(channels) + [e.label for e in extras]
    if list(z["labels"]) != labels:
        raise ValueError(f"{path}: its parameters {list(z['labels'])} are not the model's {labels}")
    est = estimate.PointEstimate(tuple(channels), z["theta"], z["cov"], z["biases"], z["chi0"],
                                 z["log_sigma"], float(z["cost"]), int(z["nfev"]), str(z["message"]),
                                 list(extras), float(z["correlation_time_s"]))
    return est, json.loads(str(z["settings"]))


def contract_scale(channels, extras=()) -> np.ndarray:
    """Multipliers from SI to the contract's units (ppm, arcsec; effects' own units), per parameter."""
    base = [1 / PPM if p.startswith("sf") else 1 / arcsec_to_rad(1.0) for c in channels for p in c.parameter_names]
    return np.array(base + [1 / e.parameter.si_per_unit for e in extras])


def parameter_units(channels, extras=()) -> list:
    return [ch.PARAMETER_UNITS[p] for c in channels for p in c.parameter_names] + [e.parameter.unit for e in extras]


def priors_for(channels, cfg, settings, extras=()) -> posterior.Priors:
    """Config priors, overridden by an earlier campaign's posterior (``prior_from``)."""
    pcfg = dict(cfg["priors"])
    if cfg.get("prior_from"):
        earlier = pd.read_csv(cfg["prior_from"])
        labels = set(ch.parameter_labels(channels))
        chosen = earlier[(earlier["channel"] + "." + earlier["parameter"]).isin(labels)]
        pcfg["mean"] = {f"{r.channel}.{r.parameter}": r.mean for r in chosen.itertuples()}
        pcfg["sd"] = {f"{r.channel}.{r.parameter}": r.sd for r in chosen.itertuples()}
    return posterior.Priors.from_config(channels, pcfg, settings, extras)


def run_posterior(npz_paths, point_npz, cfg, model, out_nc, out_summary, out_fit, out_sampler):
    """Sample the posterior, check convergence, save InferenceData, summary and model fit."""
    maneuvers = load_maneuvers(npz_paths)
    channels = maneuvers[0].channels
    extras = model_extras(cfg, model, channels)
    est, settings = load_point_estimate(point_npz, channels, extras)
    priors = priors_for(channels, cfg, settings, extras)
    post = posterior.sample(maneuvers, est, settings["boresight_body"], priors, cfg, cfg["seed"])
    labels = post.labels
    scale = contract_scale(channels, extras)
    draws = post.ensemble_draws()
    full = _posterior_dataset(draws, est.theta, scale, labels)
    with warnings.catch_warnings():
        # every walker is a chain here, and a short run may have more walkers than steps
        warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
        per_walker = _posterior_dataset(post.walker_draws(), est.theta, scale, labels)
    summary = _summary(full, per_walker, labels, cfg["convergence"])
    res = post.result
    converged = bool(summary["converged"].all() and res.converged_length)
    sampler_info = {
        "converged": converged,
        "chain_length_ok": res.converged_length,
        "steps": res.steps, "burn_steps": res.burn, "walkers": res.walkers,
        "ensembles": int(draws.shape[0]), "seed": cfg["seed"],
        "tau_max_steps": float(res.tau.max()), "steps_over_tau": float(res.steps / res.tau.max()),
        "acceptance": res.acceptance.tolist(),
        "grid": {"nodes": post.grid.nodes, "start": post.grid.start.tolist(), "step": post.grid.step.tolist()},
        "settings": {k: cfg["sampler"][k] for k in cfg["sampler"]},
        "point_estimate": {"cost": est.cost, "nfev": est.nfev, "message": est.message,
                           "noise": _noise_contract(est.log_sigma),
                           "st_correlation_time_s": est.correlation_time_s},
        "failed_parameters": summary.loc[~summary["converged"], "label"].tolist(),
    }
    if not converged:
        log.warning("THE SAMPLER DID NOT CONVERGE: %s; numbers are not reliable",
                    sampler_info["failed_parameters"] or "chains shorter than the autocorrelation limit")
    thin = np.linspace(0, draws.shape[1] - 1, cfg["sampler"]["loglik_draws"]).astype(int)
    kept = draws[:, thin]
    idata, fit = _inference_data(post, maneuvers, kept, scale, cfg)
    with atomic(out_nc) as tmp:
        idata.to_netcdf(str(tmp))
    write_csv(summary, out_summary)
    write_csv(fit, out_fit)
    write_json(sampler_info, out_sampler)


def _noise_contract(log_sigma) -> dict:
    s = np.exp(np.asarray(log_sigma))
    return {"sigma_cross_arcsec": float(rad_to_arcsec(s[0])), "sigma_about_arcsec": float(rad_to_arcsec(s[1])),
            "arw_deg_sqrt_h": float(np.rad2deg(s[2]) * 60.0)}


def _posterior_dataset(draws, theta_hat, scale, labels) -> az.InferenceData:
    p = len(labels)
    values = (theta_hat + draws[..., :p]) * scale
    s = np.exp(draws[..., p:])
    return az.from_dict(
        posterior={"channel_param": values, "sigma_cross_arcsec": rad_to_arcsec(s[..., 0]),
                   "sigma_about_arcsec": rad_to_arcsec(s[..., 1]),
                   "arw_deg_sqrt_h": np.rad2deg(s[..., 2]) * 60.0},
        coords={"parameter": labels}, dims={"channel_param": ["parameter"]})


def _summary(idata, per_walker, labels, conv) -> pd.DataFrame:
    """Mean, sd, central 95 % interval (arviz), r_hat across the independent ensembles
    (each one chain, step-major) and bulk ESS over every walker's own chain."""
    stats = az.summary(idata, kind="stats", stat_focus="mean", round_to="none")
    eti = az.summary(idata, kind="stats", stat_focus="median", hdi_prob=0.95, round_to="none")
    rhat = az.rhat(idata)
    ess = az.ess(per_walker, method="bulk")
    rows = []
    names = [f"channel_param[{label}]" for label in labels] + \
            ["sigma_cross_arcsec", "sigma_about_arcsec", "arw_deg_sqrt_h"]
    for label, name in zip(labels + ["noise.sigma_cross_arcsec", "noise.sigma_about_arcsec",
                                     "noise.arw_deg_sqrt_h"], names):
        if name.startswith("channel_param"):
            sel = {"parameter": label}
            r, e = float(rhat["channel_param"].sel(sel)), float(ess["channel_param"].sel(sel))
        else:
            r, e = float(rhat[name]), float(ess[name])
        rows.append({"label": label, "mean": stats.loc[name, "mean"], "sd": stats.loc[name, "sd"],
                     "ci95_low": eti.loc[name, "eti_2.5%"], "ci95_high": eti.loc[name, "eti_97.5%"],
                     "r_hat": r, "ess_bulk": e})
    frame = pd.DataFrame(rows)
    frame["converged"] = (frame["r_hat"] < conv["r_hat_max"]) & (frame["ess_bulk"] >= conv["ess_bulk_min"])
    return frame


def _inference_data(post, maneuvers, kept, scale, cfg):
    """InferenceData with log_likelihood per time block and a posterior predictive of the
    attitude errors; also the per-sample fit table behind the report's figures."""
    p = post.n_params
    n_chain, n_draw = kept.shape[:2]
    flat = kept.reshape(-1, kept.shape[-1])
    dtheta, log_sigma = flat[:, :p], flat[:, p:]
    ratios = np.mean(log_sigma[:, 1:] - log_sigma[:, :1], axis=0)
    scale2 = np.exp(2 * log_sigma[:, 0])
    n_pred = min(cfg["sampler"]["predictive_draws"], n_draw)
    pred_rows = (np.arange(n_chain)[:, None] * n_draw + np.arange(n_pred)[None]).ravel()
    rng = np.random.default_rng([cfg["seed"], 99])
    loglik, block_names, fit_tables = [], [], []
    pp_values, obs_values, sample_maneuver, sample_time = [], [], [], []
    zeros = ch.ChannelParams.zeros(maneuvers[0].channels)
    for data, lin, nz in zip(maneuvers, post.lins, post.noises):
        wm = predictive.WhitenedManeuver(nz, ratios)
        blocks = predictive.block_index(lin, data.st_time, cfg["sampler"]["block_s"])
        loglik.append(predictive.leave_block_out_loglik(lin, wm, dtheta, scale2, blocks))
        block_names += [f"{data.id}:{b}" for b in range(blocks.max() + 1)]
        resid = predictive.residuals_body(lin, dtheta[pred_rows], wm.nuisance(dtheta[pred_rows]))
        noise_rep = predictive.undifference_body(lin, wm.noise_draws(scale2[pred_rows], rng))
        for s, channel_set in enumerate(lin.sets):
            observed = preprocess.error_angles(data, channel_set, zeros)
            mean_pred = observed[None] - resid[:, :, s]
            replicate = mean_pred + noise_rep[:, :, s]
            lo, hi = np.quantile(replicate, [0.025, 0.975], axis=0)
            table = {"maneuver": data.id, "set": s, "channels": "+".join(channel_set), "time": data.st_time}
            mean = mean_pred.mean(axis=0)
            for i, axis in enumerate(AXES):
                table[f"observed_{axis}"] = rad_to_arcsec(observed[:, i])
                table[f"mean_{axis}"] = rad_to_arcsec(mean[:, i])
                table[f"lo_{axis}"] = rad_to_arcsec(lo[:, i])
                table[f"hi_{axis}"] = rad_to_arcsec(hi[:, i])
                table[f"residual_{axis}"] = rad_to_arcsec(observed[:, i] - mean[:, i])
                table[f"outside_{axis}"] = (observed[:, i] < lo[:, i]) | (observed[:, i] > hi[:, i])
            fit_tables.append(pd.DataFrame(table))
            if s == 0:
                keep = np.arange(0, len(data.st_time), max(1, len(data.st_time) // 300))
                pp_values.append(rad_to_arcsec(replicate[:, keep]))
                obs_values.append(rad_to_arcsec(observed[keep]))
                sample_maneuver += [data.id] * len(keep)
                sample_time.append(data.st_time[keep])
    loglik = np.concatenate(loglik, axis=1).reshape(n_chain, n_draw, -1)
    pp = np.concatenate(pp_values, axis=1).reshape(n_chain, n_pred, -1, 3)
    idata = _posterior_dataset(kept, post.estimate.theta, scale, post.labels)
    chain_draw = {"chain": np.arange(n_chain), "draw": np.arange(n_draw)}
    sample_coords = {"axis": list(AXES), "maneuver": ("sample", sample_maneuver),
                     "time": ("sample", np.concatenate(sample_time))}
    idata.add_groups(
        log_likelihood=xr.Dataset({"attitude_error": (("chain", "draw", "block"), loglik)},
                                  coords={**chain_draw, "block": block_names}),
        posterior_predictive=xr.Dataset(
            {"attitude_error": (("chain", "draw", "sample", "axis"), pp)},
            coords={"chain": np.arange(n_chain), "draw": np.arange(n_pred), **sample_coords}),
        observed_data=xr.Dataset({"attitude_error": (("sample", "axis"), np.concatenate(obs_values))},
                                 coords=sample_coords),
    )
    idata.posterior.attrs.update({"gyrocal_version": __version__, "seed": cfg["seed"],
                                  "units": "ppm for sf_*, arcsec for mis_*"})
    return idata, pd.concat(fit_tables, ignore_index=True)


def run_calibrate(point_npz, summary_csv, npz_paths, cfg, model, out_csv, out_correction):
    """``calibration.csv`` per the contract and the correction file for every channel set.

    Rows of the baseline's parameters come first; an extended model adds rows for its
    effects' parameters, in their own units."""
    maneuvers = load_maneuvers(npz_paths)
    channels = maneuvers[0].channels
    extras = model_extras(cfg, model, channels)
    est, _ = load_point_estimate(point_npz, channels, extras)
    summary = pd.read_csv(summary_csv).set_index("label")
    scale = contract_scale(channels, extras)
    units = parameter_units(channels, extras)
    point = est.theta * scale
    rows = []
    for i, label in enumerate(ch.parameter_labels(channels) + [e.label for e in extras]):
        channel, parameter = label.split(".")
        s = summary.loc[label]
        rows.append({"channel": channel, "parameter": parameter, "unit": units[i],
                     "point": point[i], "mean": s["mean"], "sd": s["sd"], "ci95_low": s["ci95_low"],
                     "ci95_high": s["ci95_high"], "r_hat": s["r_hat"], "ess_bulk": s["ess_bulk"]})
    table = pd.DataFrame(rows)
    write_csv(table, out_csv)
    mean_theta = table["mean"].to_numpy() / scale
    params = ch.ChannelParams.from_vector(channels, mean_theta[:est.n_base])
    in_loop = {tuple(d.sets[0]) for d in maneuvers}
    sets = list(dict.fromkeys(tuple(s) for d in maneuvers for s in d.sets))
    doc = correction.correction_file(params, sets, in_loop, "posterior mean")
    doc["gyrocal_version"] = __version__
    write_json(doc, out_correction)


def run_diagnostics(npz_paths, point_npz, summary_csv, fit_csv, cfg, model, out_json):
    """``diagnostics.json`` per interface.md section 5: misfit verdict and ranking."""
    maneuvers = load_maneuvers(npz_paths)
    channels = maneuvers[0].channels
    model_fx = model_effects(cfg, model)
    extras = effects.extra_parameters(model_fx, channels)
    est, settings = load_point_estimate(point_npz, channels, extras)
    boresight = settings["boresight_body"]
    lins, noises = estimate.linearize_all(maneuvers, est, boresight)
    fit = pd.read_csv(fit_csv)
    residual_rms = float(np.sqrt(np.mean(fit[[f"residual_{a}" for a in AXES]].to_numpy() ** 2)))
    noise_rms = diagnostics.noise_rms_arcsec(maneuvers, settings)
    white = diagnostics.whiteness(maneuvers, lins, noises, est)
    plugins = effects.load_plugins(cfg.get("plugins") or [])
    ranking, detail = diagnostics.rank(maneuvers, est, boresight, model_fx, list(maneuvers[0].extras),
                                       plugins.values(), white)
    summary = pd.read_csv(summary_csv).set_index("label")
    noise_post = {k: float(summary.loc[f"noise.{k}", "mean"])
                  for k in ("sigma_cross_arcsec", "sigma_about_arcsec", "arw_deg_sqrt_h")}
    checks = diagnostics.misfit_checks(residual_rms, noise_rms, white, ranking, noise_post, settings,
                                       cfg["diagnostics"])
    per_maneuver = {}
    for (m, s), group in fit.groupby(["maneuver", "set"], sort=False):
        per_maneuver.setdefault(m, {})[f"set{s}"] = {
            a: round(float(np.sqrt(np.mean(group[f"residual_{a}"] ** 2))), 3) for a in AXES}
    write_json({
        "model": model,
        "effects": [e.name for e in model_fx],
        "residual_rms_arcsec": round(residual_rms, 4),
        "noise_rms_arcsec": round(noise_rms, 4),
        "misfit": not all(c["passed"] for c in checks),
        "ranking": ranking,
        "checks": checks,
        "whiteness": white,
        "noise_posterior": noise_post,
        "noise_stated": {k: settings[k] for k in ("sigma_cross_arcsec", "sigma_about_arcsec", "arw_deg_sqrt_h")},
        "st_correlation_time_s": est.correlation_time_s,
        "residual_rms_per_maneuver_arcsec": per_maneuver,
        "signature_detail_chi2": detail,
        "unexplained_fraction": round(float(fit[[f"outside_{a}" for a in AXES]].to_numpy().mean()), 4),
    }, out_json)


def _loo(idata, model):
    """PSIS-LOO once per model. arviz warns when Pareto k > 0.7 (blocks the posterior
    cannot importance-sample to their leave-out posterior); the count goes in the table
    and the log says what it means, instead of a bare warning."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Estimated shape parameter of Pareto", category=UserWarning)
        loo = az.loo(idata, pointwise=True)
    high = int(np.sum(loo.pareto_k.values > 0.7))
    if high:
        log.info("PSIS-LOO for model %s: %d of %d blocks have Pareto k > 0.7, so its elpd_loo is less "
                 "reliable; typical of a misfitting model, whose residual blocks are influential",
                 model, high, loo.pareto_k.size)
    return loo, high


def run_compare(models, posterior_paths, diagnostics_paths, summary_paths, out_csv, out_png):
    """``model_comparison.csv``: residual RMS and PSIS-LOO per variant, and what moved."""
    diags = [json.loads(Path(p).read_text()) for p in diagnostics_paths]
    loos = {m: _loo(az.from_netcdf(p), m) for m, p in zip(models, posterior_paths)}
    summaries = {m: pd.read_csv(p).set_index("label") for m, p in zip(models, summary_paths)}
    reference = models[0]
    ref_loo = loos[reference][0]
    rows = []
    for m, d in zip(models, diags):
        moved = []
        ref, cur = summaries[reference], summaries[m]
        for label in ref.index.intersection(cur.index):
            if label.startswith("noise."):
                continue
            sd = max(ref.loc[label, "sd"], cur.loc[label, "sd"])
            if abs(cur.loc[label, "mean"] - ref.loc[label, "mean"]) > 2 * sd:
                moved.append(label)
        loo, high = loos[m]
        paired = loo.loo_i.values - ref_loo.loo_i.values
        rows.append({"model": m, "effects": "+".join(d["effects"]),
                     "residual_rms_arcsec": d["residual_rms_arcsec"], "noise_rms_arcsec": d["noise_rms_arcsec"],
                     "misfit": d["misfit"], "elpd_loo": float(loo.elpd_loo), "elpd_loo_se": float(loo.se),
                     "p_loo": float(loo.p_loo),
                     "elpd_diff_vs_first": float(loo.elpd_loo - ref_loo.elpd_loo),
                     "elpd_diff_se": float(np.sqrt(len(paired) * np.var(paired))),
                     "pareto_k_max": float(np.max(loo.pareto_k.values)), "pareto_k_over_0.7": high,
                     f"moved_over_2sd_vs_{reference}": " ".join(moved)})
    table = pd.DataFrame(rows)
    write_csv(table, out_csv)
    fig = plots.comparison_figure(table)
    with atomic(out_png) as tmp:
        plots.save(fig, tmp)


def run_report(results_dir, models, npz_paths, truth_path, cfg, out_html):
    """``report.html``: the pre-uplink review of a campaign (see `gyrocal.report`)."""
    from . import report

    results_dir = Path(results_dir)
    maneuvers = load_maneuvers(npz_paths)
    channels = maneuvers[0].channels
    comparison = pd.read_csv(results_dir / "model_comparison.csv")
    model = report.preferred_model(comparison)
    mdir = results_dir / model
    extras = model_extras(cfg, model, channels)
    calibration = pd.read_csv(mdir / "calibration.csv")
    diag = json.loads((mdir / "diagnostics.json").read_text())
    sampler = json.loads((mdir / "sampler.json").read_text())
    correction_doc = json.loads((mdir / "correction.json").read_text())
    fit = pd.read_csv(mdir / "fit.csv")
    est, _ = load_point_estimate(mdir / "point_estimate.npz", channels, extras)
    truth = json.loads(Path(truth_path).read_text())["parameters"] if truth_path else None
    info = json.loads((results_dir / "input.json").read_text())

    base = calibration[calibration["unit"].isin(["ppm", "arcsec"])]
    scale = contract_scale(channels)
    mean = ch.ChannelParams.from_vector(channels, base["mean"].to_numpy() / scale)
    params = [ch.ChannelParams(channels, mean.sf_pos, mean.sf_neg, mean.mis_rad, est.biases[m])
              for m in range(len(maneuvers))]
    nominal = [ch.ChannelParams(channels, np.zeros(len(channels)), np.zeros(len(channels)),
                                np.zeros((len(channels), 3)), est.biases[m]) for m in range(len(maneuvers))]
    effect_table = report.correction_effect(maneuvers, params, nominal)
    checks = report.verdict_checks(calibration, sampler, diag, effect_table, cfg)

    figures = {}
    for data, path in zip(maneuvers, npz_paths):
        table = pd.read_csv(Path(path).with_suffix(".csv"))
        own = fit[(fit["maneuver"] == data.id) & (fit["set"] == 0)]
        fig = plots.maneuver_figure(table, f"{data.id}: model {model}, in-loop set", own)
        figures[data.id] = report._img(fig) + report._img(plots.residual_figure(fit[fit["maneuver"] == data.id], data.id))
    idata = az.from_netcdf(str(mdir / "posterior.nc"))
    posterior_figs = "".join(report._img(plots.pair_figure(idata, c.name)) for c in channels)
    posterior_figs += report._img(plots.trace_figure(idata, calibration))
    convergence = calibration[["channel", "parameter", "unit", "mean", "sd", "r_hat", "ess_bulk"]].round(
        {"mean": 2, "sd": 2, "r_hat": 4, "ess_bulk": 0})
    accounting = pd.DataFrame([{"maneuver": d.id, **d.counts} for d in maneuvers])
    accounting.loc[len(accounting)] = {"maneuver": "campaign files", "st_read": info["rows"]["star_tracker"],
                                       "st_invalid": info["rows"]["star_tracker_invalid"],
                                       "gyro_read": info["rows"]["gyro"]}
    in_loop = maneuvers[0].sets[0]
    ctx = {
        "campaign": info["campaign"], "model": model, "effects": cfg["models"][model], "checks": checks,
        "simulated": truth is not None,
        "tables": report.paper_tables(calibration, channels, in_loop, truth),
        "maneuver_figures": figures, "posterior_figures": posterior_figs, "convergence": convergence,
        "diagnostics": diag, "comparison": comparison.round(3),
        "comparison_figure": report._img(plots.comparison_figure(comparison)),
        "correction": correction_doc, "correction_path": str(mdir / "correction.json"),
        "effect_table": effect_table.drop(columns=["before norm", "after norm"]).assign(
            **{"before norm (arcsec)": effect_table["before norm"].round(1),
               "after norm (arcsec)": effect_table["after norm"].round(1)}),
        "accounting": accounting, "checksums": info["checksums_sha256"], "sampler": sampler,
        "config": yaml.safe_dump(cfg, sort_keys=False),
    }
    with atomic(out_html) as tmp:
        tmp.write_text(report.render(ctx))
