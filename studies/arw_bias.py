"""Is the fitted angle random walk biased? Simulated campaigns at many seeds, each fitted as the
pipeline fits it (REML about the classic start, `estimate.point_estimate`), and again with one
thing changed at a time, to find where a bias comes from:

- ``reml_truth``: REML of the noise about the true parameters and biases (the linearisation point);
- ``ml_truth``: maximum likelihood instead of REML there (the degrees of freedom the fit takes);
- ``reml_raw_columns``: REML about the truth with the model's columns not smoothed
  (`errormodel.smoothed_columns`, the errors-in-variables guard);
- ``reml_no_pulse``: the pipeline's fit on the same campaign simulated without pulse quantisation;
- ``posterior_mean``: the posterior mean of the ARW (``--posterior``; the config's sampler);
- ``realised``: the ARW the simulator's own draws realise in that campaign.

``--channels dtg1_roll,dtg1_pitch,dtg2_yaw`` flies three of the scenario's channels: one channel
set, as a triad of single-axis gyros, where no second set's difference measures the walk.
``--gyro-hz 2.5`` samples the gyros so that every other 1-Hz star-tracker sample falls mid-interval.
``--misalignment-arcsec 2000,2800`` draws each campaign's misalignments afresh, of either sign and of a
magnitude between the two (a triad far from its nominal axes, as the verdict battery's
``large_misalignment``; the mounting declared correctly).

    python studies/arw_bias.py [--scenario tests/data/tiny.yaml] [--seeds 20] [--posterior] [--out OUT.csv]

Prints each column's ratio to the stated ARW (mean, its standard error, median, how many below 1)
and writes one row per seed. docs/validation.md ("The fitted ARW") has the figures.
"""

import argparse
import copy
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy.optimize import minimize

ROOT = Path(__file__).resolve().parents[1]


def profile_ml(noises, ratios):
    """`noisefit.profile_reml`'s profile with maximum likelihood: the nuisance and the channel
    parameters are fitted, not integrated out (all n data count, no log det of the information)."""
    from gyrocal.inference.fit.likelihood import campaign_stats
    from gyrocal.inference.noise.covariance import variances

    stats = campaign_stats(noises, variances([0.0, ratios[0], ratios[1]]))
    informed = np.diag(stats.A) > 0
    factor = np.linalg.cholesky(stats.A[np.ix_(informed, informed)])
    explained = np.linalg.solve(factor, stats.b[informed])
    scale = (stats.c - explained @ explained) / stats.n
    return 0.5 * (stats.n * np.log(scale) + stats.logdet), 0.5 * np.log(scale)


def noise_at(noises, log_sigma0, ml: bool) -> np.ndarray:
    from gyrocal.inference.fit import noisefit

    if not ml:
        return noisefit.estimate_noise(noises, log_sigma0)[0]
    start = np.asarray(log_sigma0)[1:] - log_sigma0[0]
    opt = minimize(lambda r: profile_ml(noises, r)[0], start, method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-3})
    log_cross = profile_ml(noises, opt.x)[1]
    return np.array([log_cross, log_cross + opt.x[0], log_cross + opt.x[1]])


def realised_arw(scenario, seed) -> float:
    """The ARW (rad/sqrt(s)) the simulator's gyro noise realises in this campaign: the same seed
    simulated without quantisation, with and without the ARW (the generator draws the same
    numbers either way), differ by the noise alone."""
    from gyrocal.simulation import simulate

    runs = []
    for arw in (scenario["gyro"]["arw_deg_sqrt_h"], 0.0):
        s = copy.deepcopy(scenario)
        s["gyro"].update(pulse_arcsec=0.0, arw_deg_sqrt_h=arw)
        runs.append(simulate.simulate(s, seed)[0])
    noisy, clean = (np.column_stack([c.gyro_columns[n] for n in c.channel_names]) for c in runs)
    return float(np.sqrt(np.mean((noisy - clean) ** 2) * scenario["gyro_hz"]))


def fit(scenario, seed, cfg, posterior_draws: bool) -> dict:
    from gyrocal.inference import errormodel
    from gyrocal.inference.fit import classic, estimate
    from gyrocal.inference.noise import covariance
    from gyrocal.inference.sampling import posterior
    from gyrocal.inference.sampling.priors import model_priors
    from gyrocal.maneuvers import preprocess
    from gyrocal.model.spec import baseline
    from gyrocal.model.units import deg_h_to_rad_s
    from gyrocal.simulation import simulate

    campaign, truth = simulate.simulate(scenario, seed)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = covariance.noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = baseline(campaign.channels)
    est = estimate.point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    row = {"seed": seed, "point": est.log_sigma[2]}
    theta = spec.core_vector(spec.params_from_contract(truth["parameters"]))
    bias = deg_h_to_rad_s([truth["parameters"][c.name]["bias_deg_h"] for c in spec.channels])
    log_sigma0 = covariance.log_sigma_of(stated)
    for name, ml, raw in (("reml_truth", False, False), ("ml_truth", True, False), ("reml_raw_columns", False, True)):
        smoothed = errormodel.smoothed_columns
        if raw:
            errormodel.smoothed_columns = lambda columns, dt, st: columns
        try:
            lins = [errormodel.linearize(d, spec, theta, bias) for d in maneuvers]
        finally:
            errormodel.smoothed_columns = smoothed
        noises = [covariance.build(lin, stated["boresight_body"]) for lin in lins]
        row[name] = noise_at(noises, log_sigma0, ml)[2]
    row["realised"] = np.log(realised_arw(scenario, seed))
    quiet = copy.deepcopy(scenario)
    quiet["gyro"]["pulse_arcsec"] = 0.0
    campaign0, _ = simulate.simulate(quiet, seed)
    maneuvers0 = [preprocess.slice_maneuver(campaign0, m.id) for m in campaign0.maneuvers]
    row["reml_no_pulse"] = estimate.point_estimate(maneuvers0, spec, stated,
                                                   classic.classic_start(maneuvers0, spec)).log_sigma[2]
    if posterior_draws:
        priors = model_priors(est, cfg["priors"])
        post = posterior.run(posterior.prepare(maneuvers, est, priors, cfg["grid"]), cfg["sampler"], seed)
        arw = np.exp(post.result.chains[..., -1])
        row["posterior_mean"] = np.log(arw.mean())
    stated_arw = covariance.stated_si(stated)[2]
    return {k: (float(np.exp(v) / stated_arw) if k != "seed" else v) for k, v in row.items()}


def with_misalignments(scenario, bounds_arcsec, seed):
    """The scenario with every channel's misalignments drawn afresh for ``seed``: either sign, magnitude
    uniform between ``bounds_arcsec``."""
    rng = np.random.default_rng([seed, 2800])
    out = copy.deepcopy(scenario)
    for values in out["truth"].values():
        for key in values:
            if key.startswith("mis_"):
                values[key] = float(rng.choice([-1.0, 1.0]) * rng.uniform(*bounds_arcsec))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default=str(ROOT / "tests" / "data" / "tiny.yaml"))
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--posterior", action="store_true")
    parser.add_argument("--channels", default="", help="comma-separated: fly only these channels")
    parser.add_argument("--gyro-hz", type=float, default=None,
                        help="the gyros' rate; 2.5 puts every other 1-Hz star-tracker sample mid-interval")
    parser.add_argument("--misalignment-arcsec", default="",
                        help="LO,HI: every misalignment drawn per campaign, either sign, magnitude in [LO, HI]")
    parser.add_argument("--out", default=None)
    args = parser.parse_args(argv)
    bounds = [float(v) for v in args.misalignment_arcsec.split(",")] if args.misalignment_arcsec else None
    if bounds is not None and not (len(bounds) == 2 and 0.0 <= bounds[0] <= bounds[1]):
        parser.error(f"--misalignment-arcsec: two numbers LO,HI with 0 <= LO <= HI, got {args.misalignment_arcsec}")
    from gyrocal.io.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    scenario["star_tracker"]["invalid_fraction"] = 0.0
    if args.gyro_hz:
        scenario["gyro_hz"] = args.gyro_hz
    if args.channels:
        keep = args.channels.split(",")
        scenario["channels"] = {k: v for k, v in scenario["channels"].items() if k in keep}
        scenario["in_loop"] = keep
        scenario["truth"] = {k: v for k, v in scenario["truth"].items() if k in keep}
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    rows = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        flown = with_misalignments(scenario, bounds, seed) if bounds else scenario
        rows.append(fit(flown, seed, cfg, args.posterior))
        print(" ".join(f"{k}={v:.4f}" if k != "seed" else f"seed={v}" for k, v in rows[-1].items()), flush=True)
    table = pd.DataFrame(rows)
    if args.out:
        table.to_csv(args.out, index=False)
    summary = pd.DataFrame({
        "mean": table.drop(columns="seed").mean(),
        "se": table.drop(columns="seed").std(ddof=1) / np.sqrt(len(table)),
        "median": table.drop(columns="seed").median(),
        "below_1": (table.drop(columns="seed") < 1).sum(),
    })
    print(f"\nARW fitted / stated over {len(table)} campaigns of {Path(args.scenario).name}"
          f"{' with ' + args.channels if args.channels else ''}"
          f"{', misalignments ' + args.misalignment_arcsec + ' arcsec' if args.misalignment_arcsec else ''}:")
    print(summary.to_string(float_format=lambda v: f"{v:.4f}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
