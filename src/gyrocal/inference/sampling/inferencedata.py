"""What the posterior step writes: the InferenceData, its summary, the fit table and the rest.

`assemble` turns a sampled `posterior.Posterior` into an arviz InferenceData holding
the thinned posterior (in each parameter's unit), the leave-one-block-out pointwise
log-likelihood PSIS-LOO needs, and a posterior predictive of the attitude errors;
with it, the per-sample fit table behind the report's figures, the posterior summary,
the sampler record, PSIS-LOO per block, the exact leave-one-maneuver-out densities and the
channel sets' non-orthogonality (`Outputs`). The array maths lives in `predictive`; this is the
xarray layer.
"""

import logging
import warnings
from dataclasses import dataclass

import arviz as az
import numpy as np
import pandas as pd
import xarray as xr
from scipy.special import expit

from gyrocal import __version__
from gyrocal.inference.noise.covariance import (
    GM_FRACTION_SCALE,
    GM_TAU_SCALE,
    build,
    correlation_time_of,
    noise_scales,
    position,
    ratios_of,
    scales_in_units,
    stated_scales,
)
from gyrocal.inference.noise.parts import SPLIT_KEYS, split_parts, white_log_sigma, white_stated
from gyrocal.inference.sampling import predictive
from gyrocal.inference.sampling.posterior import leave_one_maneuver_out
from gyrocal.inference.sampling.predictive import PARETO_K_MAX
from gyrocal.maneuvers import preprocess
from gyrocal.model import channels as ch
from gyrocal.model import combinations, orthogonality
from gyrocal.model.correction import flown_sets
from gyrocal.model.units import AXES, rad_to_arcsec

__all__ = ["CI_PROB", "ORTHOGONALITY_COLUMNS", "Outputs", "assemble", "combination_summary", "loo", "loo_blocks",
           "noise_split_summary", "orthogonality_summary", "orthogonality_table", "posterior_dataset", "sampler_record",
           "summarize"]

log = logging.getLogger("gyrocal")

def loo(idata, model: str):
    """PSIS-LOO of one model (arviz). arviz warns about blocks with Pareto k > `PARETO_K_MAX` (the
    posterior cannot importance-sample their leave-out posterior); the log says how many and what
    it means instead, and `comparison.compare` counts them in its table."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Estimated shape parameter of Pareto", category=UserWarning)
        result = az.loo(idata, pointwise=True)
    high = int(np.sum(result.pareto_k.values > PARETO_K_MAX))
    if high:
        log.info("PSIS-LOO for model %s: %d of %d blocks have Pareto k > %g, so its elpd_loo is less "
                 "reliable; typical of a misfitting model, whose residual blocks are influential",
                 model, high, result.pareto_k.size, PARETO_K_MAX)
    return result


def loo_blocks(idata, model: str) -> pd.DataFrame:
    """``elpd_blocks.csv``: PSIS-LOO per block (`loo`), with each block's lppd (arviz's) and share of
    p_loo (its lppd less its elpd), so that the model's elpd_loo, its se and p_loo follow from the
    table alone, as arviz's ``loo`` gives them (`comparison.loo_totals`), and the comparison needs
    neither arviz nor the InferenceData."""
    result = loo(idata, model)
    loglik = idata.log_likelihood["attitude_error"]
    flat = loglik.values.reshape(-1, loglik.sizes["block"])
    top = flat.max(axis=0)  # arviz's logsumexp, step for step: its lppd to the bit, as `loo` sums it
    lppd = np.log(np.exp(flat - top).sum(axis=0)) + (top - np.log(len(flat)))
    elpd = result.loo_i.values
    return pd.DataFrame({"block": [str(b) for b in loglik.coords["block"].values], "elpd_loo": elpd,
                         "lppd": lppd, "p_loo": lppd - elpd, "pareto_k": result.pareto_k.values})


def posterior_dataset(draws, theta_hat, spec, noise_groups=()) -> az.InferenceData:
    """(chains, draws, P + k) sampled offsets and the k log noise scales of the model
    (`covariance.noise_scales`), in the parameters' units; with ``noise_groups`` (more than one), each
    group's level (its ``sigma_cross`` over the campaign's) and their log sd follow, as
    ``noise_group_level`` and ``noise_group_sd``."""
    p = len(spec)
    scales = noise_scales(spec.correlated_noise, spec.jitter_noise)
    k = len(scales)
    values = spec.to_unit(theta_hat + draws[..., :p])
    noise = scales_in_units(draws[..., p:p + k])
    posterior = {"channel_param": values, **{s.key: noise[..., i] for i, s in enumerate(scales)}}
    coords, dims = {"parameter": spec.labels}, {"channel_param": ["parameter"]}
    if len(noise_groups) > 1:
        posterior["noise_group_level"] = np.exp(draws[..., p + k:-1] - draws[..., p:p + 1])
        posterior["noise_group_sd"] = np.exp(draws[..., -1])
        coords["noise_group"] = list(noise_groups)
        dims["noise_group_level"] = ["noise_group"]
    return az.from_dict(posterior=posterior, coords=coords, dims=dims)


CI_PROB = 0.95
"""The credible interval of the summary: central, as arviz's ``summary`` gives its ETI."""


def summarize(idata, per_walker, labels, convergence: dict) -> pd.DataFrame:
    """Mean, sd and central 95 % interval over every draw, computed as arviz's ``summary`` does
    (xarray over chain and draw; the interval's tails at ``(1 - CI_PROB) / 2``), to the bit, without
    the HDI it also sorts every parameter for; r_hat across the independent ensembles (each one
    chain, step-major) and bulk ESS over every walker's own chain (arviz)."""
    rhat = az.rhat(idata)
    ess = az.ess(per_walker, method="bulk")
    draws = idata.posterior
    mean, sd = draws.mean(dim=("chain", "draw")), draws.std(dim=("chain", "draw"), ddof=1)
    tail = (1 - CI_PROB) / 2
    low, high = (draws.quantile(q, dim=("chain", "draw")) for q in (tail, 1 - tail))
    rows = []
    keys = [s.key for s in noise_scales(True, True)] + [key for parts in SPLIT_KEYS.values() for key in parts]
    noise_labels = [f"noise.{key}" for key in keys if key in draws]
    group_labels = {}
    if "noise_group_level" in draws:
        group_labels = {f"noise.level.{g}": ("noise_group_level", {"noise_group": g})
                        for g in draws.coords["noise_group"].values}
        group_labels["noise.group_sd"] = ("noise_group_sd", {})
    for label in list(labels) + noise_labels + list(group_labels):
        if label in noise_labels:
            name, sel = label.removeprefix("noise."), {}
        elif label in group_labels:
            name, sel = group_labels[label]
        else:
            name, sel = "channel_param", {"parameter": label}
        value = {k: float(v[name].sel(sel)) for k, v in (("mean", mean), ("sd", sd), ("ci95_low", low),
                                                          ("ci95_high", high), ("r_hat", rhat), ("ess_bulk", ess))}
        rows.append({"label": label, **value})
    frame = pd.DataFrame(rows)
    frame["converged"] = (frame["r_hat"] < convergence["r_hat_max"]) & (frame["ess_bulk"] >= convergence["ess_bulk_min"])
    return frame


def _derived_summary(full, per_walker, labels, draws_of, convergence: dict) -> pd.DataFrame:
    """`summarize` of quantities derived draw by draw from the parameters' draws (``draws_of``: the
    parameters' draws (..., P) in their units to the derived ones (..., K)), so that the parameters'
    correlation is honoured."""

    def derived(idata):
        values = draws_of(idata.posterior["channel_param"].to_numpy())
        with warnings.catch_warnings():
            # per walker, every walker is a chain: a short run may have more walkers than steps
            warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
            return az.from_dict(posterior={"channel_param": values}, coords={"parameter": labels},
                                dims={"channel_param": ["parameter"]})

    return summarize(derived(full), derived(per_walker), labels, convergence)


def combination_summary(full, per_walker, spec, convergence: dict) -> pd.DataFrame | None:
    """`summarize` of the identifiable combinations (`combinations.scale_combinations`: ``sf_mean``,
    ``sf_asym``), computed draw by draw from the parameters' draws, so their correlation is honoured;
    None for a model with no scale factor."""
    combos = combinations.scale_combinations(spec)
    if not combos:
        return None
    return _derived_summary(full, per_walker, [c.label for c in combos],
                            lambda values: combinations.combination_draws(values, combos), convergence)


def noise_split_summary(full, per_walker, convergence: dict) -> pd.DataFrame | None:
    """`summarize` of the star tracker's white and Gauss-Markov parts (`parts.split_parts`), draw by
    draw, so their intervals are the posterior's; None for a model with no Gauss-Markov share."""

    def split(idata):
        draws = idata.posterior
        parts = split_parts({k: draws[k].to_numpy() for k in (*SPLIT_KEYS, GM_FRACTION_SCALE.key) if k in draws})
        return az.from_dict(posterior=parts) if parts else None

    whole = split(full)
    if whole is None:
        return None
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
        return summarize(whole, split(per_walker), [], convergence)


def orthogonality_summary(full, per_walker, spec, pairs, convergence: dict) -> pd.DataFrame | None:
    """`summarize` of the channel sets' non-orthogonality (`orthogonality.pair_draws`, arcsec), draw by
    draw; None where there are no ``pairs`` (a model without misalignments)."""
    if not pairs:
        return None
    return _derived_summary(full, per_walker, [p.label for p in pairs],
                            lambda values: orthogonality.pair_draws(values, spec, pairs), convergence)


def sampler_record(post, summary, sampler_cfg: dict, seed: int) -> dict:
    """``sampler.json``: the convergence verdict and what it rests on."""
    res, est = post.result, post.estimate
    return {
        "converged": bool(summary["converged"].all() and res.converged_length),
        "chain_length_ok": res.converged_length,
        "steps": res.steps, "burn_steps": res.burn, "refits": res.refits, "walkers": res.walkers,
        "ensembles": int(res.chains.shape[0]), "seed": seed,
        "tau_max_steps": float(res.tau.max()), "steps_over_tau": float(res.steps / res.tau.max()),
        "acceptance": res.acceptance.tolist(),
        "grid": {"nodes": post.grid.nodes, "start": post.grid.start.tolist(), "step": post.grid.step.tolist()},
        "settings": dict(sampler_cfg),
        "point_estimate": {"cost": est.cost, "nfev": est.nfev, "message": est.message,
                           "noise": stated_scales(est.log_sigma), "st_correlation_time_s": est.correlation_time_s},
        "failed_parameters": summary.loc[~summary["converged"], "label"].tolist(),
    }


def _correlated_replicates(post, lin, log_sigma, ratios, level, rng) -> np.ndarray:
    """(D, M, S, 3) noise replicates of a model with a Gauss-Markov part, per draw's ``log_sigma`` (D, k)
    and noise-group ``level`` (D,): the white part, walk and jitter through the white model's
    differences (`covariance.build` at tau 0, whitened at the draws' mean ratios), and the Gauss-Markov
    part drawn as its process (`predictive.gauss_markov_draws`, at the draws' mean tau, as the filter
    is built), each draw's white part at its own scale. The walk and jitter take the draws' mean ratios to
    the white part (one whitening), so where the white share varies across draws a draw's walk is off by
    that ratio's spread (a few % on BROAD). The band is the noise's unconditional spread: the fitted
    attitude offset and bias take part of a slow error, which the data's residual has lost, so it holds
    more than 95 % of a fitting model's samples, and the band check, one-sided, can only flag too few."""
    share = expit(log_sigma[:, position(log_sigma, GM_FRACTION_SCALE)])
    white = np.delete(white_log_sigma(log_sigma),
                      [position(log_sigma, GM_FRACTION_SCALE), position(log_sigma, GM_TAU_SCALE)], axis=1)
    est = post.estimate
    nz_white = build(lin, est.boresight, 0.0, est.spec.jitter_noise)
    wm_white = predictive.WhitenedManeuver(nz_white, np.mean(ratios_of(white), axis=0))
    series = predictive.undifference_body(lin, wm_white.noise_draws(np.exp(2 * white[:, 0]) * level, rng), nz_white)
    gm_cross, gm_about = (np.exp(2 * log_sigma[:, i]) * share * level for i in (0, 1))
    return series + predictive.gauss_markov_draws(lin.gm_steps, correlation_time_of(ratios), est.boresight,
                                                  gm_cross, gm_about, lin.z.shape[1], rng)


def _fit_and_predictive(post, maneuvers, kept, sampler_cfg, seed):
    """Pointwise leave-one-block-out log-likelihood, the fit table and predictive draws, maneuver by
    maneuver; each maneuver's linearisation and noise are taken out of ``post`` on the way
    (`posterior.Posterior.take_maneuvers`)."""
    p = post.n_params
    n_chain, n_draw = kept.shape[:2]
    flat = kept.reshape(-1, kept.shape[-1])
    k = len(post.estimate.log_sigma)
    dtheta, ratios, scale2 = predictive.split_draws(flat, p, k)
    offsets = flat[:, p + k:-1] - flat[:, p:p + 1] if post.group_index is not None else None
    n_pred = min(sampler_cfg["predictive_draws"], n_draw)
    pred_rows = (np.arange(n_chain)[:, None] * n_draw + np.arange(n_pred)[None]).ravel()
    rng = np.random.default_rng([seed, 99])
    loglik, block_names, fit_tables = [], [], []
    pp_values, obs_values, sample_maneuver, sample_time = [], [], [], []
    zeros = ch.ChannelParams.zeros(maneuvers[0].channels)
    for m, (data, (lin, nz)) in enumerate(zip(maneuvers, post.take_maneuvers(), strict=True)):
        level = 1.0 if offsets is None else np.exp(2 * offsets[:, post.group_index[m]])
        if nz.filter is not None:  # Gauss-Markov noise: filtered at the draws' mean correlation time
            nz = build(lin, post.estimate.boresight, correlation_time_of(ratios), post.estimate.spec.jitter_noise)
        wm = predictive.WhitenedManeuver(nz, ratios)
        blocks = predictive.block_index(lin, data.st_time, sampler_cfg["block_s"])
        loglik.append(predictive.leave_block_out_loglik(lin, wm, dtheta, scale2 * level, blocks))
        block_names += [f"{data.id}:{b}" for b in range(blocks.max() + 1)]
        resid = predictive.residuals_body(lin, dtheta[pred_rows], wm.nuisance(dtheta[pred_rows]))
        if nz.filter is None:
            noise_rep = predictive.undifference_body(lin, wm.noise_draws((scale2 * level)[pred_rows], rng), nz)
        else:
            noise_rep = _correlated_replicates(post, lin, flat[pred_rows, p:p + k], ratios,
                                               (level * np.ones(len(flat)))[pred_rows], rng)
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
    sample_coords = {"axis": list(AXES), "maneuver": ("sample", sample_maneuver),
                     "time": ("sample", np.concatenate(sample_time))}
    groups = {
        "log_likelihood": xr.Dataset({"attitude_error": (("chain", "draw", "block"), loglik)},
                                     coords={"chain": np.arange(n_chain), "draw": np.arange(n_draw),
                                             "block": block_names}),
        "posterior_predictive": xr.Dataset({"attitude_error": (("chain", "draw", "sample", "axis"), pp)},
                                           coords={"chain": np.arange(n_chain), "draw": np.arange(n_pred),
                                                   **sample_coords}),
        "observed_data": xr.Dataset({"attitude_error": (("sample", "axis"), np.concatenate(obs_values))},
                                    coords=sample_coords),
    }
    return groups, pd.concat(fit_tables, ignore_index=True)


ORTHOGONALITY_COLUMNS = ["set", "channels", "parameter", "unit", "definition", "point", "mean", "sd", "ci95_low",
                         "ci95_high", "r_hat", "ess_bulk", "prior_only"]
"""``orthogonality.csv``'s columns (docs/interface.md section 5)."""


def orthogonality_table(spec, point_theta, pairs, summary: pd.DataFrame | None) -> pd.DataFrame:
    """``orthogonality.csv``: per channel set, the non-orthogonality of each pair of its channels
    (`gyrocal.model.orthogonality`) from the point estimate (SI) and its posterior ``summary``
    (`orthogonality_summary`, arcsec), beside ``calibration.csv``'s ``sf_mean``; a table of its own,
    so that ``calibration.csv`` keeps its rows. No rows for a model without misalignments."""
    point = orthogonality.pair_draws(spec.to_unit(point_theta), spec, pairs) if pairs else []
    rows = []
    for p, value in zip(pairs, point, strict=True):
        row = summary.loc[summary["label"] == p.label].iloc[0]
        rows.append({"set": p.set, "channels": "+".join(p.channels), "parameter": p.name, "unit": "arcsec",
                     "definition": p.definition, "point": float(value),
                     **{k: row[k] for k in ORTHOGONALITY_COLUMNS[6:-1]}, "prior_only": p.prior_only})
    return pd.DataFrame(rows, columns=ORTHOGONALITY_COLUMNS)


@dataclass
class Outputs:
    """Everything the posterior step writes, each under its `ModelPaths` name."""

    posterior: az.InferenceData
    summary: pd.DataFrame
    fit: pd.DataFrame
    sampler: dict
    elpd_blocks: pd.DataFrame
    elpd_maneuvers: pd.DataFrame
    orthogonality: pd.DataFrame


def assemble(post, maneuvers, priors, sampler_cfg: dict, convergence: dict, seed: int) -> Outputs:
    """Everything the posterior step writes (`Outputs`) from a sampled ``post`` and its ``priors``.

    ``post``'s linearisations and noise structures are used up (`_fit_and_predictive`).
    The summary and convergence use every draw (the summary also holds the identifiable
    combinations, after the noise scales; the sampler record judges the parameters alone); the InferenceData keeps
    ``loglik_draws`` evenly spaced draws per ensemble, with the pointwise
    log-likelihood per ``block_s`` block and ``predictive_draws`` predictive draws. The channel sets'
    non-orthogonality (every flown set's pairs, `orthogonality.pairs`) is summarised from every draw,
    like the summary.
    """
    spec, theta_hat = post.estimate.spec, post.estimate.theta
    groups = post.estimate.noise_groups if post.group_index is not None else ()
    draws = post.ensemble_draws()
    full = posterior_dataset(draws, theta_hat, spec, groups)
    with warnings.catch_warnings():
        # every walker is a chain here, and a short run may have more walkers than steps
        warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
        per_walker = posterior_dataset(post.walker_draws(), theta_hat, spec, groups)
    summary = summarize(full, per_walker, spec.labels, convergence)
    record = sampler_record(post, summary, sampler_cfg, seed)
    derived = [combination_summary(full, per_walker, spec, convergence)]
    if white_stated(priors.stated_noise or {}):  # the part the stated noise judges, and the motion's
        derived.append(noise_split_summary(full, per_walker, convergence))
    summary = pd.concat([summary, *(d for d in derived if d is not None)], ignore_index=True)
    if not record["converged"]:
        log.warning("THE SAMPLER DID NOT CONVERGE: %s; numbers are not reliable",
                    record["failed_parameters"] or "chains shorter than the autocorrelation limit")
    elpd = leave_one_maneuver_out(post, priors)
    thin = np.linspace(0, draws.shape[1] - 1, sampler_cfg["loglik_draws"]).astype(int)
    kept = draws[:, thin]
    extra, fit = _fit_and_predictive(post, maneuvers, kept, sampler_cfg, seed)
    idata = posterior_dataset(kept, theta_hat, spec, groups)
    idata.add_groups(**extra)
    units = ", ".join(f"{label} {unit}" for label, unit in zip(spec.labels, spec.units))
    idata.posterior.attrs.update({"gyrocal_version": __version__, "seed": seed, "units": units,
                                  "prior_only": ", ".join(p.label for p in spec.parameters if p.prior_only)})
    for group in idata.groups():
        idata[group].attrs.pop("created_at", None)  # same config and seed, same bytes
    pairs = orthogonality.pairs(spec, flown_sets(maneuvers))
    orth = orthogonality_summary(full, per_walker, spec, pairs, convergence)
    return Outputs(idata, summary, fit, record, loo_blocks(idata, spec.model),
                   pd.DataFrame({"maneuver": [d.id for d in maneuvers], "elpd": elpd}),
                   orthogonality_table(spec, theta_hat, pairs, orth))
