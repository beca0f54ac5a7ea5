"""The Gauss-Markov validation (issue 30): star-tracker noise white plus first-order Gauss-Markov.

    python studies/gauss_markov.py run --tau 3 --n 200 --out /tmp/gm       # one record per campaign
    python studies/gauss_markov.py run --tau 30 --n 200 --out /tmp/gm
    python studies/gauss_markov.py run --tau 0 --n 100 --out /tmp/gm                  # the white control
    python studies/gauss_markov.py run --tau 3 --n 20 --sampled --out /tmp/gm_full   # + the full sampler
    python studies/gauss_markov.py summary /tmp/gm /tmp/gm_full                       # prints the tables

Each campaign is the tiny hidden-effect campaign (tests/data/hidden_st_correlated_noise.yaml:
six single-axis maneuvers, 1 Hz star tracker, 60 s holds) with its channel parameters drawn from
the configured prior, as in the validation study, and star-tracker noise white (5 / 20 arcsec
across / about the boresight) plus a Gauss-Markov part of the same sd and anisotropy (share 0.5)
and correlation time ``tau``. Per campaign, in this process:

- the ``st_correlated_noise`` model's point estimate (REML of the five noise scales, then WLS);
- its channel parameters' exact conditional Gaussian posterior at the REML noise
  (`likelihood.conditional_posterior`, what the sampler's intervals reduce to when the noise is
  well determined): 95 % (and 50, 90 %) intervals against the truth;
- the Cramér-Rao bound of the correlated model at the true noise (`planning.plan.crlb_sd` on the
  statistics at the true scales and tau), and the conditional posterior at the true noise (what
  the intervals would be were the noise known: the share of any shortfall that the noise's
  estimation causes);
- the baseline (white) model's point estimate on the same data, with the diagnostics' whiteness
  and structure checks and its ranking of explanations (`criticism.diagnostics`);
- with ``--sampled``, both models' whole steps up to the diagnostics (`pipeline.run.calibrate_campaign`,
  the default sampler), for the sampler's intervals beside the conditional ones and the baseline's
  full ``diagnostics.json``.

``--tau 0`` is the control: white star-tracker noise alone (5 / 20 arcsec), fitted by the white
model only, whose conditional intervals should cover as the validation study's do.

Records are written one JSON file per campaign, so a run can be stopped and resumed.
"""

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from gauss_markov_tables import summary

ROOT = Path(__file__).resolve().parents[1]
BASE = ROOT / "tests/data/hidden_st_correlated_noise.yaml"
WHITE_ARCSEC = (5.0, 20.0)
GM_SHARE = 0.5


def scenario_for(tau_s: float, index: int, truth: dict, gap_s=None) -> dict:
    """The base campaign flown with ``truth``, white plus Gauss-Markov star-tracker noise of correlation time
    ``tau_s``; ``gap_s``, the time between maneuvers (the base campaign's 20 s where None)."""
    from gyrocal.simulation.simulate import load_scenario

    base = load_scenario(BASE)
    if gap_s is not None:
        base["maneuver_defaults"]["gap_s"] = float(gap_s)
    ratio = np.sqrt(GM_SHARE / (1 - GM_SHARE)) if tau_s > 0 else 0.0  # tau 0: white noise alone (the control)
    base["star_tracker"].update(gm_sigma_cross_arcsec=WHITE_ARCSEC[0] * ratio,
                                gm_sigma_about_arcsec=WHITE_ARCSEC[1] * ratio, gm_tau_s=float(tau_s),
                                sigma_cross_arcsec=WHITE_ARCSEC[0], sigma_about_arcsec=WHITE_ARCSEC[1])
    base["effects"]["st_correlation_time_s"] = 0.0
    base.update(name=f"gm_tau{tau_s:g}_{index}", seed=int(1000003 * tau_s) + index, truth=truth)
    return base


def true_log_sigma(scenario: dict) -> np.ndarray:
    """The correlated model's five noise scales (SI) of the simulated noise: total sd, ARW, logit share, log tau."""
    from gyrocal.model.units import arcsec_to_rad, arw_to_rad_sqrt_s

    st = scenario["star_tracker"]
    cross = np.hypot(st["sigma_cross_arcsec"], st["gm_sigma_cross_arcsec"])
    about = np.hypot(st["sigma_about_arcsec"], st["gm_sigma_about_arcsec"])
    share = max(st["gm_sigma_cross_arcsec"] ** 2 / cross**2, 1e-12)
    return np.array([np.log(arcsec_to_rad(cross)), np.log(arcsec_to_rad(about)),
                     np.log(arw_to_rad_sqrt_s(scenario["gyro"]["arw_deg_sqrt_h"])),
                     np.log(share / (1 - share)), np.log(max(st["gm_tau_s"], 1e-12))])


def intervals(spec, theta, cov) -> dict:
    """Per parameter, the conditional posterior's mean and sd in the parameters' units."""
    return {"mean": spec.to_unit(theta).tolist(), "sd": (np.sqrt(np.diag(cov)) / spec.si_per_unit).tolist()}


def one(tau_s: float, index: int, cfg: dict, sampled: bool, baseline_every: int = 1, gap_s=None) -> dict:
    from gyrocal import checks
    from gyrocal.criticism import diagnostics
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import linearize_all, point_estimate
    from gyrocal.inference.fit.likelihood import campaign_stats, conditional_posterior
    from gyrocal.inference.noise import segments
    from gyrocal.inference.noise.covariance import noise_knowledge, scales_in_units, variances
    from gyrocal.inference.sampling.priors import Priors
    from gyrocal.io.telemetry import write_campaign
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec
    from gyrocal.planning.plan import crlb_sd
    from gyrocal.simulation import simulate
    from gyrocal.study.campaign import draw_truth, prior_spec

    rng = np.random.default_rng([int(tau_s * 1000), index])
    channels = simulate.scenario_channels(simulate.load_scenario(BASE))
    truth = draw_truth(prior_spec(channels, cfg["priors"]), rng)
    scenario = scenario_for(tau_s, index, truth, gap_s)
    record = {"tau_s": tau_s, "index": index, "true_log_sigma": true_log_sigma(scenario).tolist()}
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="gyrocal-gm-") as tmp:
        campaign, _ = simulate.simulate(scenario)
        write_campaign(campaign, Path(tmp) / "campaign")
        campaign, _ = checks.read_checked(Path(tmp) / "campaign")
        maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
        stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
        models = {}
        fitted = ("st_correlated_noise", "baseline")[:1 + (index % baseline_every == 0)] if tau_s > 0 else ("baseline",)
        for model in fitted:
            names = list(effects.BASELINE) + ([model] if model != "baseline" else [])
            spec = ModelSpec.build(model, effects.resolve(model, names, {}), maneuvers[0].channels)
            est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
            spec = est.spec.with_priors(cfg["priors"])
            priors = Priors.from_spec(spec, stated, cfg["priors"]["noise_log_sd"])
            lins, noises = linearize_all(maneuvers, est)
            chained = segments.Chains.of(maneuvers)  # the likelihood the posterior samples (its grid)
            parts = chained.noises(lins, est.boresight, est.correlation_time_s) if spec.correlated_noise else noises
            stats = campaign_stats(parts, variances(est.log_sigma))
            mean, cov = conditional_posterior(stats, priors.mean - est.theta, priors.sd)
            true = np.array([truth[p.owner][p.name] if p.core else 0.0 for p in spec.parameters])
            out = {"labels": list(spec.labels), "core": [bool(p.core) for p in spec.parameters],
                   "free": spec.free.tolist(), "truth": true.tolist(), "wls": spec.to_unit(est.theta).tolist(),
                   "log_sigma": est.log_sigma.tolist(), "scales": scales_in_units(est.log_sigma).tolist(),
                   **intervals(spec, est.theta + mean, cov)}
            if model == "st_correlated_noise":
                true_ls = true_log_sigma(scenario)
                true_noises = chained.noises(lins, est.boresight, float(np.exp(true_ls[4])))
                at_truth = campaign_stats(true_noises, variances(true_ls))
                out["crlb_sd"] = (crlb_sd(at_truth.A, spec.free, spec.prior_sd_si) / spec.si_per_unit).tolist()
                mean_t, cov_t = conditional_posterior(at_truth, priors.mean - est.theta, priors.sd)
                out["at_true_noise"] = intervals(spec, est.theta + mean_t, cov_t)
            else:
                white = diagnostics.whiteness(maneuvers, zip(lins, noises), est)
                ranking, _ = diagnostics.rank(maneuvers, est, list(maneuvers[0].extras), (), white)
                out["whiteness_z"] = white["z"]
                out["ranking"] = [{"name": r["name"], "kind": r["kind"], "log10_p": r["log10_p"]} for r in ranking[:5]]
                out["stated"] = {k: stated[k] for k in ("sigma_cross_arcsec", "sigma_about_arcsec", "arw_deg_sqrt_h")}
            models[model] = out
        record["models"] = models
        record["seconds_point"] = time.perf_counter() - start
        if sampled:
            record["sampled"] = full_run(Path(tmp) / "campaign", Path(tmp) / "work", cfg, index)
    record["seconds"] = time.perf_counter() - start
    return record


def full_run(campaign_dir, work, cfg, index) -> dict:
    """Both models through the default sampler and the diagnostics; their posterior means, sd and
    95 % intervals, and the baseline's ``diagnostics.json`` verdict and ranking."""
    import pandas as pd

    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.run import calibrate_campaign

    models = ["baseline", "st_correlated_noise"]
    model_cfg = {**cfg, "seed": 1000 + index,
                 "models": {"baseline": ["scale_factor", "misalignment", "bias"],
                            "st_correlated_noise": ["scale_factor", "misalignment", "bias", "st_correlated_noise"]}}
    paths = CampaignPaths.under(work)
    calibrate_campaign(campaign_dir, paths, model_cfg, models, figures=False)
    out = {}
    for model in models:
        d = Path(work) / model
        if (d / "refused.json").exists():  # refused or stopped: its reason, in place of a posterior
            out[model] = {"refused": json.loads((d / "refused.json").read_text())["reason"]}
            continue
        summary = pd.read_csv(d / "posterior_summary.csv")
        diag = json.loads((d / "diagnostics.json").read_text())
        sampler = json.loads((d / "sampler.json").read_text())
        out[model] = {"summary": json.loads(summary.to_json(orient="records")), "misfit": diag["misfit"],
                      "failed": [c["check"] for c in diag["checks"] if not c["passed"]],
                      "ranking": [r["name"] for r in diag["ranking"][:3]], "converged": sampler["converged"],
                      "steps": sampler["steps"], "whiteness_z": diag["whiteness"]["z"]}
    return out


def run(args):
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for index in range(args.first, args.first + args.n):
        path = out / f"tau{args.tau:g}_{index:04d}.json"
        if path.exists():
            continue
        record = one(args.tau, index, cfg, args.sampled, args.baseline_every, args.gap_s)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(record))
        tmp.replace(path)
        print(f"tau {args.tau:g} s, campaign {index}: {record['seconds']:.1f} s", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="simulate and fit campaigns, one JSON record each")
    r.add_argument("--tau", type=float, required=True)
    r.add_argument("--n", type=int, default=200)
    r.add_argument("--first", type=int, default=0)
    r.add_argument("--sampled", action="store_true", help="also run the full sampler and diagnostics")
    r.add_argument("--baseline-every", type=int, default=1, help="fit the white model on every k-th campaign")
    r.add_argument("--gap-s", type=float, default=None, help="time between maneuvers (s); the base campaign's 20 s if not given")
    r.add_argument("--out", required=True)
    s = sub.add_parser("summary", help="print the tables of the records in the given folders")
    s.add_argument("folders", nargs="+")
    args = parser.parse_args()
    if args.command == "run":
        run(args)
    else:
        summary([Path(f) for f in args.folders])


if __name__ == "__main__":
    main()
