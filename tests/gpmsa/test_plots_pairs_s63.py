"""``gpmsa.plots.weight_pairs``: the runs' weights in pairs of components with the
experiments' projections (SEPIA's ``plot_u_w_pairs``)."""

import functools
import warnings

import numpy as np
import pytest

import gpmsa

GRID = np.linspace(0.0, 1.0, 20)


@functools.cache
def _emulator():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.outer(x, GRID) + np.outer(t, GRID**2), index=GRID)
    return gpmsa.Emulator.from_params(sim, {"betaU": np.ones((2, 2)), "lamUz": [1, 1],
                                            "lamWs": [1e3, 1e3], "lamWOs": [1e3]})  # fmt: skip


def test_experiments_outside_the_runs_hull_are_counted_per_pair():
    emu = _emulator()
    inside = 0.5 * GRID + 0.5 * GRID**2
    far = 0.5 * GRID + 3.0 * GRID**2  # t = 3: beyond every run
    obs = gpmsa.ObsData(x=[[0.5], [0.5]], y=[inside, far])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fig = gpmsa.plots.weight_pairs(emu, obs)
    diag0, corner, below, diag1 = fig.axes
    assert not corner.axison and below.get_title() == "1 of 2 outside the runs"
    u = gpmsa.calibration.observations.reduce(emu, obs, None, extrapolate=True).obs.u
    marks = below.get_lines()[1:]
    assert [(m.get_xdata()[0], m.get_ydata()[0]) for m in marks] == [tuple(r) for r in u]
    assert [t.get_text() for t in corner.get_legend().get_texts()] == [
        "runs", "experiment 0", "experiment 1"]  # fmt: skip


def test_without_observations_and_with_one_component():
    fig = gpmsa.plots.weight_pairs(_emulator())
    assert len(fig.axes) == 4 and fig.axes[2].get_title() == ""
    assert len(gpmsa.plots.weight_pairs(_emulator(), max_pc=1).axes) == 1


def test_bad_inputs_are_named():
    with pytest.raises(gpmsa.GPMSAError, match="obs must be a gpmsa.ObsData or None"):
        gpmsa.plots.weight_pairs(_emulator(), obs=np.ones((2, 20)))
    with pytest.raises(gpmsa.GPMSAError, match="max_pc"):
        gpmsa.plots.weight_pairs(_emulator(), max_pc=0)
