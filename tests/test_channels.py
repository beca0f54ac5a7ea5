import numpy as np
import pytest

from gyrocal.model import channels as ch
from gyrocal.model.spec import baseline as baseline_spec
from gyrocal.model.units import ARCSEC_RAD, PPM, paper_term


@pytest.fixture
def params():
    rng = np.random.default_rng(1)
    return ch.ChannelParams(ch.MOM_CHANNELS, rng.normal(0, 2e-3, 6), rng.normal(0, 2e-3, 6),
                            rng.normal(0, 2e-3, (6, 3)), rng.normal(0, 1e-7, 6))


def test_forward_applies_eq_3_per_channel():
    p = baseline_spec(ch.MOM_CHANNELS).params_from_contract({"dtg2_yaw": {"sf_pos": -1712, "sf_neg": -1000,
                                                                          "mis_roll": 133, "mis_pitch": 0}})
    w = np.array([[0.01, 0.02, 0.03], [0.01, 0.02, -0.03]])
    out = ch.measure(w, p)[:, 2]
    m = 133 * ARCSEC_RAD
    assert np.allclose(out, [(1 - 1712 * PPM) * (0.03 + m * 0.01), (1 - 1000 * PPM) * (-0.03 + m * 0.01)])


@pytest.mark.parametrize("channel_set", [("dtg1_roll", "dtg2_pitch", "dtg2_yaw"),
                                         ("dtg3_roll", "dtg1_pitch", "dtg3_yaw"),
                                         ("dtg3_roll", "dtg2_pitch", "dtg2_yaw")])
def test_inverse_recovers_body_rate_from_any_spanning_set(params, channel_set):
    rng = np.random.default_rng(2)
    raw = rng.normal(0, 0.01, (500, 3))
    w = np.sign(raw) * (0.002 + np.abs(raw))   # away from zero: the branch follows the output's sign
    dt = np.full(500, 0.1)
    out = ch.measure(w * 0.1, params, dt_s=dt)
    idx = [ch.MOM_CHANNELS.index(next(c for c in ch.MOM_CHANNELS if c.name == n)) for n in channel_set]
    back = ch.solve_body(out[:, idx], params.subset(channel_set), dt_s=dt)
    assert np.allclose(back, w * 0.1, rtol=0, atol=1e-15)


def test_the_branch_follows_what_the_channel_senses_so_the_inverse_is_exact_near_zero_own_rate(params):
    """A channel whose own axis barely turns while another does senses mostly the misalignment's share
    of that rate; forward and inverse take the branch from that sensed rate and agree exactly."""
    rng = np.random.default_rng(4)
    w = np.column_stack([rng.normal(0, 1e-6, 400), rng.normal(0, 1e-6, 400), np.full(400, 0.003)])
    sensed = w @ ch.response_rows(params).T
    own = w[:, ch.input_axes(params.channels)]
    assert np.mean(np.sign(sensed) != np.sign(own)) > 0.1  # the case the branch on omega_a got wrong
    back = ch.solve_body(ch.measure(w, params), params)
    assert np.allclose(back, w, rtol=0, atol=1e-15)


def test_inverse_with_all_six_channels_is_least_squares(params):
    raw = np.random.default_rng(3).normal(0, 0.01, (100, 3))
    w = np.sign(raw) * (0.002 + np.abs(raw))
    back = ch.solve_body(ch.measure(w, params), params)
    assert np.allclose(back, w, atol=1e-15)


def test_inverse_refuses_a_set_that_misses_an_axis(params):
    with pytest.raises(ValueError, match="no channel senses roll"):
        ch.solve_body(np.zeros((2, 3)), params.subset(["dtg1_pitch", "dtg2_pitch", "dtg2_yaw"]))


def test_paper_names_index_yaw_1_roll_2_pitch_3():
    assert [paper_term("yaw", "roll"), paper_term("yaw", "pitch"), paper_term("roll", "yaw"),
            paper_term("roll", "pitch"), paper_term("pitch", "yaw"), paper_term("pitch", "roll")] == \
        ["mc12", "mc13", "mc21", "mc23", "mc31", "mc32"]


def test_terms_are_read_and_written_by_their_contract_names(params):
    params.set(2, "mis_roll", 1e-4)
    params.set(2, "sf_neg", -2e-3)
    assert params.mis_rad[2, 0] == 1e-4 and params.get(2, "mis_roll") == 1e-4
    assert params.sf_neg[2] == -2e-3 and params.get(2, "sf_neg") == -2e-3


def test_channel_sets_start_with_the_in_loop_set_and_cover_every_channel():
    sets = ch.channel_sets(ch.MOM_CHANNELS, ["dtg2_yaw", "dtg1_roll", "dtg2_pitch"])
    assert sets[0] == ("dtg1_roll", "dtg2_pitch", "dtg2_yaw")
    assert sets[1] == ("dtg3_roll", "dtg1_pitch", "dtg3_yaw")
    assert {n for s in sets for n in s} == {c.name for c in ch.MOM_CHANNELS}
