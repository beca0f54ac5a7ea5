"""PSIS-LOO against exact refits, and why its effective number of parameters is small (issue 12).

PSIS-LOO (`inferencedata.loo`) estimates each block's ``log p(y_i | y_-i)`` by importance
sampling the full posterior, with the block's pointwise term ``log p(y_i | theta, y_-i)``
(`predictive.block_conditionals`: the block given the rest of its maneuver, the nuisance
integrated out) as the log weight. Here that estimate is checked against the value it
approximates, computed by brute force:

    log p(y_i | y_-i) = log mean_s p(y_i | theta_s, y_-i),   theta_s ~ p(theta | y_-i),

with ``p(theta | y_-i)`` sampled by gyrocal's own steps (validate, preprocess, classic,
point estimate, posterior) on a copy of the campaign whose star-tracker rows in the block
are marked invalid (``valid = 0``: read, counted and skipped, see `preprocess.slice_maneuver`),
and ``p(y_i | theta_s, y_-i)`` evaluated as the full run evaluates it: the full data's
linearisation, the full posterior's mean noise ratios and each draw's own ``sigma_cross``
(`predictive.split_draws`). The refit's draws are taken as offsets from the full run's point
estimate, so the two sides differ only in the posterior the draws come from.

The second half explains p_loo. Each pointwise term is quadratic in the channel parameters,
``-|r_i - W_i dtheta|^2 / (2 s)`` with ``s = sigma_cross^2``, so its curvature ``H_i`` in
``(dtheta, log sigma_cross)`` is exact. For a near-Gaussian posterior with covariance ``Sigma``
a block's share of p_loo is about the posterior variance of its term, ``g_i' Sigma g_i +
tr((H_i Sigma)^2) / 2`` (``g_i`` its gradient at the posterior mean), whose expectation over
the data is about ``tr(H_i Sigma)``, the block's leverage. Were the blocks independent given
the parameters, ``sum_i H_i`` would be the campaign's information ``A`` and the sum of
leverages ``tr(A Sigma)``, about the number of parameters the data determine. A block's term is
conditional on the rest of its maneuver, though, whose nuisance (initial attitude error, biases)
and gyro random walk already predict most of what the parameters do inside it; `curvature_table`
measures by how much, block by block.
"""

import json
import shutil
from dataclasses import asdict, dataclass
from pathlib import Path

import arviz as az
import numpy as np
import pandas as pd
from scipy.special import logsumexp

from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.fit.likelihood import maneuver_stats
from gyrocal.inference.noise import covariance
from gyrocal.inference.sampling import inferencedata, predictive
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.model import effects
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.run import calibrate_campaign

__all__ = [
    "BlockRefit", "FullRun", "block_curvature", "block_hessian", "block_kinds", "block_name", "block_times",
    "campaign_without", "curvature_table", "invalidated_star_tracker", "joint_curvature", "log_mean_density",
    "p_loo_summary", "parse_block", "posterior_draws", "refit_table", "run_maneuver_ids", "run_steps", "scale_moments"
]

# ----------------------------------------------------------------------------------------------
# pure pieces


def block_name(maneuver_id: str, block: int) -> str:
    """A block's coordinate in ``posterior.nc``'s log-likelihood group."""
    return f"{maneuver_id}:{block}"


def parse_block(name: str) -> tuple:
    """``(maneuver id, block number)`` of a block's coordinate."""
    maneuver_id, block = name.rsplit(":", 1)
    return maneuver_id, int(block)


def block_times(st_time: np.ndarray, block: int, block_s: float) -> np.ndarray:
    """The star-tracker times of one block of a preprocessed maneuver, numbered as the
    pointwise log-likelihood numbers them (`predictive.sample_blocks`)."""
    return st_time[predictive.sample_blocks(st_time, block_s) == block]


def block_kinds(data: ManeuverData, block_s: float) -> list:
    """Per block: ``holding`` (every sample in an inertial hold, as the classic method finds the
    holds), ``turning`` (none) or ``mixed``."""
    before, after = classic.hold_windows(data)
    held = before | after
    blocks = predictive.sample_blocks(data.st_time, block_s)
    kinds = []
    for b in range(blocks.max() + 1):
        share = held[blocks == b].mean() if np.any(blocks == b) else np.nan
        kinds.append("holding" if share == 1 else "turning" if share == 0 else "mixed")
    return kinds


def invalidated_star_tracker(text: str, t_lo: float, t_hi: float) -> tuple:
    """``star_tracker.csv`` text with every row timed in ``[t_lo, t_hi]`` marked ``valid = 0``
    (a ``valid`` column of ones is added if there is none), and how many rows that marks. Every
    other character is kept, so the remaining samples are bit for bit the original ones."""
    lines = text.splitlines()
    head = next(i for i, line in enumerate(lines) if line.strip())
    names = [c.strip() for c in lines[head].split(",")]
    t_col = names.index("time")
    add = "valid" not in names
    v_col = len(names) if add else names.index("valid")
    out = lines[:head] + [lines[head] + ",valid" if add else lines[head]]
    marked = 0
    for line in lines[head + 1:]:
        if not line.strip():
            out.append(line)
            continue
        fields = line.split(",") + (["1"] if add else [])
        if t_lo <= float(fields[t_col]) <= t_hi:
            fields[v_col] = "0"
            marked += 1
        out.append(",".join(fields))
    return "\n".join(out) + "\n", marked


def posterior_draws(idata, spec, theta_ref: np.ndarray) -> np.ndarray:
    """(chains * draws, P + 3) draws of ``posterior.nc`` as the sampler holds them, ``[theta -
    theta_ref, log sigma (SI)]``, in the order of its log-likelihood group. ``theta_ref`` is the
    point estimate the offsets are taken from (another run's, to compare two posteriors)."""
    post = idata.posterior
    labels = [str(v) for v in post["channel_param"].coords["parameter"].values]
    if labels != list(spec.labels):
        raise ValueError(f"posterior parameters {labels} are not the model's {list(spec.labels)}")
    theta = spec.to_si(post["channel_param"].values)
    scales = np.stack([post[s.key].values for s in covariance.NOISE_SCALES], axis=-1)
    log_sigma = np.log(scales * np.array([s.si_per_unit for s in covariance.NOISE_SCALES]))
    flat = np.concatenate([theta - theta_ref, log_sigma], axis=-1)
    return flat.reshape(-1, flat.shape[-1])


def log_mean_density(loglik: np.ndarray) -> tuple:
    """``log mean_s exp(loglik_s)`` and its Monte Carlo standard error (delta method, draws taken
    as independent): the exact elpd of a block from draws of the posterior without it."""
    value = logsumexp(loglik) - np.log(len(loglik))
    ratio = np.exp(loglik - value)
    return float(value), float(np.std(ratio, ddof=1) / np.sqrt(len(loglik)))


def block_hessian(term: predictive.BlockConditional, mean: np.ndarray) -> tuple:
    """Negative Hessian ``H`` and gradient ``g`` of one block term in ``x = (dtheta, log sigma_cross)``
    at ``mean``: with ``e = r - W dtheta`` and ``s = sigma_cross^2`` there,
    ``H = [[W'W, 2 W'e], [2 e'W, 2 e'e]] / s`` and ``g = (W'e / s, e'e / s - n_b)``."""
    p = len(mean) - 1
    w, r = term.w[:, :p], term.w[:, -1]
    s = np.exp(2 * mean[-1])
    e = r - w @ mean[:p]
    h = np.zeros((p + 1, p + 1))
    h[:p, :p] = w.T @ w
    h[:p, p] = h[p, :p] = 2 * (w.T @ e)
    h[p, p] = 2 * (e @ e)
    return h / s, np.append(w.T @ e / s, e @ e / s - len(w))


def block_curvature(term: predictive.BlockConditional, mean: np.ndarray, cov: np.ndarray) -> dict:
    """One block term's leverage in the posterior ``N(mean, cov)`` of ``x = (dtheta, log sigma_cross)``:
    ``tr(H cov)`` (`block_hessian`), split into its channel-parameter and noise-scale parts,
    ``g' cov g`` and ``tr((H cov)^2) / 2``. The last two sum to the term's posterior variance
    when the posterior is Gaussian and the term quadratic (in ``log sigma_cross`` it is nearly so
    over the posterior's spread); the expectation of ``g' cov g`` over the data is about
    ``tr(H cov)``.
    """
    p = len(mean) - 1
    h, g = block_hessian(term, mean)
    hc = h @ cov
    params = float(np.sum(h[:p, :p] * cov[:p, :p]))
    return {"trace": float(np.trace(hc)), "trace_params": params, "trace_scale": float(np.trace(hc)) - params,
            "score": float(g @ cov @ g), "second_order": float(0.5 * np.sum(hc * hc.T))}


def joint_curvature(stats, mean: np.ndarray, cov: np.ndarray) -> dict:
    """The same traces for a whole maneuver's (or campaign's) likelihood, `likelihood.Stats` at
    unit scale: ``H = [[A, 2 (b - A dtheta)], [., 2 Q]] / s``, Q its quadratic form at the mean.
    ``tr(H cov)`` is what the leverages would sum to were the blocks independent."""
    p = len(mean) - 1
    d = mean[:p]
    s = np.exp(2 * mean[-1])
    q = d @ stats.A @ d - 2 * stats.b @ d + stats.c
    h = np.zeros((p + 1, p + 1))
    h[:p, :p] = stats.A
    h[:p, p] = h[p, :p] = 2 * (stats.b - stats.A @ d)
    h[p, p] = 2 * q
    h /= s
    return {"trace": float(np.sum(h * cov)), "trace_params": float(np.sum(h[:p, :p] * cov[:p, :p])),
            "trace_scale": float(np.sum(h * cov) - np.sum(h[:p, :p] * cov[:p, :p]))}


def scale_moments(flat: np.ndarray, n_params: int) -> tuple:
    """Mean and covariance of ``(dtheta, log sigma_cross)`` over the draws: the posterior the
    pointwise terms vary over (their noise ratios are fixed at the draws' mean)."""
    x = flat[:, :n_params + 1]
    return x.mean(axis=0), np.cov(x.T)


# ----------------------------------------------------------------------------------------------
# the runs


def run_steps(campaign_dir, out, cfg: dict, model: str = "baseline") -> list:
    """gyrocal's steps up to the posterior on one campaign directory (`gyrocal.pipeline.run.calibrate_campaign`);
    the model's outputs land in ``out/<model>/``. Returns the preprocessed maneuver files."""
    return calibrate_campaign(campaign_dir, CampaignPaths.under(out), cfg, [model], through="posterior",
                              strict=True)


def campaign_without(campaign_dir, out_dir, t_lo: float, t_hi: float) -> tuple:
    """A copy of a campaign directory whose star-tracker rows in ``[t_lo, t_hi]`` are invalid;
    returns the copy's path and how many rows were marked."""
    src, dst = Path(campaign_dir), Path(out_dir)
    dst.mkdir(parents=True, exist_ok=True)
    for item in src.iterdir():
        if item.name != "star_tracker.csv" and item.is_file():
            shutil.copy2(item, dst / item.name)
    text, marked = invalidated_star_tracker((src / "star_tracker.csv").read_text(), t_lo, t_hi)
    (dst / "star_tracker.csv").write_text(text)
    return dst, marked


def run_maneuver_ids(input_json) -> list:
    """The maneuver ids a run's ``input.json`` lists, in the campaign's order."""
    return list(json.loads(Path(input_json).read_text())["maneuvers"])


@dataclass
class BlockRefit:
    """One held-out block: PSIS-LOO and the exact refit value of ``log p(y_i | y_-i)``."""

    block: str
    kind: str
    samples: int
    """Star-tracker samples the block holds (each 3 axes per channel set)."""
    psis: float
    exact: float
    exact_mcse: float
    khat: float
    psis_p_loo: float
    """The block's share of p_loo: its lppd less its PSIS elpd."""
    leverage: float
    """``tr(H_i Sigma)`` of the block's term in the full posterior (`block_curvature`)."""
    rest_intact: bool
    """The refit saw exactly the full run's star-tracker samples less the block's."""

    @property
    def difference(self) -> float:
        return self.psis - self.exact


class FullRun:
    """A finished run's data, point estimate, posterior draws and PSIS-LOO, loaded once; the
    pointwise terms are rebuilt from them exactly as the posterior step builds them."""

    def __init__(self, out, cfg: dict, model: str = "baseline"):
        self.out, self.cfg, self.model = Path(out), cfg, model
        self.block_s = float(cfg["sampler"]["block_s"])
        self.ids = run_maneuver_ids(self.out / "input.json")
        self.maneuvers = [ManeuverData.load(self.out / f"preprocess/{m}.npz") for m in self.ids]
        self.known = effects.known(cfg["plugins"])
        self.estimate = PointEstimate.load(self.out / model / "point_estimate.npz", self.known)
        self.idata = az.from_netcdf(str(self.out / model / "posterior.nc"))
        self.flat = posterior_draws(self.idata, self.estimate.spec, self.estimate.theta)
        self.n_params = len(self.estimate.spec)
        _, self.ratios, _ = predictive.split_draws(self.flat, self.n_params)
        self.loo = inferencedata.loo(self.idata, model)
        loglik = self.idata.log_likelihood["attitude_error"]
        self.loglik = loglik.values.reshape(-1, loglik.sizes["block"])
        self.blocks = [str(b) for b in loglik.coords["block"].values]
        self._linear, self._terms = {}, {}

    def linear(self, m: int):
        """Linearisation and noise structure of maneuver ``m`` about the full point estimate."""
        if m not in self._linear:
            lin = self.estimate.linearize(self.maneuvers, m)
            self._linear[m] = lin, covariance.build(lin, self.estimate.boresight, self.estimate.correlation_time_s,
                                                         self.estimate.spec.jitter_noise)
        return self._linear[m]

    def terms(self, m: int) -> list:
        """Every block's `predictive.BlockConditional` of maneuver ``m``, at the full run's ratios."""
        if m not in self._terms:
            lin, nz = self.linear(m)
            blocks = predictive.block_index(lin, self.maneuvers[m].st_time, self.block_s)
            self._terms[m] = list(predictive.block_conditionals(lin, predictive.WhitenedManeuver(nz, self.ratios),
                                                                blocks))
        return self._terms[m]

    def term(self, name: str) -> predictive.BlockConditional:
        maneuver_id, b = parse_block(name)
        return next(t for t in self.terms(self.ids.index(maneuver_id)) if t.block == b)

    def pointwise(self, name: str) -> dict:
        """PSIS-LOO of one block: its elpd, Pareto k and share of p_loo."""
        i = self.blocks.index(name)
        loo_i = float(self.loo.loo_i.values[i])
        lppd = float(logsumexp(self.loglik[:, i]) - np.log(len(self.loglik)))
        return {"psis": loo_i, "khat": float(self.loo.pareto_k.values[i]), "psis_p_loo": lppd - loo_i}

    def refit(self, name: str, campaign_dir, work) -> BlockRefit:
        """Hold block ``name`` out of the campaign, run the steps on what is left, and compare
        the exact ``log p(y_i | y_-i)`` from the refit's draws with PSIS-LOO's."""
        maneuver_id, b = parse_block(name)
        m = self.ids.index(maneuver_id)
        data = self.maneuvers[m]
        times = block_times(data.st_time, b, self.block_s)
        work = Path(work)
        copy, _ = campaign_without(campaign_dir, work / "campaign", times[0], times[-1])
        run_steps(copy, work / "out", self.cfg, self.model)
        refit = ManeuverData.load(work / "out" / f"preprocess/{maneuver_id}.npz")
        rest_intact = bool(np.array_equal(refit.st_time, np.setdiff1d(data.st_time, times)) and all(
            np.array_equal(ManeuverData.load(work / "out" / f"preprocess/{k}.npz").st_time, d.st_time)
            for k, d in zip(self.ids, self.maneuvers) if k != maneuver_id))
        refit_est = PointEstimate.load(work / "out" / self.model / "point_estimate.npz", self.known)
        refit_idata = az.from_netcdf(str(work / "out" / self.model / "posterior.nc"))
        flat = posterior_draws(refit_idata, refit_est.spec, self.estimate.theta)
        dtheta, _, scale = predictive.split_draws(flat, self.n_params)
        term = self.term(name)
        exact, mcse = log_mean_density(term.loglik(dtheta, scale))
        mean, cov = scale_moments(self.flat, self.n_params)
        return BlockRefit(name, block_kinds(data, self.block_s)[b], len(times), exact=exact, exact_mcse=mcse,
                          leverage=block_curvature(term, mean, cov)["trace"], rest_intact=rest_intact,
                          **self.pointwise(name))


def refit_table(results) -> pd.DataFrame:
    """One row per `BlockRefit`, with the difference PSIS minus exact."""
    rows = [{**asdict(r), "difference": r.difference} for r in results]
    return pd.DataFrame(rows)


def curvature_table(full: FullRun) -> pd.DataFrame:
    """Per block of the full run: its kind (`block_kinds`) and position in its maneuver, its PSIS
    share of p_loo and Pareto k, the posterior variance of its term over the draws, and
    `block_curvature`'s traces; per maneuver, as rows named ``<maneuver>:joint``,
    `joint_curvature` of the maneuver's whole likelihood."""
    mean, cov = scale_moments(full.flat, full.n_params)
    dtheta, _, scale = predictive.split_draws(full.flat, full.n_params)
    unit = covariance.variances([0.0, full.ratios[0], full.ratios[1]])
    rows = []
    for m, data in enumerate(full.maneuvers):
        kinds = block_kinds(data, full.block_s)
        for term in full.terms(m):
            name = block_name(data.id, term.block)
            position = "first" if term.block == 0 else "last" if term.block == len(kinds) - 1 else "interior"
            rows.append({"block": name, "maneuver": data.id, "kind": kinds[term.block], "position": position,
                         "rows": len(term.w),
                         **{k: v for k, v in full.pointwise(name).items() if k != "psis"},
                         "variance": float(np.var(term.loglik(dtheta, scale), ddof=1)),
                         **block_curvature(term, mean, cov)})
        rows.append({"block": block_name(data.id, "joint"), "maneuver": data.id, "kind": "joint",
                     **joint_curvature(maneuver_stats(full.linear(m)[1], unit), mean, cov)})
    return pd.DataFrame(rows)


def p_loo_summary(full: FullRun, table: pd.DataFrame) -> dict:
    """p_loo against what should explain it: the sum of the blocks' posterior variances (p_waic),
    their leverages ``sum_i tr(H_i Sigma)`` (and its parts), the joint ``tr(A Sigma)`` were
    the blocks independent, and the number of sampled parameters.

    The terms hold the noise ratios at their posterior mean, so ``log sigma_cross`` is the only
    noise scale they vary with, and it varies with the ratios' uncertainty folded in: its share
    stands for all three scales (a noise level is learnt from a block's innovations, which
    conditioning on the neighbours does not thin out)."""
    blocks, joint = table[table["kind"] != "joint"], table[table["kind"] == "joint"]
    return {
        "p_loo": float(full.loo.p_loo),
        "sum_variance": float(blocks["variance"].sum()),
        "trace_sum": float(blocks["trace"].sum()),
        "trace_sum_params": float(blocks["trace_params"].sum()),
        "trace_sum_scale": float(blocks["trace_scale"].sum()),
        "score_sum": float(blocks["score"].sum()),
        "second_order_sum": float(blocks["second_order"].sum()),
        "joint_trace": float(joint["trace"].sum()),
        "joint_trace_params": float(joint["trace_params"].sum()),
        "free_parameters": int(full.estimate.spec.free.sum()),
        "sampled_parameters": full.n_params + len(covariance.NOISE_SCALES),
        "blocks": len(blocks),
        "khat_max": float(blocks["khat"].max()),
    }
