"""A gyro that clips at its range, told from the gyro alone (gyrocal.checks.saturation): on gyrocal's
own simulated campaigns, clean and clipped, and on synthetic rates whose shape is known. The real
trial that clips is in tests/test_realdata.py."""

import dataclasses

import numpy as np
import pytest

from gyrocal import checks
from gyrocal.checks import saturation, sensing
from gyrocal.io.telemetry import read_campaign
from gyrocal.maneuvers import preprocess


def refusals(campaign, range_rad_s=None) -> dict:
    """Each maneuver's saturation refusal ("" where it is not refused)."""
    found = {}
    for m in campaign.maneuvers:
        findings = checks.Findings()
        clipped = saturation.saturation_findings(sensing.sense(preprocess.slice_maneuver(campaign, m.id)), 0.02,
                                                 findings, range_rad_s)
        assert clipped == bool(findings.errors)
        found[m.id] = findings.errors[0] if findings.errors else ""
    return found


def clipped(campaign, channel, rate_deg_s):
    """The campaign with one channel's increments clipped at ``rate_deg_s`` (as a gyro at its range)."""
    dt = np.diff(campaign.gyro_time, prepend=campaign.gyro_time[0] - np.median(np.diff(campaign.gyro_time)))
    limit = np.deg2rad(rate_deg_s) * dt
    columns = dict(campaign.gyro_columns)
    columns[channel] = np.clip(columns[channel], -limit, limit)
    return dataclasses.replace(campaign, gyro_columns=columns)


@pytest.mark.parametrize("name", ["tiny", "mom"])
def test_the_clean_simulated_campaigns_do_not_clip(name, request):
    """Their slews coast at a steady rate for hundreds of samples: at the peak, but with the
    sensor's noise (their runs' own noise is 1.0 of the channel's on both, against 0.25 to be flat)."""
    campaign = read_campaign(request.getfixturevalue(name)[0])
    assert refusals(campaign) == {m.id: "" for m in campaign.maneuvers}


def test_a_simulated_gyro_clipped_below_its_slew_rate_is_refused_naming_channel_rate_and_samples(tiny):
    """dtg1_roll clipped at 0.45 deg/s, below the 0.5 deg/s slews: both roll maneuvers are refused
    for it, whatever the reference; the yaw and pitch maneuvers, where it stays below its range, are not."""
    found = refusals(clipped(read_campaign(tiny[0]), "dtg1_roll", 0.45))
    assert [m for m, why in found.items() if why] == ["roll_pos", "roll_neg"]
    for maneuver, sign, start in (("roll_pos", "+", 1748.8), ("roll_neg", "-", 2079.0)):
        why = found[maneuver]
        assert (f"maneuver {maneuver}: gyro channel dtg1_roll sits flat at its peak {sign}0.45 deg/s for 861 samples "
                "(within 1%; 1 run of 8 or more), its noise there 0 deg/s where the channel's is ") in why
        assert why.endswith(f"clips at its range, so the body's rotation there is not measured. Leave the maneuver "
                            f"out, or cut it before the first clipped sample, at {start:.2f} s")


def test_a_declared_range_refuses_a_flat_top_that_still_shows_noise():
    """Noise added after the clip (a converter that clips before its noise): not flatter than the
    noise, so only a declared range tells it; 2 samples in a row at the range are enough."""
    rng = np.random.default_rng(3)
    t = 0.01 * np.arange(3000)
    rate = np.clip(3.0 * np.sin(2 * np.pi * 0.2 * t), -2.0, 2.0) + rng.normal(0, 0.005, t.size)
    assert saturation.plateaus("g", rate) == []
    found = saturation.plateaus("g", rate, range_rad_s=2.0)
    assert [(p.sign, p.level_rad_s, p.declared, p.samples, p.flat_runs) for p in found] == [
        (1, 2.0, True, 811, 6), (-1, 2.0, True, 812, 6)]


def test_a_slew_at_the_declared_range_of_its_channel_is_refused(tiny):
    """tiny's slews coast at 0.5 deg/s: declared as dtg1_roll's range, the roll maneuvers sit at
    it (a gyro at its range cannot say whether the body turned faster); the others do not."""
    found = refusals(read_campaign(tiny[0]), {"dtg1_roll": np.deg2rad(0.5)})
    assert [m for m, why in found.items() if why] == ["roll_pos", "roll_neg"]
    assert "gyro channel dtg1_roll sits at its declared range +0.5 deg/s for 852 samples" in found["roll_pos"]
    assert "gyro channel dtg1_roll sits at its declared range -0.5 deg/s for 852 samples" in found["roll_neg"]


@pytest.mark.parametrize("seed", range(5))
def test_a_smooth_peak_and_a_steady_noisy_rate_are_not_flat(seed):
    """A hand-held swing (slow sinusoids) and a coast at a steady rate, each with white noise, and
    their trapezoid-integrated rates: never flat at their peaks, however many samples sit near them."""
    rng = np.random.default_rng(seed)
    t = 0.01 * np.arange(6000)
    swing = 1.4 * np.sin(2 * np.pi * 0.1 * t + seed) + 0.5 * np.sin(2 * np.pi * 0.23 * t)
    coast = np.where((t > 10) & (t < 50), 0.5, 0.0)
    for rate in (swing, coast):
        noisy = rate + rng.normal(0, 0.006, t.size)
        for series in (noisy, 0.5 * (noisy[1:] + noisy[:-1])):
            assert saturation.plateaus("g", series) == []


def test_a_clipped_channel_is_flat_to_a_tenth_of_its_noise():
    """The same swing, clipped at 1.2 rad/s before its noise: flat at both signs, with a count of
    the samples at the clip."""
    rng = np.random.default_rng(0)
    t = 0.01 * np.arange(6000)
    rate = np.clip(1.4 * np.sin(2 * np.pi * 0.1 * t) + rng.normal(0, 0.006, t.size), -1.2, 1.2)
    found = saturation.plateaus("g", rate)
    assert [(p.sign, p.level_rad_s) for p in found] == [(1, 1.2), (-1, 1.2)]
    assert all(p.roughness_rad_s == 0.0 and 0.005 < p.noise_rad_s < 0.007 for p in found)
    assert [p.samples for p in found] == [int((rate >= 1.188).sum()), int((rate <= -1.188).sum())]


def test_a_clipped_plateau_that_drifts_along_its_top_is_flat():
    """A clipped Xsens's output is not one value: it drifts smoothly along the plateau (0.1 deg/s a
    sample on RepoIMU's Test06, under 1 % of its 426 deg/s), a third of the channel's noise between
    samples, so a test on the change between samples let it through. Here 20-sample plateaus at each
    crest of a noisy swing climb 0.0018 rad/s a sample (0.3 of the noise) from 1.2 rad/s: their second
    differences are flat, and both signs are found at the plateau's top, with its samples."""
    rng = np.random.default_rng(1)
    t = 0.01 * np.arange(6000)
    rate = np.sin(2 * np.pi * 0.1 * t) + rng.normal(0, 0.006, t.size)
    drift = 1.2 + 0.0018 * np.arange(20)
    for sign in (1, -1):
        for crest in np.flatnonzero(np.isclose(np.sin(2 * np.pi * 0.1 * t), sign)):
            rate[crest - 10:crest + 10] = sign * drift
    plateau = np.abs(rate) > 1.1
    assert np.median(np.abs(np.diff(rate[plateau]))) > 0.25 * 0.006  # the change between samples: not flat
    found = saturation.plateaus("g", rate)
    top = float(drift[-1])
    assert [(p.sign, round(p.level_rad_s, 4)) for p in found] == [(1, round(top, 4)), (-1, round(top, 4))]
    assert [p.samples for p in found] == [int((rate >= 0.99 * top).sum()), int((rate <= -0.99 * top).sum())]
    assert all(p.roughness_rad_s < 0.25 * p.noise_rad_s for p in found)


def test_a_steady_peak_too_short_to_judge_is_not_called_flat():
    """Steep noisy ramps (0.09 rad/s a sample, beyond the band of 8 noise sds) to a run of 12 samples at
    each sign's peak: 10 second differences, fewer than `MIN_SECOND_DIFFERENCES` (white noise would
    read flat by chance in 0.3 % of such peaks), so even a run all but noise-free is not judged from
    the gyro alone. The same runs 18 samples long are."""
    def swings(run):
        rng = np.random.default_rng(5)
        up, across, down = np.linspace(0, 0.85, 10), np.linspace(0.85, -0.85, 20), np.linspace(-0.85, 0, 10)
        rate = np.concatenate([up, np.zeros(run), across, np.zeros(run), down])
        rate = rate + rng.normal(0, 0.01, rate.size)
        rate[10:10 + run] = 1.0 + 0.0001 * np.arange(run)
        rate[30 + run:30 + 2 * run] = -1.0 - 0.0001 * np.arange(run)
        return rate
    assert saturation.plateaus("g", swings(12)) == []
    assert [p.sign for p in saturation.plateaus("g", swings(18))] == [1, -1]
