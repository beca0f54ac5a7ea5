"""The reference interval chosen from the data (`gyrocal.inference.interval`, ``reference_interval_s: auto``)."""

import copy
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation

from gyrocal.errors import InputError
from gyrocal.inference import interval
from gyrocal.inference.noise import smoothness
from gyrocal.io.scenario import load_scenario
from gyrocal.maneuvers import preprocess
from gyrocal.model.units import arcsec_to_rad
from gyrocal.simulation.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]


def _campaign(seed=3, star_tracker=None, maneuver=None, short=None, gyro=None, **top):
    """A short simulated campaign (the default's yaw maneuvers, 100 s holds), with ``star_tracker``,
    ``maneuver`` (defaults), ``short`` (the second maneuver's own), ``gyro`` and ``top`` scenario keys changed;
    with the noise it states, as the pipeline would take it."""
    scenario = copy.deepcopy(load_scenario(ROOT / "config" / "scenarios" / "mom.yaml"))
    scenario["maneuvers"] = scenario["maneuvers"][:2]
    if short:
        scenario["maneuvers"][1] = {**scenario["maneuvers"][1], **short}
    scenario["maneuver_defaults"].update({"hold_s": 100.0, **(maneuver or {})})
    scenario["star_tracker"].update(star_tracker or {})
    scenario["gyro"].update(gyro or {})
    scenario.update(top)
    campaign, _ = simulate(scenario, seed)
    st = scenario["star_tracker"]
    stated = {"sigma_cross_arcsec": st["sigma_cross_arcsec"], "sigma_about_arcsec": st["sigma_about_arcsec"],
              "boresight_body": st["boresight_body"], "arw_deg_sqrt_h": scenario["gyro"]["arw_deg_sqrt_h"]}
    return campaign, stated


def _sliced(campaign, interval_s=0.0):
    return [preprocess.slice_maneuver(campaign, m.id, reference_interval_s=interval_s) for m in campaign.maneuvers]


def _with_smooth_error(campaign, sd_arcsec, kernel_samples, seed=0):
    """The campaign with a smooth error in the reference (white noise through a Gaussian kernel of
    ``kernel_samples`` sd, ``sd_arcsec`` per axis), in its own frame: a pose-dependent error."""
    smooth = gaussian_filter1d(np.random.default_rng(seed).normal(size=(len(campaign.st_time), 3)), kernel_samples,
                               axis=0)
    smooth *= arcsec_to_rad(sd_arcsec) / smooth.std(axis=0)
    quat = (Rotation.from_quat(campaign.st_quat) * Rotation.from_rotvec(smooth)).as_quat()
    return dataclasses.replace(campaign, st_quat=quat)


def test_auto_and_seconds_are_read_and_anything_else_is_refused_by_name():
    assert interval.requested("auto") is None and interval.requested(" Auto ") is None
    assert interval.requested(0) == 0.0 and interval.requested(0.5) == 0.5
    with pytest.raises(InputError, match=r"a number of seconds or 'auto', got 'fast'"):
        interval.requested("fast")
    with pytest.raises(InputError, match=r"0 or more seconds, got -1"):
        interval.requested(-1)


def test_a_white_reference_keeps_every_sample_with_no_fit():
    """The default campaign's kind: the nominal error is white at 1 s, so no pilot fit is made."""
    campaign, stated = _campaign()
    choice = interval.choose(_sliced(campaign), stated)
    assert choice.interval_s == 0.0 and not choice.fitted
    assert [s.maneuver for s in choice.measured] == ["yaw_pos", "yaw_neg"]
    assert all(not s.smooth for s in choice.measured)
    assert choice.reason.startswith("every reference sample is used: the nominal error is not smooth")


def test_a_nominal_error_smooth_from_the_scale_factors_alone_is_fitted_and_keeps_every_sample():
    """A 0.2-arcsec tracker at 10 Hz on a 180-degree turn ramping to 3 deg/s over 30 s, with the
    default's 0.2 % scale factors: the nominal error's rate changes by 20 arcsec/s (a constant rate
    counts as nothing), smooth; the baseline fitted at every sample leaves white noise."""
    campaign, stated = _campaign(star_tracker={"sigma_cross_arcsec": 0.2, "sigma_about_arcsec": 0.2},
                                 maneuver={"rate_deg_s": 3.0, "accel_deg_s2": 0.1, "hold_s": 20.0, "gap_s": 20.0,
                                           "angle_deg": 180.0},
                                 star_tracker_hz=10.0, gyro_hz=20.0)
    nominal = [interval.nominal(d) for d in _sliced(campaign)]
    assert any(s.smooth for s in nominal), [s.exponent[0] for s in nominal]
    choice = interval.choose(_sliced(campaign), stated)
    assert choice.fitted and choice.interval_s == 0.0, [s.exponent[0] for s in choice.measured]
    assert "the baseline model's residual, fitted at every sample with its noise scales estimated, is not smooth" in choice.reason


@pytest.mark.full  # 11 s; the fast tier keeps the smooth error found between slews and the interval's refusals
def test_a_reference_error_smooth_at_its_rate_is_used_every_five_knees_and_is_not_smooth_there():
    """A 30-arcsec error through a 0.5 s kernel on a 10 Hz tracker (the T-stick's kind at 100 Hz):
    smooth on both maneuvers; used every `recommended_interval_s`, the pilot's residual is no longer smooth."""
    campaign, stated = _campaign(star_tracker={"sigma_cross_arcsec": 2.0, "sigma_about_arcsec": 2.0},
                                 star_tracker_hz=10.0, gyro_hz=20.0)
    campaign = _with_smooth_error(campaign, 30.0, 5)
    choice = interval.choose(_sliced(campaign), stated)
    assert choice.fitted and all(s.smooth for s in choice.measured)
    assert choice.interval_s == smoothness.recommended_interval_s(choice.measured)
    assert 1.0 <= choice.interval_s <= 10.0, choice.interval_s
    assert f"the reference is used every {choice.interval_s:.3g} s" in choice.reason
    thinned = _sliced(campaign, choice.interval_s)
    assert all(d.counts["st_thinned"] > 0 for d in thinned)
    again = interval.choose(thinned, stated)
    assert again.interval_s == 0.0, [s.exponent[0] for s in again.measured]


def test_the_record_says_what_was_measured_and_is_json(tmp_path):
    campaign, stated = _campaign()
    record = interval.choose(_sliced(campaign), stated).record()
    assert record["requested"] == "auto" and record["interval_s"] == 0.0 and record["fitted"] is False
    assert set(record["maneuvers"]) == {"yaw_pos", "yaw_neg"}
    assert json.loads(json.dumps(record)) == record


@pytest.mark.parametrize("setting, interval_s, fitted", [("auto", 0.0, False), (0, 0.0, False), (4, 4.0, False)])
def test_the_preprocess_step_records_the_interval_it_used_and_counts_what_it_left_out(tiny, tmp_path, config,
                                                                                       setting, interval_s, fitted):
    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.run import calibrate_campaign
    from gyrocal.pipeline.steps.common import load_maneuvers

    paths = CampaignPaths.under(tmp_path)
    ids = calibrate_campaign(tiny[0], paths, {**config, "reference_interval_s": setting}, [], figures=False)
    record = json.loads(Path(paths.reference_interval).read_text())
    assert (record["requested"], record["interval_s"], record["fitted"]) == (setting, interval_s, fitted)
    thinned = [d.counts["st_thinned"] for d in load_maneuvers(paths.maneuvers(ids))]
    assert all(n > 0 for n in thinned) if interval_s else not any(thinned)
    assert ("as the config sets" in record["reason"]) == (setting != "auto")


@pytest.mark.full
def test_a_maneuver_too_short_for_the_interval_auto_chose_is_used_at_the_longest_one_it_can_take(tmp_path, config):
    """The smooth-error campaign of above, its second maneuver cut to 14 s: auto chooses 5 s from the long
    one; the short one cannot keep 10 samples every 5 or 2 s, and is used every 1 s, which the record and
    its reason say (the smoothness check then judges each model's residual)."""
    from gyrocal.io.telemetry import write_campaign
    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.run import calibrate_campaign
    from gyrocal.pipeline.steps.common import load_maneuvers

    short = {"hold_s": 3.0, "angle_deg": 12.0, "rate_deg_s": 2.0, "accel_deg_s2": 1.0}
    campaign, stated = _campaign(star_tracker={"sigma_cross_arcsec": 2.0, "sigma_about_arcsec": 2.0},
                                 star_tracker_hz=10.0, gyro_hz=20.0, short=short)
    campaign = _with_smooth_error(campaign, 30.0, 5)
    write_campaign(campaign, tmp_path / "campaign")
    cfg = {**config, "noise": {**config["noise"], **{k: v for k, v in stated.items() if k != "boresight_body"}},
           "sampler": {**config["sampler"], "block_s": 5.0}}
    paths = CampaignPaths.under(tmp_path / "out")
    ids = calibrate_campaign(tmp_path / "campaign", paths, cfg, [], figures=False)
    record = json.loads(Path(paths.reference_interval).read_text())
    assert record["interval_s"] == 5.0
    assert [record["maneuvers"][m]["interval_s"] for m in ids] == [5.0, 1.0]
    assert record["reason"].endswith("too short to keep 10 samples at that interval, yaw_neg every 1 s")
    kept = [d.counts["st_used"] for d in load_maneuvers(paths.maneuvers(ids))]
    assert kept[1] >= 10 and kept[0] > kept[1]


def test_the_1_2_5_ladder_steps_down():
    assert [interval.shorter(s) for s in (5.0, 2.0, 1.0, 0.5, 0.2, 50.0)] == [2.0, 1.0, 0.5, 0.2, 0.1, 20.0]


def test_a_smooth_error_seen_only_between_slews_is_still_found():
    """The smooth-error campaign with the tracker blind while turning (found by an independent review): the
    nominal parameters' error steps across each gap (0.2 % of 90 degrees), which, counted in samples,
    grows with the lag as a walk and hid the smooth error (auto kept every sample); the increments are
    now taken between gaps only."""
    campaign, stated = _campaign(star_tracker={"sigma_cross_arcsec": 2.0, "sigma_about_arcsec": 2.0},
                                 star_tracker_hz=10.0, gyro_hz=20.0)
    campaign = _with_smooth_error(campaign, 30.0, 5)
    rate = np.abs(campaign.increments()).max(axis=1) / np.gradient(campaign.gyro_time)
    turning = np.interp(campaign.st_time, campaign.gyro_time, rate) > np.radians(0.03)
    blind = dataclasses.replace(campaign, st_valid=np.where(turning, 0, campaign.st_valid))
    sliced = _sliced(blind)
    assert all(np.diff(d.st_time).max() > 100 for d in sliced)
    assert all(interval.nominal(d).smooth for d in sliced)
    assert interval.choose(sliced, stated).interval_s == 5.0  # as without the gaps (above)


@pytest.mark.full  # 4 s; the fast tier keeps the smooth error found between slews and the white reference kept whole
def test_a_stated_arw_four_times_too_low_does_not_thin_a_campaign_whose_model_is_right():
    """A 20 Hz, 0.5-arcsec tracker on 25 Hz gyros of ARW 0.5 deg/sqrt(h), stated as 0.125 (found by an
    independent review): weighed at the stated walk, the interpolated walk's shortfall was too small and
    the residual looked smooth (exponents 0.58-0.60, thinned to 0.5 s); the pilot's walk is now estimated."""
    campaign, stated = _campaign(star_tracker={"sigma_cross_arcsec": 0.5, "sigma_about_arcsec": 0.5},
                                 maneuver={"hold_s": 60.0, "rate_deg_s": 1.0, "accel_deg_s2": 0.1, "gap_s": 20.0},
                                 gyro={"arw_deg_sqrt_h": 0.5}, star_tracker_hz=20.0, gyro_hz=25.0)
    choice = interval.choose(_sliced(campaign), {**stated, "arw_deg_sqrt_h": 0.125})
    assert choice.fitted and choice.interval_s == 0.0, [s.exponent[0] for s in choice.measured]
    assert all(abs(s.exponent[0] - 0.5) < 0.03 for s in choice.measured)
