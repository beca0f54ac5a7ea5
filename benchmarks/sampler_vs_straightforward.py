"""gyrocal's posterior sampler against a straightforward emcee model: prints figures, asserts nothing.

    PYTHONPATH=src python benchmarks/sampler_vs_straightforward.py [--seconds S] [--campaign mom|tiny|both]

For each campaign (default: both, the default MOM scenario ``config/scenarios/mom.yaml`` and the
shortened one ``tests/data/tiny.yaml``), simulated once and sampled by both on the same maneuvers:

1. log-probability evaluations per second of each;
2. bulk ESS (arviz, every walker a chain) of the slowest of the 24 channel parameters, per second
   of sampling and per 1000 evaluations, of each;
3. the ratios gyrocal / straightforward of evaluations per second and of ESS per second;
4. for a few parameters (and a summary over all 24), each one's posterior mean and sd and their
   difference in gyrocal's sd; also the straightforward model's own mode and Laplace sd (least
   squares), which show whether the two *models* agree whatever its sampler did, and the sd of
   gyrocal's linearised model with the gyro random walk cut 100-fold, since the straightforward
   model has none.

gyrocal: `posterior.prepare` and `posterior.run` as the pipeline runs them (the linearised model about the
WLS point estimate, the nuisance integrated out in closed form, four ensembles), timed like
``benchmarks/pipeline.py``: the sampling step, after the point estimate; evaluations per second
of its `LogPosterior` on batches of 64 walkers.

The straightforward model (`Straightforward`) is what a user of emcee writes: every evaluation
applies the calibration to the raw gyro increments of each maneuver and channel set
(`gyrocal.model.correction`, the exact inverse of eq. 3), integrates them from the star tracker's
attitude at the maneuver's start, turned by the maneuver's initial attitude error, compares the
propagated attitude with every star-tracker quaternion (eq. 4) and adds a Gaussian
log-likelihood with the stated star-tracker noise (across and about the boresight, white, each
channel set compared on its own). Parameters, in ppm, arcsec and deg/h: the 24 channel
parameters with gyrocal's priors and bounds, and per maneuver the initial attitude error (3) and
every channel's bias (6), flat priors: 78 dimensions for six maneuvers. The noise scales are held
at the stated values. Plain ``emcee.EnsembleSampler`` (default stretch move, ``vectorize=False``:
one walker per call, a Python loop over maneuvers and the two channel sets), 2 * dim + 2 walkers,
run for a fixed wall-clock budget (``--seconds``); the first half is discarded as burn-in and the
ESS taken on the rest, per second of the whole run. Two choices favour it, so the ratios are
conservative: each propagation is vectorised over the samples with gyrocal's exact
`kinematics.propagate` (scipy `Rotation` quaternions composed by a parallel scan, about 80 times
faster than the per-sample ``R = R * Rotation.from_rotvec(dphi)`` loop), and the walkers start
in the straightforward posterior's own Laplace approximation (mode by
`scipy.optimize.least_squares` from gyrocal's WLS point, covariance from its Jacobian), not in
emcee's customary tiny ball.

A budget of minutes buys the straightforward sampler a few to a few tens of steps, far below the
stretch move's autocorrelation time in 78 dimensions (over a thousand steps), so arviz's ESS of that
run measures its start draws, not its mixing, and is not used for the ratio (it is printed). The
ESS per second is projected instead: the stretch move's ESS per evaluation on a Gaussian of the
same dimension (`stretch_on_gaussian`; affine invariance makes that its mixing on the
straightforward posterior's Laplace approximation, the easiest target of that shape) times the
measured evaluations per second. Also printed: the bound of one effective sample per
straightforward evaluation, which no MCMC run reaches.
"""

import argparse
import functools
import logging
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import arviz as az
import emcee
import numpy as np
import yaml
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation
from simulated import baseline_fit, evaluations_per_s

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = {"mom": ROOT / "config/scenarios/mom.yaml", "tiny": ROOT / "tests/data/tiny.yaml"}
SHOWN = ("dtg2_yaw.sf_pos", "dtg2_yaw.sf_neg", "dtg1_roll.mis_yaw", "dtg3_roll.sf_pos", "dtg1_pitch.mis_roll")
"""Parameters of the agreement check: in-loop and redundant channels, scale factors and misalignments."""


def load_config() -> dict:
    from snakemake.utils import validate
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    validate(cfg, str(ROOT / "workflow/schemas/config.schema.yaml"))
    return cfg


@dataclass
class Campaign:
    """One simulated campaign's maneuvers and the point estimate both samplers start from."""

    name: str
    maneuvers: list
    stated: dict
    estimate: object
    priors: object


def prepare(name: str, cfg: dict) -> Campaign:
    """Simulate the scenario, slice its maneuvers and compute gyrocal's WLS point estimate."""
    fitted = baseline_fit(SCENARIOS[name], cfg)
    return Campaign(name, fitted.maneuvers, fitted.stated, fitted.estimate, fitted.priors)


# --- gyrocal -------------------------------------------------------------------------------


@dataclass
class Figures:
    """What the comparison prints of one sampler."""

    evals_per_s: float
    ess: float
    """Bulk ESS of the slowest channel parameter (NaN: too few draws for arviz)."""
    seconds: float
    evaluations: int
    mean: np.ndarray
    """Posterior means of the channel parameters, in their units."""
    sd: np.ndarray
    note: str = ""
    steps: int = 0
    converged: bool = True
    sd_without_walk: np.ndarray = None
    """gyrocal only: the linearised model's conditional sd with the gyro random walk cut 100-fold."""


def gyrocal_figures(c: Campaign, cfg: dict) -> Figures:
    """Run `posterior.prepare` and `posterior.run` as the pipeline does; time them and its log posterior."""
    from gyrocal.inference.fit.likelihood import campaign_stats, conditional_posterior
    from gyrocal.inference.noise.covariance import variances
    from gyrocal.inference.sampling import inferencedata, posterior
    est, spec = c.estimate, c.estimate.spec
    start = time.perf_counter()
    post = posterior.run(posterior.prepare(c.maneuvers, est, c.priors, cfg["grid"]), cfg["sampler"], cfg["seed"])
    seconds = time.perf_counter() - start
    summary = inferencedata.summarize(inferencedata.posterior_dataset(post.ensemble_draws(), est.theta, spec),
                                      inferencedata.posterior_dataset(post.walker_draws(), est.theta, spec),
                                      spec.labels, cfg["convergence"]).set_index("label").loc[spec.labels]
    r = post.result
    evaluations = r.chains.shape[0] * r.walkers * (2 * (r.burn // 2) + r.steps)
    evals_per_s = evaluations_per_s(post, est, c.priors, 500)
    note = (f"{r.chains.shape[0]} ensembles x {r.walkers} walkers x {r.steps} steps (+{2 * (r.burn // 2)} burn-in), "
            f"max r_hat {summary['r_hat'].max():.3f}, run long enough: {r.converged_length}")
    _, cov = conditional_posterior(campaign_stats(post.noises, variances(est.log_sigma + [0.0, 0.0, np.log(0.01)])),
                                   c.priors.mean - est.theta, c.priors.sd)
    return Figures(evals_per_s, float(summary["ess_bulk"].min()), seconds, evaluations,
                   summary["mean"].to_numpy(), summary["sd"].to_numpy(), note,
                   sd_without_walk=spec.to_unit(np.sqrt(np.diag(cov))))


# --- the straightforward model -------------------------------------------------------------


class Straightforward:
    """The log posterior a user writes: re-propagate every maneuver at every evaluation.

    ``x`` = the channel parameters in their units (ppm, arcsec; the spec's order), then per
    maneuver its initial attitude error (arcsec, inertial axes) and each channel's bias (deg/h).
    """

    def __init__(self, maneuvers, spec, priors, stated: dict):
        from gyrocal.model.units import ARCSEC_RAD
        self.maneuvers, self.spec = maneuvers, spec
        self.n_par, self.n_ch = len(spec), len(spec.channels)
        self.dim = self.n_par + len(maneuvers) * (3 + self.n_ch)
        self.prior_mean = spec.to_unit(priors.mean)
        self.prior_sd = spec.to_unit(priors.sd)
        self.bound = spec.to_unit(priors.bound)
        self.start = [Rotation.from_quat(d.attitude0_quat) for d in maneuvers]
        self.star = [Rotation.from_quat(d.st_quat) for d in maneuvers]
        b = np.asarray(stated["boresight_body"], dtype=float)
        b = np.outer(b, b) / (b @ b)
        cross, about = (stated[k] * ARCSEC_RAD for k in ("sigma_cross_arcsec", "sigma_about_arcsec"))
        self.whiten = np.linalg.cholesky((np.eye(3) - b) / cross**2 + b / about**2)
        """``L`` with ``L L' = `` the star tracker's information matrix in body axes."""

    def unpack(self, x):
        """Channel parameters (SI `ChannelParams` per maneuver, with its biases) and initial errors (rad)."""
        from gyrocal.model.units import arcsec_to_rad, deg_h_to_rad_s
        theta = self.spec.to_si(x[:self.n_par])
        nuisance = np.asarray(x[self.n_par:]).reshape(len(self.maneuvers), 3 + self.n_ch)
        biases = deg_h_to_rad_s(nuisance[:, 3:])
        return [self.spec.channel_params(theta, b) for b in biases], arcsec_to_rad(nuisance[:, :3])

    def errors(self, x) -> list:
        """(M, 3) star tracker relative to the propagated attitude (rad, body axes; eq. 4), for every
        maneuver and, within it, every channel set."""
        from gyrocal.model import correction, kinematics
        params, chi0 = self.unpack(x)
        out = []
        for m, d in enumerate(self.maneuvers):
            start = Rotation.from_rotvec(chi0[m]) * self.start[m]
            for channel_set in d.sets:
                sub = params[m].subset(channel_set)
                raw = d.set_increments(channel_set) - np.outer(d.dt, sub.bias_rad_s)
                body = correction.apply(correction.correction_for_set(params[m], channel_set), raw)
                attitudes = kinematics.propagate(start, body)
                at_star = kinematics.attitude_at(d.gyro_time, attitudes, body, d.st_time)
                out.append(kinematics.error_angles_rad(at_star, self.star[m]))
        return out

    def residuals(self, x) -> np.ndarray:
        """The `errors` whitened with the star tracker's noise, flattened."""
        return np.concatenate([(e @ self.whiten).ravel() for e in self.errors(x)])

    def log_prior(self, x) -> float:
        theta = x[:self.n_par]
        if np.any(np.abs(theta) > self.bound):
            return -np.inf
        return -0.5 * float(np.sum(((theta - self.prior_mean) / self.prior_sd) ** 2))

    def log_likelihood(self, x) -> float:
        r = self.residuals(x)
        return -0.5 * float(r @ r)

    def __call__(self, x) -> float:
        lp = self.log_prior(x)
        return lp + self.log_likelihood(x) if np.isfinite(lp) else -np.inf

    def point(self, est) -> np.ndarray:
        """gyrocal's WLS point estimate as an ``x``."""
        from gyrocal.model.units import rad_s_to_deg_h, rad_to_arcsec
        nuisance = np.column_stack([rad_to_arcsec(est.chi0), rad_s_to_deg_h(est.biases)])
        return np.concatenate([self.spec.to_unit(est.theta), nuisance.ravel()])


def laplace(model: Straightforward, x0, max_nfev: int = 3):
    """Mode and Laplace covariance of the straightforward posterior (`least_squares`, 2-point Jacobian)."""
    prior = lambda x: (x[:model.n_par] - model.prior_mean) / model.prior_sd
    fun = lambda x: np.concatenate([model.residuals(x), prior(x)])
    fit = least_squares(fun, x0, x_scale="jac", method="trf", max_nfev=max_nfev)
    cov = np.linalg.inv(fit.jac.T @ fit.jac)
    return fit.x, cov, fit


def straightforward_figures(model: Straightforward, mode, cov, seconds: float, seed: int = 1) -> Figures:
    """Plain emcee for ``seconds`` of wall time from the Laplace approximation; ESS on the second half."""
    walkers = 2 * model.dim + 2
    rng = np.random.default_rng(seed)
    p0 = rng.multivariate_normal(mode, cov, walkers)
    sampler = emcee.EnsembleSampler(walkers, model.dim, model)
    sampler.random_state = np.random.RandomState(seed).get_state()
    chain = []
    start = time.perf_counter()
    for state in sampler.sample(p0, iterations=10**9, store=False):
        chain.append(state.coords.copy())
        if time.perf_counter() - start > seconds:
            break
    elapsed = time.perf_counter() - start
    chain = np.array(chain)
    steps = len(chain)
    acceptance = np.mean(np.any(np.diff(chain, axis=0) != 0, axis=2)) if steps > 1 else np.nan
    kept = np.transpose(chain[steps // 2:, :, :model.n_par], (1, 0, 2))
    idata = az.from_dict(posterior={"p": kept})
    if kept.shape[1] >= 4:
        ess = float(az.ess(idata, method="bulk")["p"].min())
        rhat = float(az.rhat(idata)["p"].max())
    else:
        ess = rhat = np.nan
    note = (f"1 ensemble x {walkers} walkers x {steps} steps (first {steps // 2} discarded), acceptance "
            f"{acceptance:.2f}, max r_hat over walkers {rhat:.2f}")
    flat = kept.reshape(-1, model.n_par)
    return Figures(steps * walkers / elapsed, ess, elapsed, steps * walkers, flat.mean(axis=0), flat.std(axis=0, ddof=1),
                   note, steps, converged=steps >= 50 * stretch_on_gaussian(model.dim, model.n_par)[1])


@functools.lru_cache
def stretch_on_gaussian(dim: int, n_par: int, steps: int = 40_000, thin: int = 10, seed: int = 0):
    """Bulk ESS per evaluation, and emcee's autocorrelation time (steps), of the slowest of ``n_par``
    coordinates, for plain emcee (stretch move, 2 dim + 2 walkers) on a standard normal of ``dim``
    dimensions, started in it. The stretch move is affine invariant, so this is its mixing on any
    Gaussian of that dimension, the straightforward posterior's Laplace approximation included.
    The run is some 20 autocorrelation times long: shorter runs underestimate the time, so this
    ESS per evaluation errs, if anything, in the straightforward sampler's favour."""
    walkers = 2 * dim + 2
    sampler = emcee.EnsembleSampler(walkers, dim, lambda x: -0.5 * np.sum(x * x, axis=1), vectorize=True)
    sampler.random_state = np.random.RandomState(seed).get_state()
    p0 = np.random.default_rng(seed).standard_normal((walkers, dim))
    chain = np.array([state.coords[:, :n_par].copy()
                      for state in sampler.sample(p0, iterations=steps // thin, thin_by=thin, store=False)])
    ess = float(az.ess(az.from_dict(posterior={"p": np.transpose(chain, (1, 0, 2))}), method="bulk")["p"].min())
    tau = thin * float(np.max(emcee.autocorr.integrated_time(chain, quiet=True)))
    return ess / (steps * walkers), tau


# --- printing ------------------------------------------------------------------------------


def print_speed(name: str, fig: Figures):
    per_s = fig.ess / fig.seconds
    print(f"  {name:34s} {fig.evals_per_s:9.0f} {fig.seconds:8.1f} {fig.evaluations:9d} {fig.ess:9.1f} {per_s:9.3g} "
          f"{1000 * fig.ess / fig.evaluations:9.3g}")
    print(f"    {fig.note}")


def print_speeds(g: Figures, s: Figures, dim: int, n_par: int):
    """Both samplers' speed, the straightforward one measured and projected, and the ratios."""
    per_eval, tau = stretch_on_gaussian(dim, n_par)
    projected = per_eval * s.evals_per_s
    print(f"  {'sampler':34s} {'evals/s':>9s} {'seconds':>8s} {'evals':>9s} {'min ESS':>9s} {'ESS/s':>9s} "
          f"{'ESS/1000ev':>9s}")
    print_speed("gyrocal", g)
    print_speed("straightforward, measured (arviz)", s)
    print(f"  {'straightforward, projected':34s} {s.evals_per_s:9.0f} {'':8s} {'':9s} {'':9s} {projected:9.3g} "
          f"{1000 * per_eval:9.3g}")
    print(f"    stretch move's ESS per evaluation on a {dim}-D Gaussian (emcee tau {tau:.0f} steps there), "
          "times the measured evaluations/s")
    g_rate = g.ess / g.seconds
    if s.steps >= tau and np.isfinite(s.ess):
        measured = f"{g_rate / (s.ess / s.seconds):.3g}x"
    elif np.isfinite(s.ess):
        measured = (f"n/a: its {s.steps} steps are shorter than one autocorrelation time, so arviz's ESS "
                    f"({s.ess:.0f}) counts the independent start draws, not what the sampler mixed")
    else:
        measured = f"n/a: {s.steps} steps are too few for arviz"
    print(f"  ratio gyrocal / straightforward: evaluations/s {g.evals_per_s / s.evals_per_s:.0f}x")
    print(f"  ratio gyrocal / straightforward ESS/s: projected {g_rate / projected:.3g}x; bound "
          f"{g_rate / s.evals_per_s:.3g}x (were every straightforward evaluation an independent draw); measured {measured}")


def print_agreement(labels, units, g: Figures, s: Figures, mode, laplace_sd):
    print(f"  {'parameter':20s} {'unit':6s} {'gyrocal mean':>12s} {'sd':>6s} | {'emcee mean':>10s} {'sd':>6s} "
          f"{'dz':>6s} | {'LS mode':>8s} {'Laplace sd':>10s} {'dz':>6s}")
    for label in SHOWN:
        i = labels.index(label)
        dz, dz_mode = (s.mean[i] - g.mean[i]) / g.sd[i], (mode[i] - g.mean[i]) / g.sd[i]
        print(f"  {label:20s} {units[i]:6s} {g.mean[i]:12.1f} {g.sd[i]:6.1f} | {s.mean[i]:10.1f} {s.sd[i]:6.1f} "
              f"{dz:6.2f} | {mode[i]:8.1f} {laplace_sd[i]:10.1f} {dz_mode:6.2f}")
    n = len(labels)
    z_emcee, z_mode = np.abs(s.mean - g.mean) / g.sd, np.abs(mode[:n] - g.mean) / g.sd
    print(f"  all {n}: |mean - gyrocal mean| / gyrocal sd: emcee median {np.median(z_emcee):.2f}, max "
          f"{z_emcee.max():.2f}; LS mode median {np.median(z_mode):.2f}, max {z_mode.max():.2f}")
    print(f"  sd / gyrocal sd: emcee {np.min(s.sd / g.sd):.2f} .. {np.max(s.sd / g.sd):.2f}; Laplace "
          f"{np.min(laplace_sd[:n] / g.sd):.2f} .. {np.max(laplace_sd[:n] / g.sd):.2f}; gyrocal's own linearised model "
          f"without the gyro random walk (cut 100-fold), which the straightforward model lacks: "
          f"{np.min(g.sd_without_walk / g.sd):.2f} .. {np.max(g.sd_without_walk / g.sd):.2f}")
    if not s.converged:
        print(f"  the straightforward run has not converged ({s.steps} steps, fewer than 50 autocorrelation times): "
              "its walkers have barely left their start, draws from its Laplace approximation, so its mean and sd "
              "show that start")


def compare(name: str, cfg: dict, seconds: float):
    t0 = time.perf_counter()
    c = prepare(name, cfg)
    spec = c.estimate.spec
    n_samples = sum(len(d.dt) for d in c.maneuvers)
    print(f"\n== campaign {name}: {len(c.maneuvers)} maneuvers, {n_samples} gyro samples, "
          f"{sum(len(d.st_time) for d in c.maneuvers)} star-tracker samples (simulated and point estimate in "
          f"{time.perf_counter() - t0:.0f} s)", flush=True)
    g = gyrocal_figures(c, cfg)
    model = Straightforward(c.maneuvers, spec, c.priors, c.stated)
    t0 = time.perf_counter()
    mode, cov, fit = laplace(model, model.point(c.estimate))
    print(f"  straightforward model: {model.dim} dimensions; its mode and Laplace covariance by least squares "
          f"from gyrocal's WLS point in {time.perf_counter() - t0:.0f} s ({fit.nfev} steps: {fit.message})", flush=True)
    s = straightforward_figures(model, mode, cov, seconds, cfg["seed"])
    print_speeds(g, s, model.dim, len(spec))
    print_agreement(spec.labels, spec.units, g, s, mode, np.sqrt(np.diag(cov)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="straightforward sampler's budget per campaign")
    parser.add_argument("--campaign", choices=["mom", "tiny", "both"], default="both")
    args = parser.parse_args()
    warnings.filterwarnings("ignore", module="arviz")
    logging.getLogger("emcee").setLevel(logging.ERROR)
    cfg = load_config()
    for name in (["mom", "tiny"] if args.campaign == "both" else [args.campaign]):
        compare(name, cfg, args.seconds)


if __name__ == "__main__":
    main()
