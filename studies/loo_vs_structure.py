"""Why the structure test and PSIS-LOO can disagree: prints figures, asserts nothing.

    python studies/loo_vs_structure.py [SCENARIO.yaml EFFECT]
    (default: tests/data/hidden_bias_drift.yaml bias_drift; the long-maneuver case is
    studies/data/mom_bias_drift.yaml bias_drift)

On a small campaign with a hidden effect, run with the baseline and with the variant
that adds the effect, it prints for the same added effect:

1. the structure test: the score-test chi2 of the effect at the baseline fit, and the
   log-likelihood gain it implies (about chi2 / 2 less the parameters' cost);
2. PSIS-LOO over 60-s blocks (as ``model_comparison.csv``): the elpd difference and p_loo;
3. exact refits for a few held-out blocks: ``log p(y_b | y_-b)`` with the parameters
   integrated over their posterior given everything but the block (dense algebra, noise
   scales at the point estimate's), against the PSIS value of the same block;
4. how much of one maneuver's information about the parameters its blocks' conditional
   densities carry once their neighbours are known: ``tr(Cov_post sum_b I_b)`` against
   ``tr(Cov_post A_m)`` (what the blocks would carry were they independent); p_loo
   estimates the former, summed over maneuvers;
5. exact leave-one-maneuver-out: the elpd difference and its standard error.
"""

import sys
import tempfile
from pathlib import Path

import arviz as az
import numpy as np
import pandas as pd
import yaml

from gyrocal.inference.fit.estimate import PointEstimate, linearize_all
from gyrocal.inference.fit.likelihood import Stats, leave_one_out_log_evidence, log_evidence, maneuver_stats, total
from gyrocal.inference.noise import covariance
from gyrocal.inference.sampling import inferencedata, predictive
from gyrocal.inference.sampling.priors import model_priors
from gyrocal.model import effects
from gyrocal.pipeline.steps import common
from gyrocal.simulation import simulate
from gyrocal.study.hidden import calibrate, with_variant

ROOT = Path(__file__).resolve().parents[1]


def dense_parts(lin, nz, var):
    """Undifferenced data, design, nuisance design and covariance of one maneuver (dense)."""
    n, width = nz.n, 3 * lin.z.shape[1]
    c = np.zeros((n, n))
    ab = nz.covariance(var)
    for d in range(ab.shape[0]):
        idx = np.arange(n - d)
        c[idx + d, idx] = c[idx, idx + d] = ab[d, idx]
    t_inv = np.tril(np.ones((n // width, n // width)))
    t_inv = np.kron(t_inv, np.eye(width))
    cov = t_inv @ c @ t_inv.T
    return (lin.z.reshape(n), lin.design.reshape(n, -1), covariance.nuisance_design(lin).reshape(n, -1), cov)


def dense_stats(y, x, g, cov) -> Stats:
    """`Stats` of a data vector with its nuisance integrated out (flat prior), dense."""
    chol = np.linalg.cholesky(cov)
    wy, wx, wg = (np.linalg.solve(chol, a) for a in (y, x, g))
    q, r = np.linalg.qr(wg)
    proj = lambda a: a - q @ (q.T @ a)
    py, px = proj(wy), proj(wx)
    logdet = 2 * np.sum(np.log(np.diag(chol))) + 2 * np.sum(np.log(np.abs(np.diag(r))))
    return Stats(px.T @ px, px.T @ py, float(py @ py), logdet, len(y) - g.shape[1])


def block_innovation_trace(lin, nz, var, blocks, cov_post):
    """sum over blocks of tr(Cov_post I_b), I_b the information about the parameters in the
    block's density given all other samples of its maneuver (nuisance integrated out)."""
    _, x, g, cov = dense_parts(lin, nz, var)
    prec = np.linalg.inv(cov)
    prec = prec - prec @ g @ np.linalg.solve(g.T @ prec @ g, g.T @ prec)
    total = 0.0
    for b in range(blocks.max() + 1):
        rows = blocks == b
        p_bb = prec[np.ix_(rows, rows)]
        innovation = np.linalg.solve(p_bb, prec[rows] @ x)
        total += np.trace(cov_post @ innovation.T @ p_bb @ innovation)
    return total


def study(scenario: Path, effect: str, tmp: Path):
    simulate.run(scenario, tmp / "sim")
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    from snakemake.utils import validate
    validate(cfg, str(ROOT / "workflow/schemas/config.schema.yaml"))
    cfg = with_variant(cfg, effect)
    npz = calibrate(tmp / "sim" / "campaign", tmp / "out", cfg)
    maneuvers = common.load_maneuvers(npz)
    table = pd.read_csv(tmp / "out" / "model_comparison.csv").set_index("model")
    base_diag = common.read_json(tmp / "out" / "baseline" / "diagnostics.json")
    chi2 = next(r for r in base_diag["ranking"] if r["name"] == effect)
    print(f"\n=== {scenario.name}: baseline vs baseline + {effect} ===")
    print(f"1. structure test at the baseline: chi2 {chi2['chi2_drop']:.1f} on {chi2['df']} df "
          f"(log10 p {chi2['log10_p']}); implies a log-likelihood gain of about "
          f"{chi2['chi2_drop'] / 2:.1f} nats before the parameters' cost")
    print(f"2. PSIS-LOO, 60-s blocks: elpd diff {table.loc['extended', 'elpd_diff_vs_first']:.1f} "
          f"+- {table.loc['extended', 'elpd_diff_se']:.1f}; p_loo baseline {table.loc['baseline', 'p_loo']:.1f}, "
          f"extended {table.loc['extended', 'p_loo']:.1f}")
    known = effects.known(cfg["plugins"])
    lomo = {}
    for model in ("baseline", "extended"):
        est = PointEstimate.load(tmp / "out" / model / "point_estimate.npz", known)
        priors = model_priors(est, cfg["priors"])
        prior_mean, prior_sd = priors.mean - est.theta, priors.sd
        var = covariance.variances(est.log_sigma)
        lins, noises = linearize_all(maneuvers, est)
        parts = [maneuver_stats(nz, var) for nz in noises]
        lomo[model] = leave_one_out_log_evidence(parts, prior_mean, prior_sd)
        whole = total(parts)
        full = log_evidence(whole, prior_mean, prior_sd)
        cov_post = np.linalg.inv(whole.A + np.diag(1 / prior_sd**2))
        loo = inferencedata.loo(az.from_netcdf(tmp / "out" / model / "posterior.nc"), model)
        psis = loo.loo_i.values
        m = 1
        y, x, g, cov = dense_parts(lins[m], noises[m], var)
        blocks = predictive.block_index(lins[m], maneuvers[m].st_time, cfg["sampler"]["block_s"])
        offset = sum(predictive.block_index(lins[k], maneuvers[k].st_time, cfg["sampler"]["block_s"]).max() + 1
                     for k in range(m))
        rows_out = []
        for b in range(min(4, blocks.max() + 1)):
            keep = blocks != b
            without = dense_stats(y[keep], x[keep], g[keep], cov[np.ix_(keep, keep)])
            rest = total([s for k, s in enumerate(parts) if k != m] + [without])
            exact = full - log_evidence(rest, prior_mean, prior_sd)
            rows_out.append(f"block {b}: exact {exact:9.2f}, PSIS {psis[offset + b]:9.2f}")
        print(f"3. {model}, maneuver {maneuvers[m].id}: " + "; ".join(rows_out))
        seen = block_innovation_trace(lins[m], noises[m], var, blocks, cov_post)
        print(f"4. {model}, maneuver {maneuvers[m].id}: its blocks given their neighbours carry "
              f"tr(Cov_post sum_b I_b) = {seen:.2f} of the tr(Cov_post A_m) = "
              f"{np.trace(cov_post @ parts[m].A):.2f} its data carry ({seen / np.trace(cov_post @ parts[m].A):.0%})")
    diff = lomo["extended"] - lomo["baseline"]
    print(f"5. exact leave-one-maneuver-out: elpd baseline {lomo['baseline'].sum():.1f}, extended "
          f"{lomo['extended'].sum():.1f}; difference {diff.sum():.1f} +- {np.sqrt(len(diff) * np.var(diff)):.1f} "
          f"(per maneuver: {', '.join(f'{v:.1f}' for v in diff)})")


def main():
    scenario, effect = (Path(sys.argv[1]), sys.argv[2]) if len(sys.argv) > 2 else (ROOT / "tests/data/hidden_bias_drift.yaml",
                                                                                   "bias_drift")
    with tempfile.TemporaryDirectory() as tmp:
        study(scenario, effect, Path(tmp))


if __name__ == "__main__":
    main()
