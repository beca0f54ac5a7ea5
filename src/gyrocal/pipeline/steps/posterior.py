"""Rule ``posterior``: emcee over one model's parameters and noise scales."""

import pandas as pd

from gyrocal.checks import fit as checks
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.sampling import inferencedata, posterior
from gyrocal.inference.sampling.budget import SamplingStopped
from gyrocal.inference.sampling.priors import model_priors
from gyrocal.inference.sampling.proposal import SamplingError
from gyrocal.io.orthogonality import orthogonality_table
from gyrocal.io.outputs import atomic, write_csv, write_json
from gyrocal.model import effects, orthogonality
from gyrocal.model.correction import flown_sets
from gyrocal.pipeline.paths import ModelPaths
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(maneuver_files, point_estimate_npz, out: ModelPaths, settings: PosteriorSettings):
    """Sample the posterior (refused where the data do not identify a parameter at the fitted noise, or
    stopped with the reason where the sampler's budget cannot converge: `gyrocal.checks.fit`), check
    convergence, save InferenceData, summary, model fit, the exact leave-one-maneuver-out predictive
    densities, PSIS-LOO per block and the channel sets' non-orthogonality (here, where arviz, the
    InferenceData and every draw already are, so that the comparison of the models needs neither).
    ``maneuver_files``: the preprocessed ``.npz``, in the campaign's order; ``out``: where each output
    goes, by its `ModelPaths` name (a `ModelPaths`, or the rule's ``snakemake.output``, whose names are
    those)."""
    s = settings
    maneuvers = load_maneuvers(maneuver_files)
    est = PointEstimate.load(point_estimate_npz, effects.known(s.plugins))
    priors = model_priors(est, s.priors, s.prior_from)
    checks.check_blocks(maneuvers, s.sampler["block_s"])
    checks.check_noise(maneuvers, est)
    checks.check_physical(maneuvers, est, priors.bound)
    checks.check_representable(maneuvers, est)
    try:
        ready = posterior.prepare(maneuvers, est, priors, s.grid)
        weakest = checks.check_identified(est, priors.sd, ready.stats, ready.ratio_sd, priors.log_ratio_sd)
        post = posterior.run(ready, s.sampler, s.seed)
    except SamplingStopped as stopped:
        raise checks.sampling_stopped(stopped, est, weakest, ready.labels) from None
    except SamplingError as failed:
        raise checks.sampling_failed(failed, maneuvers, est) from None
    pairs = orthogonality.pairs(est.spec, flown_sets(maneuvers))
    idata, summary, fit, record, orth = inferencedata.assemble(post, maneuvers, s.sampler, s.convergence, s.seed, pairs)
    blocks = inferencedata.loo_blocks(idata, est.spec.model)
    elpd = posterior.leave_one_maneuver_out(post, priors)
    with atomic(out.posterior) as tmp:
        idata.to_netcdf(str(tmp))
    write_csv(summary, out.summary)
    write_csv(fit, out.fit)
    write_json(record, out.sampler)
    write_csv(blocks, out.elpd_blocks)
    write_csv(orthogonality_table(est.spec, est.theta, pairs, orth), out.orthogonality)
    write_csv(pd.DataFrame({"maneuver": [d.id for d in maneuvers], "elpd": elpd}), out.elpd_maneuvers)
