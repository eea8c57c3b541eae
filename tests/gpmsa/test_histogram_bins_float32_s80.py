"""diagnostics.histogram_bins for float32 draws: numpy spaces its equal bins in the draws' own
float type, so float32 draws a few of their ulps apart were refused ("Too many bins for data
range") where the float64 check found the bins apart and kept the count."""

import numpy as np
import pytest

from gpmsa.mcmc.diagnostics import histogram_bins


@pytest.mark.parametrize("value", [1.0, 400.0, 1e12])
def test_float32_draws_a_few_ulps_apart_get_edges_numpy_takes(value):
    v = np.float32(value)
    draws = (v + np.spacing(v) * (np.arange(200) % 4)).astype(np.float32)
    edges = histogram_bins(draws, 40)  # before: 40, and numpy refused it
    counts, _ = np.histogram(draws, bins=edges)
    assert counts.sum() == draws.size
    assert edges[0] == draws.min() and edges[-1] == draws.max()


def test_ordinary_draws_keep_the_count_in_either_type():
    rng = np.random.default_rng(0)
    draws = rng.normal(size=300)
    assert histogram_bins(draws, 40) == 40
    assert histogram_bins(draws.astype(np.float32), 40) == 40
    assert histogram_bins(np.arange(10), 40) == 40  # integers: numpy's float64 edges
