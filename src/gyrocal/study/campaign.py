"""One campaign of the Monte Carlo validation study: draw, simulate, calibrate, compare with the truth.

Each campaign draws its channel parameters from the configured prior (the prior the posterior
uses, so that simulation-based calibration applies), flies the scenario's maneuvers with its
noise, residual biases and optionally one hidden library effect, and goes through gyrocal's own
steps (`gyrocal.pipeline.run.calibrate_campaign`). Its record holds,
per parameter, the truth beside every estimator, the posterior's quantiles, the SBC rank of the
truth and the Cramér-Rao bound; per model, the misfit checks and the ranking. `gyrocal.study.tables`
aggregates the records.
"""

import copy
import json
import math
import tempfile
from pathlib import Path

import arviz as az
import numpy as np
import pandas as pd
from scipy import stats as sps

from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import PointEstimate, linearize_all
from gyrocal.inference.fit.likelihood import campaign_stats
from gyrocal.inference.noise.covariance import log_sigma_of, variances
from gyrocal.io.outputs import strict
from gyrocal.io.telemetry import write_campaign
from gyrocal.model import effects, spec
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.run import calibrate_campaign
from gyrocal.pipeline.steps.common import load_maneuvers
from gyrocal.planning.plan import crlb_sd
from gyrocal.simulation import simulate

__all__ = [
    "QUANTILES", "QUANTILE_COLUMNS", "campaign_scenario", "classic_rows", "draw_truth", "model_record",
    "prior_spec", "run", "sampler_seed", "sbc_rank", "thinned_draws"
]

QUANTILES = (0.025, 0.05, 0.25, 0.75, 0.95, 0.975)
"""The posterior quantiles a record keeps: the central 50, 90 and 95 % intervals."""

QUANTILE_COLUMNS = tuple(f"q{q * 100:g}" for q in QUANTILES)


def prior_spec(channels, priors_cfg: dict) -> spec.ModelSpec:
    """The baseline's specification with the configured priors: what the posterior will assume."""
    return spec.baseline(channels).with_priors(priors_cfg)


def draw_truth(model_spec: spec.ModelSpec, rng) -> dict:
    """Channel parameters drawn from the prior (normal, truncated at the physical bound), in the
    contract's units: ``{channel: {parameter: value}}``."""
    p = model_spec.parameters
    mean = np.array([x.prior_mean for x in p])
    sd = np.array([x.prior_sd for x in p])
    bound = np.array([x.bound for x in p])
    values = sps.truncnorm.rvs((-bound - mean) / sd, (bound - mean) / sd, loc=mean, scale=sd, random_state=rng)
    truth = {}
    for x, v in zip(p, values):
        truth.setdefault(x.owner, {})[x.name] = float(v)
    return truth


def campaign_scenario(base: dict, truth: dict, hidden: dict, name: str, seed: int) -> dict:
    """The base scenario flown with this truth, seed and hidden effect magnitudes (simulator keys)."""
    out = copy.deepcopy(base)
    out.update(name=name, seed=int(seed), truth=truth)
    out["effects"] = {**out["effects"], **hidden}
    return out


def thinned_draws(draws: np.ndarray, steps: int, walkers: int, tau_steps: float, per_chain: int) -> np.ndarray:
    """``per_chain`` draws of each chain of ``posterior.nc`` (its draws evenly spaced over the
    step-major ``steps * walkers`` of one ensemble), spaced at least ``tau_steps`` apart in steps.

    Raises if the chain is too short for that spacing: SBC needs (nearly) independent draws.
    """
    n_chain, n_kept = draws.shape[:2]
    kept_step = np.linspace(0, steps * walkers - 1, n_kept).astype(int) // walkers
    spacing = steps / per_chain
    if spacing < tau_steps:
        raise ValueError(f"{per_chain} draws per chain of {steps} steps are {spacing:.1f} steps apart, closer "
                         f"than the autocorrelation time {tau_steps:.1f}")
    targets = (np.arange(per_chain) + 0.5) * spacing
    pick = np.abs(kept_step[None, :] - targets[:, None]).argmin(axis=1)
    return draws[:, pick].reshape(n_chain * per_chain, *draws.shape[2:])


def sbc_rank(draws: np.ndarray, truth: np.ndarray, rng) -> np.ndarray:
    """Rank of the truth among the draws per column (ties broken at random): uniform on
    ``0..L`` when the posterior is calibrated (Talts et al. 2018)."""
    below = (draws < truth).sum(axis=0)
    ties = (draws == truth).sum(axis=0)
    return below + rng.integers(0, ties + 1)


def _contract_vector(model_spec, truth: dict, hidden_units: dict) -> np.ndarray:
    """The truth of every parameter of a model in its unit: the channel model's from ``truth``,
    an added effect's from the magnitude the campaign was flown with."""
    out = []
    for p in model_spec.parameters:
        if p.core:
            out.append(truth[p.owner][p.name])
        else:
            out.append(hidden_units.get(p.effect, 0.0))
    return np.array(out, dtype=float)


def model_record(campaign_dir, work, model, truth, hidden_units, known, cfg, study_cfg, rng) -> tuple:
    """Per-parameter rows and the campaign-level facts of one model's run."""
    work = Path(work)
    d = work / model
    ids = json.loads((work / "input.json").read_text())["maneuvers"]
    npz = [work / "preprocess" / f"{m}.npz" for m in ids]  # the campaign's order, which the biases follow
    est = PointEstimate.load(d / "point_estimate.npz", known)
    model_spec = est.spec
    true = _contract_vector(model_spec, truth, hidden_units)
    idata = az.from_netcdf(d / "posterior.nc")
    draws = idata.posterior["channel_param"].sel(parameter=list(model_spec.labels)).to_numpy()
    sampler = json.loads((d / "sampler.json").read_text())
    flat = draws.reshape(-1, draws.shape[-1])
    quantiles = np.quantile(flat, QUANTILES, axis=0)
    thin = thinned_draws(draws, sampler["steps"], sampler["walkers"], sampler["tau_max_steps"],
                         math.ceil(study_cfg["sbc_draws"] / draws.shape[0]))
    ranks = sbc_rank(thin, true, rng)
    maneuvers = load_maneuvers(npz)
    _, noises = linearize_all(maneuvers, est)
    stats = campaign_stats(noises, variances(log_sigma_of(est.stated_noise)))
    prior_sd = model_spec.with_priors(cfg["priors"]).prior_sd_si
    crlb = crlb_sd(stats.A, model_spec.free, prior_sd) / model_spec.si_per_unit
    offsets = lambda values: model_spec.to_si(values) - est.theta
    loglik_truth = float(stats.loglik(offsets(true))[0])
    loglik_draws = stats.loglik(offsets(thin))
    summary = pd.read_csv(d / "posterior_summary.csv").set_index("label")
    rows = pd.DataFrame({"model": model, "label": model_spec.labels,
                         "channel": [p.owner for p in model_spec.parameters],
                         "parameter": [p.name for p in model_spec.parameters], "unit": model_spec.units,
                         "core": [p.core for p in model_spec.parameters], "truth": true,
                         "wls": model_spec.to_unit(est.theta), "mean": flat.mean(axis=0),
                         "sd": summary.loc[list(model_spec.labels), "sd"].to_numpy(),
                         **dict(zip(QUANTILE_COLUMNS, quantiles)), "sbc_rank": ranks, "sbc_draws": len(thin),
                         "crlb_sd": crlb, "converged": summary.loc[list(model_spec.labels), "converged"].to_numpy()})
    diag = json.loads((d / "diagnostics.json").read_text())
    facts = {"model": model, "misfit": diag["misfit"],
             "checks": {c["check"]: c["passed"] for c in diag["checks"]},
             "residual_rms_ratio": diag["residual_rms_arcsec"] / diag["noise_rms_arcsec"],
             "noise_ratio": {k: diag["noise_posterior"][k] / diag["noise_stated"][k] for k in diag["noise_stated"]},
             "whiteness_z": diag["whiteness"]["z"],
             "ranking": [{"name": r["name"], "kind": r["kind"], "log10_p": r["log10_p"], "df": r["df"]}
                         for r in diag["ranking"]],
             "loglik_sbc_rank": int(sbc_rank(loglik_draws[:, None], np.array([loglik_truth]), rng)[0]),
             "sbc_draws": len(thin), "converged": sampler["converged"], "steps": sampler["steps"]}
    return rows, facts


def classic_rows(work, channels) -> pd.DataFrame:
    """The paper's estimate (trusting the bias known before the maneuver) and the same with each
    maneuver's bias estimated from its holds, per channel parameter, in the parameters' units."""
    maneuvers = load_maneuvers(sorted((Path(work) / "preprocess").glob("*.npz")))
    base = spec.baseline(channels)
    paper = classic.classic_table(maneuvers, base, "trusted").set_index(["channel", "parameter"])["value"]
    holds = classic.classic_table(maneuvers, base, "holds").set_index(["channel", "parameter"])["value"]
    return pd.DataFrame({"classic_paper": paper, "classic_holds": holds}).reset_index()


def sampler_seed(study_seed: int, index: int) -> int:
    """Campaign ``index``'s own sampler seed, a stream apart from its simulation's. With one seed
    for all, the 200 posteriors reused nearly the same standardized draws (correlation 0.64
    between two campaigns), so their SBC ranks were not independent (docs/validation.md)."""
    return int(np.random.SeedSequence([int(study_seed), int(index), 1]).generate_state(1)[0])


def run(base_scenario_path, cfg: dict, study_cfg: dict, index: int, group: str, magnitude: float) -> dict:
    """Simulate and calibrate campaign ``index`` of the study's ``group`` ("clean" or a library
    effect flown at ``magnitude``); returns its record (JSON-ready)."""
    seed = int(study_cfg["seed"]) * 100003 + index
    rng = np.random.default_rng([int(study_cfg["seed"]), index])
    base = simulate.load_scenario(base_scenario_path)
    channels = simulate.scenario_channels(base)
    truth = draw_truth(prior_spec(channels, cfg["priors"]), rng)
    hidden, hidden_units, models = {}, {}, ["baseline"]
    if group != "clean":
        effect = study_cfg["effects"][group]
        hidden = {effect["simulator_key"]: float(magnitude)}
        hidden_units = {group: float(magnitude) * effect.get("model_per_simulator_unit", 1.0)}
        if effect["model"]:
            models.append(effect["model"])
    scenario = campaign_scenario(base, truth, hidden, f"study_{group}_{index}", seed)
    model_cfg = {**cfg, "seed": sampler_seed(study_cfg["seed"], index),
                 "models": {"baseline": list(effects.BASELINE), **{m: list(effects.BASELINE) + [group] for m in models[1:]}}}
    known = effects.known(cfg["plugins"])
    with tempfile.TemporaryDirectory(prefix="gyrocal-study-") as tmp:
        campaign, sim_truth = simulate.simulate(scenario)
        campaign_dir = Path(tmp) / "campaign"
        write_campaign(campaign, campaign_dir)
        work = Path(tmp) / "work"
        calibrate_campaign(campaign_dir, CampaignPaths.under(work), model_cfg, models, figures=False,
                           strict=True)
        parts, facts = [], []
        for model in models:
            rows, fact = model_record(campaign_dir, work, model, truth, hidden_units, known, cfg, study_cfg, rng)
            parts.append(rows)
            facts.append(fact)
        table = pd.concat(parts, ignore_index=True).merge(classic_rows(work, campaign.channels),
                                                          on=["channel", "parameter"], how="left")
    record = {"index": index, "group": group, "magnitude": magnitude, "seed": seed,
              "bias_deg_h": {c: v["bias_deg_h"] for c, v in sim_truth["parameters"].items()},
              "models": facts, "parameters": json.loads(table.to_json(orient="records"))}
    return json.loads(json.dumps(strict(record)))
