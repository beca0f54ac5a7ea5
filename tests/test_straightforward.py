"""The straightforward model of benchmarks/sampler_vs_straightforward.py is the same model as gyrocal's:
a benchmark against a wrong model would be worthless."""

import sys

import numpy as np
from scipy.optimize import least_squares

from gyrocal.inference import errormodel
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.inference.sampling.priors import Priors
from gyrocal.io import telemetry
from gyrocal.maneuvers import preprocess
from gyrocal.model.spec import baseline
from gyrocal.model.units import rad_s_to_deg_h

from conftest import ROOT, truth_vector

sys.path.insert(0, str(ROOT / "benchmarks"))
from sampler_vs_straightforward import Straightforward


def test_straightforward_errors_follow_gyrocal_linearisation(tiny, config):
    """About the truth, the exact re-propagated errors move as gyrocal's Jacobian says, for a step in
    every channel parameter, initial attitude error and bias at once; at the true channel parameters,
    with each maneuver's nuisance fitted, the star tracker is matched at its stated noise, and the
    log-likelihood is far lower 100 ppm or 20 arcsec off the truth, either way, in any channel
    parameter."""
    campaign = telemetry.read_campaign(tiny[0])
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, config["noise"])
    spec = baseline(campaign.channels)
    truth = truth_vector(campaign.channels, tiny[1])
    theta = spec.core_vector(truth)
    priors = Priors.from_spec(spec, stated, 1.0)
    model = Straightforward(maneuvers, spec, priors, stated)
    nuisance = np.tile(np.concatenate([np.zeros(3), rad_s_to_deg_h(truth.bias_rad_s)]), len(maneuvers))
    x0 = np.concatenate([spec.to_unit(theta), nuisance])
    rng = np.random.default_rng(3)
    step = np.concatenate([rng.normal(0, 30, len(spec)),
                           np.tile(np.concatenate([rng.normal(0, 3, 3), rng.normal(0, 0.005, 6)]), len(maneuvers))])
    change = [e1 - e0 for e0, e1 in zip(model.errors(x0), model.errors(x0 + step))]
    predicted = []
    for m, d in enumerate(maneuvers):
        lin = errormodel.linearize(d, spec, theta, truth.bias_rad_s)
        nuis = step[len(spec) + 9 * m:len(spec) + 9 * (m + 1)]
        d_theta, d_chi0 = spec.to_si(step[:len(spec)]), nuis[:3] * np.pi / 648000
        d_bias = nuis[3:] * np.pi / 180 / 3600
        for s in range(len(d.sets)):
            dz = -(lin.design[:, s] @ d_theta + lin.bias_design[:, s] @ d_bias + d_chi0)
            predicted.append(np.einsum("mba,mb->ma", lin.st_matrix, dz))
    change, predicted = np.concatenate(change), np.concatenate(predicted)
    assert np.sqrt(np.mean((change - predicted) ** 2)) < 0.02 * np.sqrt(np.mean(predicted**2))
    x_fit = x0.copy()
    for m, d in enumerate(maneuvers):
        single = Straightforward([d], spec, priors, stated)
        rows = slice(len(spec) + 9 * m, len(spec) + 9 * (m + 1))
        fit = least_squares(lambda n, single=single: single.residuals(np.concatenate([x0[:len(spec)], n])), x0[rows])
        x_fit[rows] = fit.x
    assert np.mean(model.residuals(x_fit) ** 2) < 1.3
    loglik = model.log_likelihood(x_fit)
    for i, unit in enumerate(spec.units):
        for sign in (-1, 1):
            off = x_fit.copy()
            off[i] += sign * (100 if unit == "ppm" else 20)
            assert model.log_likelihood(off) < loglik - 100, (spec.labels[i], sign)
