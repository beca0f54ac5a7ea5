"""The Allan deviation of a gyro at rest, and the angle random walk read off it."""

import numpy as np
import pytest

from gyrocal.io.importer import Imported
from gyrocal.io.telemetry import TelemetryError
from gyrocal.model.units import DEG_H_RAD_S
from gyrocal.planning import allan


def white_rate_increments(arw_deg_sqrt_h, dt_s, n, channels=2, seed=1):
    """Increments of a gyro at rest whose rate is white noise of the given angle random walk."""
    sd_rad_s = arw_deg_sqrt_h * 60.0 * DEG_H_RAD_S / np.sqrt(dt_s)
    return np.random.default_rng(seed).normal(0.0, sd_rad_s, (n, channels)) * dt_s


def test_the_angle_random_walk_of_white_rate_noise_is_recovered():
    table = allan.allan_table(white_rate_increments(2.0, 0.01, 200_000), 0.01, ["a", "b"])
    arw = allan.angle_random_walk(table)
    assert list(arw.index) == ["a", "b"]
    assert np.allclose(arw, 2.0, rtol=0.05)


def test_the_allan_deviation_is_the_dense_formula_on_a_tiny_record():
    inc = white_rate_increments(1.0, 0.5, 40, channels=1, seed=4)
    angle = np.concatenate([[0.0], np.cumsum(inc[:, 0])])
    m, dt = 2, 0.5
    second = angle[2 * m:] - 2 * angle[m:-m] + angle[:-2 * m]
    dense = np.sqrt(np.mean(second**2) / (2 * (m * dt) ** 2)) / DEG_H_RAD_S
    table = allan.allan_table(inc, dt, ["g"])
    assert table.loc[m * dt, "g adev_deg_h"] == pytest.approx(dense, rel=1e-12)


def test_uneven_intervals_are_refused_naming_the_row():
    time = np.array([0.0, 0.01, 0.02, 0.05, 0.06])
    imported = Imported("s", time, np.zeros((5, 4)), np.zeros(5, bool), np.zeros((5, 1)), {})
    with pytest.raises(TelemetryError, match=r"static\.csv: row 4 .* 0\.03 s where the file's is 0\.01 s"):
        allan.static_report(imported, ["g"], "static.csv")


@pytest.mark.parametrize("dt_s", [1.0, 0.01])
def test_a_gyro_logged_as_rates_reads_its_angle_random_walk_at_any_sample_interval(tmp_path, dt_s):
    # At 1 Hz the cluster of tau = 1 s is one sample, where the import's trapezoid would halve it.
    from gyrocal.io.importer import read_file, read_mapping
    n, arw_true = 100_000, 2.0
    rate = white_rate_increments(arw_true, dt_s, n, channels=1, seed=7)[:, 0] / dt_s
    rows = "\n".join(f"{k * dt_s:.6f},1,0,0,0,{r:.10e}" for k, r in enumerate(rate))
    (tmp_path / "static.csv").write_text("t,qw,qx,qy,qz,gyro\n" + rows + "\n")
    (tmp_path / "m.yaml").write_text(
        "format: {delimiter: ',', header_rows: 1}\ntime: {column: 1}\n"
        "reference: {columns: [2, 3, 4, 5], order: wxyz, sample_interval_s: 0}\n"
        "gyro: {quantity: rate, unit: rad/s, columns: {g: 6}, axes: {g: yaw}}\n")
    text = allan.static_report(read_file(tmp_path / "static.csv", read_mapping(tmp_path / "m.yaml")), ["g"],
                               "static.csv")
    read = float(text.split("deg/sqrt(h): g ")[1].split()[0])
    assert read == pytest.approx(arw_true, rel=0.03)
