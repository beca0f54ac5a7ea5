"""The uplink at the campaign's rates: a linear onboard correction takes the scale factor a
rate-dependent one has at the rates the campaign turned (`gyrocal.inference.fit.operating`)."""

import numpy as np
import pytest

from gyrocal.inference.fit.operating import operating_params, operating_shift
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec, baseline
from gyrocal.model.units import PPM

Q_SI = 50 * PPM / np.deg2rad(1.0) ** 2
"""A scale factor that grows by 50 ppm per (deg/s)^2."""


def nonlinear_spec(channels, scale="scale_factor"):
    names = [scale, "misalignment", "bias", "sf_nonlinearity"]
    return ModelSpec.build("nl", effects.resolve("nl", names, {}), channels)


@pytest.fixture(scope="module")
def maneuvers(tiny_run):
    return [ManeuverData.load(p) for p in tiny_run[1]]


def by_hand(maneuvers, channel, way):
    """Sum over every gyro interval turning ``channel`` that way of q w^2 dtheta, over the angle."""
    added = turned = 0.0
    for d in maneuvers:
        for k in range(len(d.dt)):
            inc = d.increments[k, channel]
            if way * inc > 0:
                added += Q_SI * (inc / d.dt[k]) ** 2 * inc
                turned += inc
    return added / turned


def test_without_a_rate_dependent_scale_factor_nothing_moves(maneuvers):
    spec = baseline(maneuvers[0].channels)
    assert not operating_shift(maneuvers, spec, np.zeros(len(spec.extras))).any()


def test_each_direction_takes_the_growth_averaged_over_the_angle_turned_that_way(maneuvers):
    spec = nonlinear_spec(maneuvers[0].channels)
    extras = np.full(len(spec.extras), Q_SI)
    shift = operating_shift(maneuvers, spec, extras)
    for c in range(len(spec.channels)):
        assert shift[0, c] == pytest.approx(by_hand(maneuvers, c, +1), rel=1e-9)
        assert shift[1, c] == pytest.approx(by_hand(maneuvers, c, -1), rel=1e-9)
    rotated = [c for c, ch in enumerate(spec.channels) if any(d.axis == ch.axis for d in maneuvers)]
    rate_deg_s = 0.5   # tiny.yaml's rotations: the growth there is about q (0.5 deg/s)^2, a little less for the ramps
    assert np.all(shift[:, rotated] > 0.5 * 50 * PPM * rate_deg_s**2)
    assert np.all(shift[:, rotated] <= 50 * PPM * rate_deg_s**2 * 1.01)


def test_a_symmetric_model_takes_one_growth_for_both_ways(maneuvers):
    spec = nonlinear_spec(maneuvers[0].channels, "scale_factor_symmetric")
    shift = operating_shift(maneuvers, spec, np.full(len(spec.extras), Q_SI))
    assert np.array_equal(shift[0], shift[1])
    c = 0
    pos, neg = by_hand(maneuvers, c, +1), by_hand(maneuvers, c, -1)
    assert min(pos, neg) - 1e-15 <= shift[0, c] <= max(pos, neg) + 1e-15


def test_the_shift_adds_to_both_branches_and_nothing_else(maneuvers):
    spec = nonlinear_spec(maneuvers[0].channels)
    params = spec.channel_params(np.linspace(-1e-3, 1e-3, len(spec))[:spec.n_core], np.arange(len(spec.channels)))
    shift = np.vstack([np.full(len(spec.channels), 2e-4), np.full(len(spec.channels), -3e-4)])
    moved = operating_params(params, shift)
    assert np.allclose(moved.sf_pos, params.sf_pos + 2e-4) and np.allclose(moved.sf_neg, params.sf_neg - 3e-4)
    assert np.array_equal(moved.mis_rad, params.mis_rad) and np.array_equal(moved.bias_rad_s, params.bias_rad_s)
