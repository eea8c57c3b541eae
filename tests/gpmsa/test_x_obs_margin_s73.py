"""Session 73: calibration's x_obs follows a joint fit's rule. Outside the emulator's x domain
by up to ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width: an ExtrapolationWarning, as
``gpmsa.fit``/``gpmsa.prepare`` and the predictions give (calibrate refused it before); further:
a GPMSAError naming the column, or with ``extrapolate=True`` a warning at any distance, now for
a functional output and a discrepancy too (their reduction refused beyond 10 % before)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.model.transforms import EXTRAPOLATION_MARGIN

S = np.linspace(0, 1, 3)


def _case(l_sim: int):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, (30, 1)), rng.uniform(0, 1, (30, 1))
    s = S if l_sim > 1 else np.zeros(1)
    y = np.sin(3 * x) * (1 + s) + t * s
    data = gpmsa.SimData(x=x, t=t, y=y, index=s if l_sim > 1 else None, x_names=["v"],
                         t_names=["a"])  # fmt: skip
    p_u = 2 if l_sim > 1 else 1
    emu = gpmsa.Emulator.from_params(data, {"betaU": np.ones((2, p_u)), "lamUz": [1] * p_u,
                                            "lamWs": [1e4] * p_u, "lamWOs": [1e4]},
                                     n_pc=p_u)  # fmt: skip
    return data, emu


def _beyond(emu, frac):
    lo, hi = emu.domain["v"]
    x = hi + frac * (hi - lo)
    return np.array([[x]]), np.sin(3 * np.array([[hi]])) * (1 + S[: emu.l_sim]) + 0.5 * S[
        : emu.l_sim
    ]


def _quiet_but_extrapolation(call):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = call()
    # the short chains of calibrate are judged too (one chain, since session 76)
    kinds = {w.category for w in caught} - {gpmsa.OutsideEmulatorWarning, gpmsa.ConvergenceWarning}
    assert kinds == {gpmsa.ExtrapolationWarning}, [str(w.message) for w in caught]
    return out


@pytest.mark.parametrize("l_sim", [1, 3])
def test_just_outside_warns_as_a_joint_fit_and_far_is_refused_naming_the_column(l_sim):
    data, emu = _case(l_sim)
    x, y = _beyond(emu, 0.5 * EXTRAPOLATION_MARGIN)
    runs = {
        "calibrate": lambda x, y: gpmsa.calibrate(emu, x, y, n_samples=40, n_burn=10, seed=0),
        "Calibrator": lambda x, y: gpmsa.Calibrator(emu, method="grid", n_grid=33).update(x, y),
        "fit": lambda x, y: gpmsa.prepare(data, gpmsa.ObsData(x=x, y=y)),
    }
    for run in runs.values():
        _quiet_but_extrapolation(lambda run=run: run(x, y))
    x_far, y_far = _beyond(emu, 2 * EXTRAPOLATION_MARGIN)
    for name in ("calibrate", "Calibrator"):
        with pytest.raises(
            gpmsa.GPMSAError,
            match=r"x_obs v=1.1\d+ lies outside the emulator's "
            r"domain \[.*\] by more than 10% of its width; pass extrapolate=True",
        ):
            runs[name](x_far, y_far)
    far = r"x_obs v=1.1\d+ lies outside the simulation design's range \[.*\] by more than 10%"
    with pytest.raises(gpmsa.GPMSAError, match=far):
        runs["fit"](x_far, y_far)


@pytest.mark.parametrize("discrepancy", [None, "constant"])
def test_extrapolate_allows_any_distance_for_a_functional_output(discrepancy):
    _, emu = _case(3)
    x, y = _beyond(emu, 3 * EXTRAPOLATION_MARGIN)
    post = _quiet_but_extrapolation(
        lambda: gpmsa.calibrate(
            emu, x, y, n_samples=40, n_burn=10, seed=0, extrapolate=True, discrepancy=discrepancy
        )
    )
    assert np.isfinite(post.mean("a"))


def test_inside_the_domain_is_silent():
    _, emu = _case(1)
    lo, hi = emu.domain["v"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ExtrapolationWarning)
        post = gpmsa.calibrate(emu, [[hi]], [[0.1]], n_samples=40, n_burn=10, seed=0)
    assert np.isfinite(post.mean("a"))
