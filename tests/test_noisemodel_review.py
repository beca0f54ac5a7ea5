"""The review's noise section: each sampled scale beside the stated one, and the correlated part's time
in words on its clock."""

import numpy as np
import pytest

from gyrocal.report.noisemodel import clock_sentence, noise_table

WHITE = {"noise_posterior": {"sigma_cross_arcsec": 20.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.01},
         "noise_posterior_ci95": {"sigma_cross_arcsec": [18.0, 22.0], "sigma_about_arcsec": [36.0, 44.0],
                                  "arw_deg_sqrt_h": [0.009, 0.011]},
         "noise_stated": {"sigma_cross_arcsec": 10.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.01}}
CORRELATED = {"noise_posterior": {**WHITE["noise_posterior"], "st_gm_fraction": 0.75, "st_gm_tau_s": 1000 * np.pi},
              "noise_posterior_ci95": {**WHITE["noise_posterior_ci95"], "st_gm_fraction": [0.7, 0.8],
                                       "st_gm_tau_s": [500 * np.pi, 2000 * np.pi]},
              "noise_stated": WHITE["noise_stated"]}


def test_each_sampled_scale_stands_beside_its_stated_value_and_an_unstated_one_beside_nothing():
    table = noise_table(CORRELATED).set_index("scale")
    assert list(table.index) == ["sigma_cross_arcsec", "sigma_about_arcsec", "arw_deg_sqrt_h", "st_gm_fraction",
                                 "st_gm_tau_s"]
    assert table.loc["sigma_cross_arcsec", "mean / stated"] == 2.0
    assert table.loc["sigma_about_arcsec", ["ci95_low", "ci95_high"]].tolist() == [36.0, 44.0]
    assert np.isnan(table.loc["st_gm_tau_s", "stated"]) and np.isnan(table.loc["st_gm_tau_s", "mean / stated"])


def test_white_reference_noise_has_no_clock_to_speak_of():
    assert clock_sentence(WHITE, 0.0) == ""


def test_on_the_time_clock_the_correlated_part_forgets_over_seconds():
    said = clock_sentence(CORRELATED, 0.0)
    assert "holds 75.0% of the reference's variance" in said and "forgets over 3.14e+03 s" in said
    assert "angle" not in said


@pytest.mark.parametrize("clock, degrees", [(1000.0, "180 deg turned (90 to 360 deg)"),
                                            (2000.0, "90 deg turned (45 to 180 deg)")])
def test_on_the_angle_clock_the_time_is_also_an_angle_turned(clock, degrees):
    said = clock_sentence(CORRELATED, clock)
    assert f"angle clock of {clock:g} s/rad" in said and "gm_clock_s_per_rad" in said
    assert "3.14e+03 s at rest" in said and degrees in said


def test_a_clock_chosen_from_the_data_says_why_even_where_the_reviewed_noise_is_white():
    chosen = {"reason": "3000 s a radian turned: on the pilot fit's residual ..."}
    said = clock_sentence(CORRELATED, 3000.0, chosen)
    assert said.endswith("The clock was chosen from the data (gm_clock_s_per_rad: auto): 3000 s a radian turned: "
                         "on the pilot fit's residual ....")
    assert clock_sentence(WHITE, 3000.0, chosen).startswith("The clock was chosen from the data")


def test_a_noise_stated_at_rest_stands_beside_the_white_part_it_judges():
    """Where campaign.yaml states the white part (``noise_judged``), the review's table puts the stated 48
    arcsec beside ``st_white_cross_arcsec`` (0.82 of it), not beside the total of 1152."""
    diagnostics = {"noise_stated": {"sigma_cross_arcsec": 48.0}, "noise_judged": {"sigma_cross_arcsec": "st_white_cross_arcsec"},
                   "noise_posterior": {"sigma_cross_arcsec": 1152.0, "st_white_cross_arcsec": 39.36},
                   "noise_posterior_ci95": {"sigma_cross_arcsec": [1070.0, 1225.0], "st_white_cross_arcsec": [37.9, 41.0]}}
    table = noise_table(diagnostics).set_index("scale")
    assert np.isnan(table.loc["sigma_cross_arcsec", "stated"])
    assert table.loc["st_white_cross_arcsec", "mean / stated"] == pytest.approx(0.82)
