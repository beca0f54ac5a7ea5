"""The outlier screen's numerics (`gyrocal.checks.outliers`) against dense references."""

import numpy as np
import pytest
from scipy.ndimage import median_filter

from gyrocal.checks.outliers import running_median


@pytest.mark.parametrize("n, window", [(1, 3), (56, 57), (200, 3), (1000, 101), (3000, 2001)])
def test_running_median_is_scipys_nearest_median_filter_to_the_bit(n, window):
    x = np.random.default_rng(n).standard_normal((n, 3))
    assert np.array_equal(running_median(x, window), median_filter(x, size=(window, 1), mode="nearest"))


def test_running_median_follows_a_trend_and_drops_a_spike():
    line = 0.5 * np.arange(101.0)[:, None]
    assert np.array_equal(running_median(line, 5)[2:-2], line[2:-2])
    flat = np.full((101, 1), 7.0)
    flat[50] = 1000.0
    assert np.array_equal(running_median(flat, 5), np.full((101, 1), 7.0))
