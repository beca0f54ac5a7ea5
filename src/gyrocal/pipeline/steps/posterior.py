"""Rule ``posterior``: emcee over one model's parameters and noise scales."""

import pandas as pd

from gyrocal.inference import inferencedata, posterior
from gyrocal.inference.estimate import PointEstimate, check_blocks, check_noise, check_physical
from gyrocal.io.outputs import atomic, write_csv, write_json
from gyrocal.pipeline.steps.common import known_effects, load_maneuvers


def model_priors(est: PointEstimate, priors_cfg: dict, prior_from=None) -> posterior.Priors:
    """The spec's declared priors, overridden by the config and by an earlier campaign's
    ``calibration.csv`` (``prior_from``)."""
    earlier = pd.read_csv(prior_from) if prior_from else None
    spec = est.spec.with_priors(priors_cfg, earlier, str(prior_from))
    return posterior.Priors.from_spec(spec, est.stated_noise, priors_cfg["noise_log_sd"])


def run(npz_paths, point_npz, plugin_paths, priors_cfg, prior_from, sampler_cfg, grid_cfg, convergence_cfg, seed,
        out_nc, out_summary, out_fit, out_sampler, out_elpd, out_loo):
    """Sample the posterior, check convergence, save InferenceData, summary, model fit, the exact
    leave-one-maneuver-out predictive densities and PSIS-LOO per block (here, where arviz and the
    InferenceData already are, so that the comparison of the models needs neither)."""
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(point_npz, known_effects(plugin_paths))
    priors = model_priors(est, priors_cfg, prior_from)
    check_blocks(maneuvers, sampler_cfg["block_s"])
    check_noise(maneuvers, est)
    check_physical(maneuvers, est, priors.bound)
    post = posterior.sample(maneuvers, est, priors, sampler_cfg, grid_cfg, seed)
    idata, summary, fit, record = inferencedata.assemble(post, maneuvers, sampler_cfg, convergence_cfg, seed)
    with atomic(out_nc) as tmp:
        idata.to_netcdf(str(tmp))
    write_csv(summary, out_summary)
    write_csv(fit, out_fit)
    write_json(record, out_sampler)
    write_csv(inferencedata.loo_blocks(idata, est.spec.model), out_loo)
    elpd = posterior.leave_one_maneuver_out(post, priors)
    write_csv(pd.DataFrame({"maneuver": [d.id for d in maneuvers], "elpd": elpd}), out_elpd)
