"""What several benchmarks start from: a simulated scenario, cut into maneuvers, with the
baseline model's WLS point estimate and the configured priors."""

import tempfile
from dataclasses import dataclass
from pathlib import Path


@dataclass
class Fitted:
    campaign: object
    maneuvers: list
    stated: dict
    estimate: object
    priors: object


def baseline_fit(scenario_path, cfg: dict) -> Fitted:
    """Simulate ``scenario_path``, slice its maneuvers, and fit the baseline model (classic start,
    REML noise, WLS) as the pipeline would."""
    from gyrocal.inference.fit import classic, estimate
    from gyrocal.inference.noise.covariance import noise_knowledge
    from gyrocal.inference.sampling.priors import model_priors
    from gyrocal.io import telemetry
    from gyrocal.maneuvers import preprocess
    from gyrocal.model.spec import baseline
    from gyrocal.simulation import simulate

    with tempfile.TemporaryDirectory() as tmp:
        simulate.run(scenario_path, tmp)
        campaign = telemetry.read_campaign(Path(tmp) / "campaign")
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = baseline(campaign.channels)
    theta0 = classic.classic_start(maneuvers, spec)
    est = estimate.point_estimate(maneuvers, spec, stated, theta0)
    return Fitted(campaign, maneuvers, stated, est, model_priors(est, cfg["priors"]))


def evaluations_per_s(post, estimate, priors, calls: int) -> float:
    """Log-posterior evaluations per second of gyrocal's sampler, in batches of 64 walkers about
    the conditional posterior mean (what emcee's vectorised calls look like)."""
    import time

    import numpy as np

    from gyrocal.inference.fit.likelihood import campaign_stats, conditional_posterior
    from gyrocal.inference.noise.covariance import variances
    from gyrocal.inference.sampling import posterior

    logpost = posterior.LogPosterior(post.grid, estimate.theta, priors)
    mean, _ = conditional_posterior(campaign_stats(post.noises, variances(estimate.log_sigma)),
                                    priors.mean - estimate.theta, priors.sd)
    x = np.concatenate([mean, estimate.log_sigma]) + np.random.default_rng(0).normal(0, 1e-6, (64, len(mean) + 3))
    start = time.perf_counter()
    for _ in range(calls):
        logpost(x)
    return calls * len(x) / (time.perf_counter() - start)
