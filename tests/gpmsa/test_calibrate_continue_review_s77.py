"""``gpmsa.calibrate(..., init=posterior)``: a constrained calibration started at ``theta_init``
continues (its chains start at their last draws, not at GPM/SA's initial), a last draw the
constraint refuses is named as such on either engine, a continued adapted ladder is recorded as
a fresh run records it (so a second continuation keeps each chain's ladder), and an appended
Metropolis source with a NUTS continuation keeps the continuation's acceptance rates."""

import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, two_param_emulator

import gpmsa
from gpmsa.calibration.continuation import appended_info

X2, Y2 = [[0.2], [0.5], [0.8]], [[0.6], [0.9], [1.2]]


def _calibrate(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        warnings.simplefilter("ignore", gpmsa.AtBoundWarning)
        return gpmsa.calibrate(*args, **kw)


def _below(t):
    """Allows b < 0.3 only: GPM/SA's initial (the design's centre, b = 0.5) is refused."""
    return bool(t[1] < 0.3)


@pytest.mark.parametrize("engine", [{}, {"fast": False, "tune_rounds": 3}])
def test_a_calibration_started_at_theta_init_continues(engine):
    emu = two_param_emulator()
    src = _calibrate(emu, X2, Y2, n_samples=80, n_burn=10, seed=7, constraint=_below,
                     theta_init=[0.5, 0.1], **engine)  # fmt: skip
    out = _calibrate(emu, X2, Y2, n_samples=40, seed=8, init=src, constraint=_below,
                     append=True)  # fmt: skip
    assert out.chains["b"].shape == (1, 110) and np.all(out.samples["b"] < 0.3)
    held = _calibrate(emu, X2, Y2, n_samples=80, n_burn=10, seed=7, constraint=_below,
                      theta_init=[0.5, 0.1], fixed={"theta": {"a": 0.4}}, **engine)  # fmt: skip
    more = _calibrate(emu, X2, Y2, n_samples=40, seed=8, init=held, constraint=_below,
                      fixed={"theta": {"a": 0.4}})  # fmt: skip
    assert np.all(more.samples["a"] == 0.4) and np.all(more.samples["b"] < 0.3)


@pytest.mark.parametrize("engine", [{}, {"fast": False, "tune_rounds": 3}])
def test_a_last_draw_outside_the_constraint_is_named(engine):
    emu = two_param_emulator()
    src = _calibrate(emu, X2, Y2, n_samples=60, n_burn=10, seed=7, constraint=_below,
                     theta_init=[0.5, 0.1], **engine)  # fmt: skip
    last = src.chains["b"][0, -1]

    def above(t):
        return bool(t[1] > last + 0.01)

    with pytest.raises(gpmsa.GPMSAError, match="chain 0's last draw .*b=.* outside this theta "
                       "constraint") as err:  # fmt: skip
        _calibrate(emu, X2, Y2, n_samples=20, seed=8, init=src, constraint=above)
    assert "theta_init" not in str(err.value)  # refused in a continuation: not the remedy


def test_a_continued_adapted_ladder_is_recorded_per_chain():
    emu, (x, y) = road_emulator(), road_obs()
    src = _calibrate(emu, x, y, n_samples=30, n_burn=5, seed=1, fast=False, tune_rounds=2,
                     temperatures=[1, 2, 4], adapt_ladder=True, n_chains=2, n_jobs=1)  # fmt: skip
    adapted = src.info["adapted_temperatures"]
    assert adapted[0] != adapted[1]
    more = _calibrate(emu, x, y, n_samples=20, seed=2, init=src, tune_rounds=2, n_chains=2,
                      n_jobs=1)  # fmt: skip
    assert more.info["temperatures"] == [1.0, 2.0, 4.0]  # the ladder they started from
    assert more.info["adapted_temperatures"] == adapted  # each chain's, as it ran
    again = _calibrate(emu, x, y, n_samples=20, seed=3, init=more, tune_rounds=2, n_chains=2,
                       n_jobs=1)  # fmt: skip
    assert again.info["adapted_temperatures"] == adapted  # chain 1 kept its own ladder


def test_a_nuts_part_is_not_averaged_with_a_metropolis_one():
    chains = {"GD": np.zeros((1, 40)), "lamOs": np.ones((1, 40))}
    info = {"backend": "numpy", "n_samples": 50, "n_burn": 10,
            "accept_rate": {"theta": [[0.3]], "lamOs": [[0.4]]}}  # fmt: skip
    source = gpmsa.Posterior({k: v.ravel() for k, v in chains.items()}, chains=chains, info=info)
    nuts = {"theta": [[0.9]], "lamOs": [[0.9]]}
    out = appended_info(source, 50, nuts, "pyro")
    assert out["accept_rate"] == nuts  # NUTS's acceptance is another figure: its own
    assert (out["pooled_sweeps"], out["sweeps_run"]) == (90, 100)
    both = appended_info(source, 50, {"theta": [[0.5]], "lamOs": [[0.6]]}, "torch")
    np.testing.assert_allclose(both["accept_rate"]["theta"], [[0.4]])  # (0.3 * 50 + 0.5 * 50) / 100
