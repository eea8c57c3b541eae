"""roadgen under a caller's ``np.seterr(all="raise")``: the checks that read an IEEE underflow
or overflow still name the problem (a RoadgenError, not numpy's FloatingPointError), a normal
estimate is the same number, and the caller's error state is left as it was (session 86)."""

import numpy as np
import pytest

import roadgen


@pytest.fixture
def fp_raise():
    """numpy's global error state set to raise on everything, as a cautious caller sets it."""
    old = np.seterr(all="raise")
    try:
        yield
        left = np.geterr()
    finally:
        np.seterr(**old)  # restored even where the test failed
    assert left == dict.fromkeys(("divide", "over", "under", "invalid"), "raise")


@pytest.mark.parametrize("method", ["fit", "welch", "periodogram"])
def test_heights_whose_psd_underflows_are_named_under_raise(fp_raise, method):
    p = roadgen.iso8608_profile(60.0, 450.0, seed=0)
    tiny = roadgen.Road(x=p.x, z=p.z * 1e-170, dx_m=p.dx_m)
    with pytest.raises(roadgen.RoadgenError, match="PSD underflows float64"):
        roadgen.estimate_gd(tiny, method=method)


def test_an_overflowing_gd_spectrum_is_named_under_raise(fp_raise):
    with pytest.raises(roadgen.RoadgenError, match=r"Gd\(n\) overflows.*above about 1.58e-157"):
        roadgen.gd_spectrum([1.0, 1e-200], 450.0)


def test_an_estimate_is_the_same_under_raise():
    p = roadgen.iso8608_profile(60.0, 450.0, seed=0)
    default = [roadgen.estimate_gd(p, method=m) for m in ("fit", "welch", "periodogram")]
    with np.errstate(all="raise"):
        raised = [roadgen.estimate_gd(p, method=m) for m in ("fit", "welch", "periodogram")]
    assert raised == default
