"""A Calibrator's update that raises (refused: bad x_obs, y_obs, prior, seed or extrapolate;
part way: a KeyboardInterrupt) is not counted (session 82's sweep): the updates after it give
the posteriors, default seeds included, of a twin that never saw it, bit for bit."""

import warnings

import numpy as np
import pytest

import gpmsa
import gpmsa.calibration.calibrator as calibrator
from tests.gpmsa._calib_cases import road_emulator, road_obs

REFUSED = {
    "x NaN": {"x_obs": [[np.nan]]},
    "x shape": {"x_obs": [[1.0, 2.0]]},
    "y shape": {"y_obs": [[1.0], [2.0], [3.0]]},
    "prior shape": {"prior": np.zeros(3)},
    "prior NaN": {"prior": lambda theta: np.full(theta.shape[0], np.nan)},
    "prior zero": {"prior": lambda theta: np.full(theta.shape[0], -np.inf)},
    "seed": {"seed": -1},
    "extrapolate": {"extrapolate": "yes"},
}


def _window(i: int) -> dict:
    (x,), (y,) = road_obs()
    return {"x_obs": [[x[0] * (1 + 0.01 * i)]], "y_obs": [[y[0] * (1 + 0.02 * i)]]}


def _stop(*args):
    raise _Stop


def _numbers(post: gpmsa.Posterior) -> tuple:
    return post.mean("GD"), post.sd("GD"), post.samples["GD"][:20].tolist()


class _Stop(KeyboardInterrupt):
    pass


@pytest.mark.parametrize("bad", [*REFUSED, "interrupt"])
def test_an_update_that_raises_leaves_the_calibrator_as_it_was(monkeypatch, bad):
    cal, twin = gpmsa.Calibrator(road_emulator(), seed=3), gpmsa.Calibrator(road_emulator(), seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the window's fit: not this test's)
        assert _numbers(cal.update(**_window(0))) == _numbers(twin.update(**_window(0)))
        if bad == "interrupt":  # after the likelihood, before the posterior is made
            with monkeypatch.context() as patch:
                patch.setattr(calibrator.Calibrator, "_posterior", _stop)
                with pytest.raises(_Stop):
                    cal.update(**_window(1))
        else:
            with pytest.raises(gpmsa.GPMSAError):
                cal.update(**{**_window(1), **REFUSED[bad]})
        for i in (1, 2):
            assert _numbers(cal.update(**_window(i))) == _numbers(twin.update(**_window(i)))
