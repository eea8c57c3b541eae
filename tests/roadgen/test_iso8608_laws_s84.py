"""ISO 8608's PSD model and classes at their edges (session 84, mutation testing): a waviness in
(0, 1] is allowed, the spectrum follows Gd(n0) (n / n0)^-w, and the classes' lower bounds are
inclusive."""

from __future__ import annotations

import numpy as np
import pytest

from roadgen.errors import RoadgenError
from roadgen.iso8608 import CLASS_LOWER_BOUNDS, GD_SCALE, MAX_WAVINESS, N0, gd_spectrum, road_class


@pytest.mark.parametrize("w", [0.25, 0.5, 1.0, 2.0, MAX_WAVINESS])
def test_any_waviness_in_its_range_gives_the_power_law(w):
    n = np.array([0.05, N0, 0.4, 2.0])
    np.testing.assert_allclose(gd_spectrum(n, 450.0, w), 450.0 * GD_SCALE * (n / N0) ** -w,
                               rtol=1e-14)  # fmt: skip
    assert gd_spectrum(np.array([N0]), 450.0, w)[0] == pytest.approx(450.0 * GD_SCALE)


@pytest.mark.parametrize("w", [0.0, -1.0, np.nextafter(MAX_WAVINESS, 10.0)])
def test_a_waviness_outside_its_range_is_refused_naming_the_range(w):
    with pytest.raises(RoadgenError, match=r"\(0, 5\]"):
        gd_spectrum(np.array([N0]), 450.0, w)


def test_each_class_starts_at_its_lower_bound_inclusive():
    names = [c for c, _ in CLASS_LOWER_BOUNDS]
    assert names == list("ABCDEFGH")
    for (c, low), (_, high) in zip(CLASS_LOWER_BOUNDS[1:], CLASS_LOWER_BOUNDS[2:], strict=False):
        assert high == 4 * low
        assert road_class(low) == c
        assert road_class(np.nextafter(low, 0.0)) == names[names.index(c) - 1]
    assert road_class(1e-3) == "A" and road_class(1e9) == "H"
