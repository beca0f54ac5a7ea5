"""Degenerate noise: perfect gyros, a perfect reference, or both, run or are refused naming the cause."""

import numpy as np
import pytest
import yaml

from gyrocal import checks
from gyrocal.inference.sampling.refusals import EstimateError, check_noise
from gyrocal.model.kinematics import increment_quantum_rad
from gyrocal.model.units import ARCSEC_RAD
from gyrocal.simulation import simulate
from gyrocal.simulation.simulate import STATED_ARW_FLOOR_DEG_SQRT_H
from gyrocal.study.baseline import baseline_ranking

from conftest import DATA, ROOT


def simulated(tmp_path, arw_deg_sqrt_h, sigma_arcsec, pulse_arcsec=0.05):
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario["gyro"].update(arw_deg_sqrt_h=arw_deg_sqrt_h, pulse_arcsec=pulse_arcsec)
    scenario["star_tracker"].update(sigma_cross_arcsec=sigma_arcsec, sigma_about_arcsec=sigma_arcsec)
    (tmp_path / "scenario.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(tmp_path / "scenario.yaml", tmp_path)
    return tmp_path / "campaign"


def fitted(directory):
    campaign, findings = checks.read_checked(directory)
    assert not findings.errors, [f.why for f in findings.errors]
    noise_defaults = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["noise"]
    maneuvers, est, _, _ = baseline_ranking(campaign, noise_defaults)
    return maneuvers, est


def test_increment_quantum_is_the_pulse_of_counted_increments_and_zero_at_full_precision():
    rng = np.random.default_rng(0)
    pulses = rng.integers(-40, 40, size=(1000, 3)) * 0.05 * ARCSEC_RAD
    assert increment_quantum_rad(pulses) == pytest.approx(0.05 * ARCSEC_RAD, rel=1e-9)
    assert increment_quantum_rad(rng.normal(size=(1000, 3))) == 0.0


def test_perfect_gyros_are_stated_at_the_floor_validate_and_fit(tmp_path):
    directory = simulated(tmp_path, 0.0, 5.0, pulse_arcsec=0.0)
    assert yaml.safe_load((directory / "campaign.yaml").read_text())["gyro"]["arw_deg_sqrt_h"] == STATED_ARW_FLOOR_DEG_SQRT_H
    maneuvers, est = fitted(directory)
    check_noise(maneuvers, est)
    assert np.exp(est.log_sigma[0]) / ARCSEC_RAD == pytest.approx(5.0, rel=0.1)


def test_a_reference_below_the_gyros_resolution_is_refused_naming_the_resolution(tmp_path):
    maneuvers, est = fitted(simulated(tmp_path, 0.003, 1e-6))
    with pytest.raises(EstimateError, match=r"below the gyros' own resolution: .* steps of 0\.05 arcsec.* adds 0\.0144"):
        check_noise(maneuvers, est)


def test_noise_free_data_are_refused_as_quieter_than_stated(tmp_path):
    maneuvers, est = fitted(simulated(tmp_path, 0.0, 1e-6, pulse_arcsec=0.0))
    with pytest.raises(EstimateError, match=r"far quieter than campaign\.yaml states"):
        check_noise(maneuvers, est)
