"""Rule ``posterior``: emcee over one model's parameters and noise scales."""

import numpy as np
import pandas as pd

from gyrocal.checks import fit as checks
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.noise import covariance
from gyrocal.inference.sampling import inferencedata, posterior
from gyrocal.inference.sampling.budget import SamplingStopped
from gyrocal.io.outputs import atomic, write_csv, write_json
from gyrocal.pipeline.paths import ModelPaths
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps.common import known_effects, load_maneuvers, posterior_spec

__all__ = ["model_priors", "run"]


def model_priors(est: PointEstimate, priors_cfg: dict, prior_from=None) -> posterior.Priors:
    """The spec's declared priors, overridden by the config and by an earlier campaign's
    ``calibration.csv`` (``prior_from``; `common.posterior_spec`)."""
    spec = posterior_spec(est.spec, priors_cfg, prior_from)
    return posterior.Priors.from_spec(spec, est.stated_noise, priors_cfg["noise_log_sd"])


def run(maneuver_files, point_estimate_npz, out: ModelPaths, settings: PosteriorSettings):
    """Sample the posterior (refused where the data do not identify a parameter at the fitted noise, or
    stopped with the reason where the sampler's budget cannot converge: `gyrocal.checks.fit`), check
    convergence, save InferenceData, summary, model fit, the exact leave-one-maneuver-out predictive
    densities and PSIS-LOO per block (here, where arviz and the InferenceData already are, so that the
    comparison of the models needs neither). ``maneuver_files``: the preprocessed ``.npz``, in the
    campaign's order; ``out``: where each output goes, by its `ModelPaths` name (a `ModelPaths`, or the
    rule's ``snakemake.output``, whose names are those)."""
    s = settings
    maneuvers = load_maneuvers(maneuver_files)
    est = PointEstimate.load(point_estimate_npz, known_effects(s.plugins))
    priors = model_priors(est, s.priors, s.prior_from)
    checks.check_blocks(maneuvers, s.sampler["block_s"])
    checks.check_noise(maneuvers, est)
    checks.check_physical(maneuvers, est, priors.bound)
    checks.check_representable(maneuvers, est)
    notes = []
    identified = lambda stats, ratio_sd: notes.append(
        checks.check_identified(est, priors.sd, stats, ratio_sd, np.sqrt(2.0) * priors.log_sigma_sd[0]))
    try:
        post = posterior.sample(maneuvers, est, priors, s.sampler, s.grid, s.seed, before=identified)
    except SamplingStopped as stopped:
        labels = list(est.spec.labels) + covariance.noise_labels(est.spec.correlated_noise)
        if est.group_offsets is not None:
            labels += [f"noise.level.{g}" for g in est.noise_groups] + ["noise.group_sd"]
        raise checks.sampling_stopped(stopped, est, notes[0] if notes else "", labels) from None
    idata, summary, fit, record = inferencedata.assemble(post, maneuvers, s.sampler, s.convergence, s.seed)
    with atomic(out.posterior) as tmp:
        idata.to_netcdf(str(tmp))
    write_csv(summary, out.summary)
    write_csv(fit, out.fit)
    write_json(record, out.sampler)
    write_csv(inferencedata.loo_blocks(idata, est.spec.model), out.elpd_blocks)
    elpd = posterior.leave_one_maneuver_out(post, priors)
    write_csv(pd.DataFrame({"maneuver": [d.id for d in maneuvers], "elpd": elpd}), out.elpd_maneuvers)
