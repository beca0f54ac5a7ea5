"""The uplink at the campaign's rates: a linear onboard correction takes the scale factor a
rate-dependent one has at the rates the campaign turned (`gyrocal.inference.fit.operating`)."""

import arviz as az
import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from gyrocal.criticism.uplinked import at_uplink, flown_intervals, uplinked_intervals
from gyrocal.inference.fit.operating import operating_map, operating_params, operating_shift
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.model import effects
from gyrocal.model.channels import MOVING_RATE_FRACTION, Channel
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
    """Sum over every gyro interval turning ``channel`` that way, faster than the share of its maneuver's
    peak rate that counts as turning, of q w^2 dtheta, over the angle (no bias: tiny's are 0.01 deg/h)."""
    added = turned = 0.0
    for d in maneuvers:
        peak = np.max(np.abs(d.increments / d.dt[:, None]))
        for k in range(len(d.dt)):
            inc = d.increments[k, channel]
            if way * inc > 0 and abs(inc / d.dt[k]) > MOVING_RATE_FRACTION * peak:
                added += Q_SI * (inc / d.dt[k]) ** 2 * inc
                turned += inc
    return added / turned


def one_turn(rate_rad_s, bias_rad_s, arw_rad_sqrt_s, seed=3):
    """A gyro triad turning about x at ``rate_rad_s`` for 100 s between two 100-s holds, 10 Hz, each
    channel reading its bias and white noise besides; the reference follows the true turn."""
    channels = tuple(Channel(f"gyro_{a}", None, axis) for a, axis in zip("xyz", ("roll", "pitch", "yaw")))
    dt = 0.1
    time = np.arange(3001) * dt
    true = np.zeros((3000, 3))
    true[1000:2000, 0] = rate_rad_s
    rng = np.random.default_rng(seed)
    increments = (true + bias_rad_s) * dt + arw_rad_sqrt_s * np.sqrt(dt) * rng.standard_normal(true.shape)
    angle = np.concatenate([[0.0], np.cumsum(true[:, 0] * dt)])
    st = np.arange(0, 3001, 10)
    quat = Rotation.from_rotvec(np.outer(angle[st], [1.0, 0.0, 0.0])).as_quat()
    return ManeuverData("turn", None, None, channels, tuple(c.name for c in channels), time, increments, time[st],
                        quat, quat[0])


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


def test_holds_noise_and_a_bias_do_not_move_the_scale_factor_at_the_campaigns_rate():
    """A turn at 0.5 deg/s between holds, with an ARW of 0.3 deg/sqrt(h) and a bias of 0.05 deg/s on
    every channel (a tenth of the rate): given the bias the fit estimates, the growth is what the
    model's own column adds over the turn (q r^2 on the raw rate r = 0.55 deg/s) per bias-free angle,
    q r^3 / 0.5 deg/s, within 1 %: the holds' noise and bias count for next to nothing. Over every
    interval, raw, it came out 6 % low with the noise and tens of percent off with the bias."""
    rate, bias = np.deg2rad(0.5), np.deg2rad(0.05)
    data = one_turn(rate, bias, np.deg2rad(0.3) / 60.0)
    spec = nonlinear_spec(data.channels)
    shift = operating_shift([data], spec, np.full(len(spec.extras), Q_SI), [np.full(3, bias)])
    assert shift[0, 0] == pytest.approx(Q_SI * (rate + bias) ** 3 / rate, rel=0.01)


def test_the_uplinked_intervals_are_each_draws_scale_factor_at_the_campaigns_rates(maneuvers):
    """Each draw's scale factor plus the growth its own coefficients give over the angle turned
    (`operating_shift` of that draw, one by one), its 2.5 and 97.5 % quantiles: the same numbers."""
    spec = nonlinear_spec(maneuvers[0].channels)
    rng = np.random.default_rng(5)
    values = rng.normal(0.0, 1.0, (2, 12, len(spec))) * np.where(np.arange(len(spec)) < spec.n_core, 300.0, 0.0)
    values[..., spec.extra] = rng.normal(50.0, 20.0, (2, 12, len(spec.extras))) * (Q_SI / spec.si_per_unit[spec.extra])
    table = flown_intervals(values, spec, operating_map(maneuvers, spec)).set_index(["channel", "parameter"])
    flat = values.reshape(-1, len(spec))
    shifts = np.array([operating_shift(maneuvers, spec, spec.to_si(v)[spec.extra]) for v in flat])
    sf = [(j, p) for j, p in enumerate(spec.parameters[:spec.n_core]) if p.name in ("sf_pos", "sf_neg")]
    assert len(table) == len(sf) + 2 * len(spec.channels)   # each channel's sf_mean and sf_asym too
    flown = {}
    for j, p in sf:
        c = [ch.name for ch in spec.channels].index(p.owner)
        flown[p.owner, p.name] = by_hand = flat[:, j] + shifts[:, int(p.name == "sf_neg"), c] / PPM
        row = table.loc[(p.owner, p.name)]
        assert row["mean"] == pytest.approx(by_hand.mean(), rel=1e-9, abs=1e-9)
        assert row["sd"] == pytest.approx(by_hand.std(ddof=1), rel=1e-9)
        assert [row["ci95_low"], row["ci95_high"]] == pytest.approx(np.quantile(by_hand, [0.025, 0.975]), rel=1e-9)
    for c in spec.channels:
        pos, neg = flown[c.name, "sf_pos"], flown[c.name, "sf_neg"]
        assert table.loc[(c.name, "sf_mean"), "sd"] == pytest.approx(np.std((pos + neg) / 2, ddof=1), rel=1e-9)
        assert table.loc[(c.name, "sf_asym"), "mean"] == pytest.approx(np.mean(pos - neg), rel=1e-9, abs=1e-9)


def test_one_rate_leaves_the_intercept_wide_and_the_uplinked_scale_factor_narrow(maneuvers):
    """Draws where the intercept and the growth trade off along the one rate flown (what a campaign at
    one rate leaves): the intercept's interval spans thousands of ppm, the uplinked one the few left."""
    spec = nonlinear_spec(maneuvers[0].channels)
    shift_map = operating_map(maneuvers, spec)
    rng = np.random.default_rng(8)
    q = rng.normal(0.0, 4000.0, 4000)[:, None] * Q_SI / 50.0   # sd 4000 ppm per (deg/s)^2: 1000 ppm at 0.5 deg/s
    values = np.zeros((4000, len(spec)))
    values[:, spec.extra] = q / spec.si_per_unit[spec.extra]
    growth = shift_map @ np.ones(len(spec.extras))            # (2, n): per unit coefficient on every channel
    noise = rng.normal(0.0, 10.0, (4000, spec.n_core))
    for j, p in enumerate(spec.parameters[:spec.n_core]):
        c = [ch.name for ch in spec.channels].index(p.owner)
        if p.name in ("sf_pos", "sf_neg"):
            values[:, j] = -q[:, 0] * growth[int(p.name == "sf_neg"), c] / PPM + noise[:, j]
    table = flown_intervals(values, spec, shift_map)
    table = table[table["parameter"].isin(["sf_pos", "sf_neg"])]
    rotated = table[table["mean"].abs() < 5.0]
    assert len(rotated) == len(table)
    width = (table["ci95_high"] - table["ci95_low"]).to_numpy()
    intercept = np.array([np.ptp(np.quantile(values[:, spec.index(f"{r.channel}.{r.parameter}")], [0.025, 0.975]))
                          for r in table.itertuples()])
    assert np.all(width < 45.0) and np.all(intercept > 10 * width)


def test_the_review_reads_the_uplinked_posterior_off_the_inferencedata_and_replaces_only_those_rows(maneuvers):
    """`uplinked_intervals` of an InferenceData's ``channel_param`` (chain, draw, parameter) is
    `flown_intervals` of its draws; a model whose scale factor does not change with the rate gets None,
    and `at_uplink` leaves its calibration as it is; otherwise it replaces the scale factors' summary
    and nothing else."""
    spec = nonlinear_spec(maneuvers[0].channels)
    rng = np.random.default_rng(2)
    values = rng.normal(0.0, 100.0, (2, 30, len(spec)))
    posterior = az.from_dict(posterior={"channel_param": values}, coords={"parameter": spec.labels},
                             dims={"channel_param": ["parameter"]})
    table = uplinked_intervals(posterior, spec, operating_map(maneuvers, spec, np.zeros((len(maneuvers), len(spec.channels)))))
    expected = flown_intervals(values, spec, operating_map(maneuvers, spec))
    pd.testing.assert_frame_equal(table, expected)
    assert uplinked_intervals(posterior, baseline(spec.channels), operating_map(maneuvers, baseline(spec.channels))) is None
    calibration = pd.DataFrame({"channel": [p.owner for p in spec.parameters], "parameter": [p.name for p in spec.parameters],
                                "unit": spec.units, "mean": 1.0, "sd": 2.0, "ci95_low": -3.0, "ci95_high": 5.0,
                                "r_hat": 1.0})
    assert at_uplink(calibration, None) is calibration
    moved = at_uplink(calibration, table).set_index(["channel", "parameter"])
    for r in expected.itertuples():
        if (r.channel, r.parameter) in moved.index:
            assert moved.loc[(r.channel, r.parameter), "ci95_high"] == r.ci95_high
    untouched = moved.drop(index=[(r.channel, r.parameter) for r in expected.itertuples()], errors="ignore")
    assert len(untouched) and (untouched["mean"] == 1.0).all() and (moved["r_hat"] == 1.0).all()
    assert list(at_uplink(calibration, table).columns) == list(calibration.columns)
