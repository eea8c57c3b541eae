"""Numerically awkward data (session 75 audit): inputs at a large offset, x in [1e6, 1e6 + 1].

Everything computed was sound (scale- and offset-invariant posteriors, predictions, sensitivity
indices, files); the refusals and warnings were not readable: values and ranges were printed
with 6 significant digits, so "x0=1e+06 lies outside the emulator's domain [1e+06, 1e+06]".
"""

import re
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import DomainWarning, ExtrapolationWarning, GPMSAError
from gpmsa.errors import numbers_text

OFF = 1e6


@cache
def _offset_emulator():
    rng = np.random.default_rng(0)
    x, t = OFF + rng.random((20, 1)), OFF + rng.random((20, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * (x - OFF)) + 2 * (t - OFF))
    return sim, gpmsa.fit(sim, n_iter=50, seed=0)


def _numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?(?:e[+-]?\d+)?", text)]


def _apart(text: str, value: float) -> None:
    """The message shows ``value`` and a range whose ends differ from it and each other."""
    nums = [v for v in _numbers(text) if abs(v - OFF) < 10]
    assert any(abs(v - value) < 1e-3 for v in nums), text
    assert len(set(nums)) >= 3, text


def test_numbers_text_keeps_close_values_apart_and_ordinary_ones_as_before():
    assert numbers_text(OFF + 1.5, OFF + 0.0165276, OFF + 0.9918) == (
        "1000001.5", "1000000.017", "1000000.992",
    )  # fmt: skip
    assert numbers_text(0.8, 0.0165276, 0.636962) == ("0.8", "0.0165276", "0.636962")
    assert numbers_text(2.5e-9, 1e-9, 2e-9) == ("2.5e-09", "1e-09", "2e-09")
    assert numbers_text(np.nan, 1.0, np.inf) == ("nan", "1", "inf")


@pytest.mark.parametrize(
    "call",
    [
        lambda emu: gpmsa.calibrate(emu, [[OFF + 1.5]], [[1.0]], n_samples=20, n_burn=5),
        lambda emu: gpmsa.Calibrator(emu).update([[OFF + 1.5]], [[1.0]]),
        lambda emu: emu.predict([[OFF + 1.5]], [[OFF + 0.5]]),
    ],
    ids=["calibrate", "update", "predict"],
)
def test_x_outside_an_offset_domain_is_named_with_readable_numbers(call):
    _, emu = _offset_emulator()
    with pytest.raises(GPMSAError, match="outside the emulator's domain") as info:
        call(emu)
    _apart(str(info.value), OFF + 1.5)


def test_x_just_outside_an_offset_domain_warns_with_readable_numbers():
    _, emu = _offset_emulator()
    hi = emu.domain["x0"][1]
    with pytest.warns(ExtrapolationWarning) as rec:
        emu.predict([[hi + 0.01]], [[OFF + 0.5]])
    _apart(str(rec[0].message), hi + 0.01)


def test_theta_init_outside_an_offset_range_is_named_with_readable_numbers():
    _, emu = _offset_emulator()
    with pytest.raises(GPMSAError, match="open range") as info:
        gpmsa.calibrate(emu, [[OFF + 0.5]], [[1.0]], n_samples=20, n_burn=5,
                        theta_init=[OFF + 1.2])  # fmt: skip
    _apart(str(info.value), OFF + 1.2)


def test_joint_fit_and_ranges_at_an_offset_are_named_with_readable_numbers():
    sim, _ = _offset_emulator()
    with pytest.raises(GPMSAError, match="simulation design's range") as info:
        gpmsa.fit(sim, gpmsa.ObsData(x=[[OFF + 1.5]], y=[[1.0]]), n_iter=5)
    _apart(str(info.value), OFF + 1.5)
    with pytest.raises(GPMSAError, match="must hold every run") as info:
        gpmsa.SimData(x=sim.x, t=sim.t, y=sim.y, x_range=[[OFF + 0.1, OFF + 1.0]])
    _apart(str(info.value), OFF + 0.1)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        gpmsa.SimData(x=sim.x, t=sim.t, y=sim.y, x_range=[[OFF - 20, OFF + 20]])
    (msg,) = [str(w.message) for w in rec if issubclass(w.category, DomainWarning)]
    assert "[999980, 1000020]" in msg and "[1000000.00" in msg, msg
