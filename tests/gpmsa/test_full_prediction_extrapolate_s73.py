"""Session 73: ``full_prediction`` takes calibrate's ``extrapolate=`` rule. A
``gpmsa.calibrate(..., extrapolate=True)`` with x_obs beyond ``EXTRAPOLATION_MARGIN`` (10 %) of
the design could not be predicted from: ``full_prediction``'s reduction of ``obs`` refused its x
("x_obs column v reaches 1.3..1.3 on the unit scale of the design"), and a prediction at that x
was refused too, with no option to allow either. Now both are refused by the column's name and
value, pointing at ``extrapolate=True``, which allows them (``x`` with an ExtrapolationWarning);
within the margin nothing changes."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.model.transforms import EXTRAPOLATION_MARGIN

S = np.linspace(0, 1, 3)


def _case(l_sim: int):
    """An emulator on x, t in [0, 1] (scalar or 3 outputs) and a calibration at an x_obs 30 %
    of the width beyond the design (extrapolate=True)."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, (30, 1)), rng.uniform(0, 1, (30, 1))
    s = S if l_sim > 1 else np.zeros(1)
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) * (1 + s) + t * s, x_names=["v"],
                         t_names=["a"], index=s if l_sim > 1 else None)  # fmt: skip
    p_u = 2 if l_sim > 1 else 1
    emu = gpmsa.Emulator.from_params(data, {"betaU": np.ones((2, p_u)), "lamUz": [1] * p_u,
                                            "lamWs": [1e4] * p_u, "lamWOs": [1e4]},
                                     n_pc=p_u)  # fmt: skip
    lo, hi = emu.domain["v"]
    xo = np.array([[hi + 3 * EXTRAPOLATION_MARGIN * (hi - lo)]])
    yo = np.sin(3 * np.array([[hi]])) * (1 + S[:l_sim]) + 0.5 * S[:l_sim]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emu, xo, yo, n_samples=40, n_burn=10, seed=0, extrapolate=True)
    return emu, gpmsa.ObsData(x=xo, y=yo), post


@pytest.mark.parametrize("l_sim", [1, 3])
def test_a_calibration_allowed_to_extrapolate_predicts_with_extrapolate_true(l_sim):
    emu, obs, post = _case(l_sim)
    xo = float(obs.x[0, 0])
    msg = (rf"^obs v={xo:.6g} lies outside the emulator's domain .* by more than 10% of its "
           r"width; pass extrapolate=True")  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match=msg):  # before: no extrapolate= to pass
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, seed=1)
    with warnings.catch_warnings():  # x inside the domain, obs warned of by calibrate: silent
        warnings.simplefilter("error")
        inside = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, seed=1,
                                       extrapolate=True)  # fmt: skip
    assert inside.y.shape == (post.samples["a"].size, 1, l_sim)
    assert np.all(np.isfinite(inside.y))
    with pytest.raises(gpmsa.GPMSAError, match=r"x: v reaches .* by more than 10% of its width; "
                                               r"pass extrapolate=True"):  # fmt: skip
        gpmsa.full_prediction(emu, obs, obs.x, posterior=post, seed=1)
    with pytest.warns(gpmsa.ExtrapolationWarning, match=r"x: v reaches .*, outside the emulator's"):
        at_obs = gpmsa.full_prediction(emu, obs, obs.x, posterior=post, seed=1, extrapolate=True)
    assert np.all(np.isfinite(at_obs.y))


def test_extrapolate_is_a_flag_and_emulator_prediction_points_at_it():
    emu, obs, post = _case(1)
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate"):
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, extrapolate="yes")
    with pytest.raises(gpmsa.GPMSAError, match=r"of its width; pass extrapolate=True to allow it$"):
        gpmsa.predictive.emulator_prediction(emu, [[1.5]], [[0.5]])  # its own since the walkthrough
