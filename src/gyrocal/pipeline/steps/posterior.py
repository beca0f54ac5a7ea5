"""Rule ``posterior``: emcee over one model's parameters and noise scales."""

from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.sampling import inferencedata, posterior, refusals
from gyrocal.inference.sampling.budget import SamplingStopped
from gyrocal.inference.sampling.priors import model_priors
from gyrocal.inference.sampling.proposal import SamplingError
from gyrocal.io.outputs import atomic, write_csv, write_json
from gyrocal.model import effects
from gyrocal.pipeline.paths import ModelPaths
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(maneuver_files, point_estimate_npz, out: ModelPaths, settings: PosteriorSettings):
    """Sample the posterior (refused where the point estimate cannot be sampled or the data do not
    identify a parameter at the fitted noise, or stopped with the reason where the sampler's budget
    cannot converge: `gyrocal.inference.sampling.refusals`), check convergence, and write what
    `inferencedata.assemble` gives: the InferenceData, summary, model fit, the exact
    leave-one-maneuver-out predictive densities, PSIS-LOO per block and the channel sets'
    non-orthogonality. ``maneuver_files``: the preprocessed ``.npz``, in the campaign's order; ``out``:
    where each output goes, by its `ModelPaths` name (a `ModelPaths`, or the rule's
    ``snakemake.output``, whose names are those). Load, check, priors, check, prepare, check, run, write."""
    s = settings
    maneuvers = load_maneuvers(maneuver_files)
    est = PointEstimate.load(point_estimate_npz, effects.known(s.plugins))
    refusals.check_blocks(maneuvers, s.sampler["block_s"])
    refusals.check_noise(maneuvers, est)
    priors = model_priors(est, s.priors, s.prior_from)  # their bounds are the config's where it sets them
    refusals.check_physical(maneuvers, est, priors.bound)
    refusals.check_representable(maneuvers, est)
    try:
        ready = posterior.prepare(maneuvers, est, priors, s.grid)
        weakest = refusals.check_identified(est, priors, ready.stats, ready.ratio_sd)
        post = posterior.run(ready, s.sampler, s.seed)
    except SamplingStopped as stopped:
        raise refusals.sampling_stopped(stopped, est, weakest, ready.labels) from None
    except SamplingError as failed:
        raise refusals.sampling_failed(failed, maneuvers, est) from None
    written = inferencedata.assemble(post, maneuvers, priors, s.sampler, s.convergence, s.seed)
    with atomic(out.posterior) as tmp:
        written.posterior.to_netcdf(str(tmp))
    write_csv(written.summary, out.summary)
    write_csv(written.fit, out.fit)
    write_json(written.sampler, out.sampler)
    write_csv(written.elpd_blocks, out.elpd_blocks)
    write_csv(written.orthogonality, out.orthogonality)
    write_csv(written.elpd_maneuvers, out.elpd_maneuvers)
