"""Free-motion maneuvers (no axis label): the eigen-axis slew and tumble scenarios simulate campaigns
that validate, classic.csv gives them no number, and a flipped channel is still named."""

import numpy as np
import pandas as pd
import pytest
import yaml

from gyrocal.checks.campaign import read_checked
from gyrocal.inference.fit import classic, identification
from gyrocal.io.telemetry import TelemetryError, read_campaign, write_campaign
from gyrocal.maneuvers import preprocess
from gyrocal.model import combinations
from gyrocal.model.spec import baseline
from gyrocal.simulation import simulate

SCENARIOS = "config/scenarios"


@pytest.fixture(scope="module", params=["mom_eigen", "mom_tumble"])
def free_campaign(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(request.param)
    simulate.run(f"{SCENARIOS}/{request.param}.yaml", out)
    return out / "campaign"


def test_free_scenarios_write_campaigns_without_axis_labels_that_validate(free_campaign):
    meta = yaml.safe_load((free_campaign / "campaign.yaml").read_text())
    assert all("axis" not in m and "direction" not in m for m in meta["maneuvers"])
    campaign, findings = read_checked(free_campaign)
    assert all(m.free and m.turn == "free" for m in campaign.maneuvers)
    assert sum("free motion" in w for w in findings.warnings) == len(campaign.maneuvers)


def test_classic_gives_free_maneuvers_no_number_and_says_so(free_campaign):
    campaign = read_campaign(free_campaign)
    data = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    table = classic.classic_table(data, baseline(campaign.channels))
    assert len(table) == 24 and table["value"].isna().all() and (table["n"] == 0).all()
    assert table["note"].str.contains("no number from the paper's method").all()
    assert not np.any(classic.classic_vector(table, baseline(campaign.channels)))


def test_a_flipped_channel_in_free_motion_is_named(tmp_path):
    campaign, _ = simulate.simulate(simulate.load_scenario(f"{SCENARIOS}/mom_eigen.yaml"))
    campaign.gyro_columns["dtg2_pitch"] = -campaign.gyro_columns["dtg2_pitch"]
    write_campaign(campaign, tmp_path / "c")
    with pytest.raises(TelemetryError, match="dtg2_pitch turns opposite"):
        read_checked(tmp_path / "c")


def test_axis_without_direction_is_refused(tmp_path):
    campaign, _ = simulate.simulate(simulate.load_scenario(f"{SCENARIOS}/mom_eigen.yaml"))
    write_campaign(campaign, tmp_path / "c")
    path = tmp_path / "c" / "campaign.yaml"
    meta = yaml.safe_load(path.read_text())
    meta["maneuvers"][0]["axis"] = "roll"
    path.write_text(yaml.safe_dump(meta))
    with pytest.raises(TelemetryError, match="direction"):
        read_campaign(tmp_path / "c")


def _sliced(scenario):
    campaign, _ = simulate.simulate(scenario)
    return campaign, [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]


def test_free_motion_turning_every_axis_both_ways_leaves_no_term_prior_only():
    campaign, data = _sliced(simulate.load_scenario(f"{SCENARIOS}/mom_eigen.yaml"))
    assert identification.unflown(data, baseline(campaign.channels)) == {}
    assert combinations.flown_directions(data) == {(a, s) for a in ("roll", "pitch", "yaw") for s in "+-"}


def test_turning_only_about_plus_roll_leaves_the_other_scale_factors_prior_only_and_names_the_turns():
    scenario = simulate.load_scenario("tests/data/tiny.yaml")
    scenario["maneuvers"] = [m for m in scenario["maneuvers"] if m["id"] == "roll_pos"]
    campaign, data = _sliced(scenario)
    for d in data:  # the motion decides, not the label
        d.axis, d.direction = None, None
    reasons = identification.unflown(data, baseline(campaign.channels))
    for c in campaign.channels:
        if c.axis == "roll":
            assert f"{c.name}.sf_pos" not in reasons
            assert reasons[f"{c.name}.sf_neg"] == "no -roll turn in the data: turn about -roll"
        else:
            for name in ("sf_pos", "sf_neg"):
                assert reasons[f"{c.name}.{name}"].startswith(f"no {'+' if name == 'sf_pos' else '-'}{c.axis} turn")
            assert f"{c.name}.mis_roll" not in reasons
    assert reasons["dtg1_roll.mis_pitch"] == "no pitch turn in the data: turn about pitch, either way"
    assert combinations.flown_directions(data) == {("roll", "+")}
    assert combinations.advice("sf_mean", "roll", combinations.flown_directions(data)) == \
        "turn about -roll (the data turn only +roll)"


def test_a_campaign_with_free_motion_is_reviewed_in_a_labs_words():
    from gyrocal.report.context import FLIGHT_WORDS, LAB_WORDS, campaign_words
    from gyrocal.report.review import paper_tables

    scenario = simulate.load_scenario("tests/data/tiny.yaml")
    campaign, data = _sliced(scenario)
    assert campaign_words(data) is FLIGHT_WORDS and campaign_words(campaign.maneuvers) is FLIGHT_WORDS
    data[0].axis, data[0].direction = None, None
    words = campaign_words(data)
    assert words is LAB_WORDS
    text = " ".join(words.values()).lower()
    assert not any(w in text for w in ("spacecraft", "uplink", "in-loop", "in loop", "star tracker"))
    cal = pd.DataFrame([{"channel": c.name, "parameter": p, "point": 0.0, "mean": 0.0, "ci95_low": -1.0,
                         "ci95_high": 1.0} for c in campaign.channels
                        for p in ("sf_pos", "sf_neg", "mis_roll", "mis_pitch", "mis_yaw")])
    tables = paper_tables(cal, campaign.channels, data[0].sets[0], axis_heading=words["axis"])
    assert "body axis" in tables["table1_sf"].columns and "spacecraft axis" not in tables["table1_sf"].columns


def test_the_clock_offset_of_a_tumble_is_found_from_all_axes_together():
    from gyrocal.checks.sampling import clock_offset_s
    from gyrocal.checks.sensing import sense

    scenario = simulate.load_scenario(f"{SCENARIOS}/mom_tumble.yaml")
    scenario["effects"]["st_latency_s"] = 0.5
    scenario["maneuvers"] = scenario["maneuvers"][:2]
    _, data = _sliced(scenario)
    offsets = [clock_offset_s(sense(d)) for d in data]
    assert np.allclose(np.abs(offsets), 0.5, atol=0.05)


def test_the_plan_reads_eigen_axis_slews_and_tumbles():
    from gyrocal.planning import plan

    for name in ("mom_eigen", "mom_tumble"):
        scenario = plan.read_scenario(f"{SCENARIOS}/{name}.yaml")
        assert all(m.axis is None for m in simulate.simulate(scenario)[0].maneuvers)


def test_with_a_known_range_a_flat_top_below_it_is_no_clipping():
    from gyrocal.checks.saturation import plateaus

    rng = np.random.default_rng(1)
    rate = np.sin(np.linspace(0, np.pi, 400)) * 1.2 + rng.normal(0, 0.002, 400)
    rate = np.minimum(rate, 1.0)  # flat at 1 rad/s: clipped, or a steady peak the gyro can hold
    assert plateaus("gyro_x", rate)  # judged at its own peak, it looks clipped
    assert not plateaus("gyro_x", rate, range_rad_s=2.0)  # the range is twice that: it is not
    assert plateaus("gyro_x", rate, range_rad_s=1.0)[0].declared


def test_two_swapped_channels_in_free_motion_are_named(tmp_path):
    campaign, _ = simulate.simulate(simulate.load_scenario(f"{SCENARIOS}/mom_eigen.yaml"))
    columns = campaign.gyro_columns
    columns["dtg1_roll"], columns["dtg2_pitch"] = columns["dtg2_pitch"].copy(), columns["dtg1_roll"].copy()
    write_campaign(campaign, tmp_path / "c")
    with pytest.raises(TelemetryError, match="channels dtg1_roll and dtg2_pitch look swapped"):
        read_checked(tmp_path / "c")


@pytest.mark.parametrize("scenario", ["mom_eigen", "mom_tumble"])
@pytest.mark.parametrize("factor, cause", [(180 / np.pi, "degrees rather than radians"), (1000.0, "1000 times too large")])
def test_a_unit_slip_in_free_motion_is_refused_naming_the_unit(scenario, factor, cause, tmp_path):
    """Every gyro column in degrees (or mrad) for radians: the composed rotations wrap and the response
    scatters so widely that no direction is determined, which the response check used to take for no
    evidence; the gyros' path over the reference's, linear in their scale, names the unit."""
    campaign, _ = simulate.simulate(simulate.load_scenario(f"{SCENARIOS}/{scenario}.yaml"))
    for name in campaign.gyro_columns:
        campaign.gyro_columns[name] = campaign.gyro_columns[name] * factor
    write_campaign(campaign, tmp_path / "c")
    with pytest.raises(TelemetryError, match=f"the gyros' path is .* times the reference's where it turns: .*{cause}"):
        read_checked(tmp_path / "c")
