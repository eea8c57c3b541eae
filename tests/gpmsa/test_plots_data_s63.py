"""``gpmsa.plots.data``: the runs and observations before fitting (SEPIA's ``plot_data``)."""

import numpy as np
import pytest

import gpmsa

GRID = np.linspace(0.0, 1.0, 12)


def _functional():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(15, 1)), rng.uniform(size=(15, 2))
    y = np.sin(2 * np.pi * GRID * (1 + t[:, :1])) + x * GRID
    return gpmsa.SimData(x=x, t=t, y=y, index=GRID, t_names=["E", "c"], t_units=["GPa", ""])


def _scalar(p: int = 1):
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(15, p)), rng.uniform(size=(15, 1))
    return gpmsa.SimData(x=x if p else None, t=t, y=t + (x.sum(axis=1, keepdims=True) if p else 0))


def test_functional_runs_are_coloured_by_an_input_and_experiments_drawn_on_their_grids():
    sim = _functional()
    grids = [np.linspace(0, 1, 5), np.array([0.2, 0.6, 0.8])]
    obs = gpmsa.ObsData(x=[[0.3], [0.6]], y=[np.sin(g) for g in grids], index=grids)
    fig = gpmsa.plots.data(sim, obs, color_by="c")
    ax, bar = fig.axes
    lines = ax.get_lines()
    assert len(lines) == sim.m + 2
    assert [tuple(line.get_xdata()) for line in lines[-2:]] == [tuple(g) for g in grids]
    colours = {tuple(line.get_color()) for line in lines[: sim.m]}
    assert len(colours) > 10  # one colour per value of c
    assert bar.get_ylabel() == "c" and "2 experiment(s)" in ax.get_title()
    assert gpmsa.plots.data(sim).axes[1].get_ylabel() == "E (GPa)"  # the first t (s70: not [GPa])


def test_scalar_output_gives_a_panel_per_input_with_the_observations():
    sim = _scalar()
    obs = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[0.9], [1.4]])
    fig = gpmsa.plots.data(sim, obs)
    x_panel, t_panel = fig.axes
    assert [a.get_xlabel() for a in fig.axes] == ["x0", "t0"]
    marks = x_panel.get_lines()[1]
    assert list(marks.get_xdata()) == [0.2, 0.7] and list(marks.get_ydata()) == [0.9, 1.4]
    assert sorted(line.get_ydata()[0] for line in t_panel.get_lines()[1:]) == [0.9, 1.4]
    assert len(gpmsa.plots.data(_scalar(p=0)).axes) == 1


def test_bad_inputs_are_named():
    sim = _functional()
    with pytest.raises(gpmsa.GPMSAError, match="sim must be a gpmsa.SimData"):
        gpmsa.plots.data(np.ones((3, 3)))
    with pytest.raises(gpmsa.GPMSAError, match="obs must be a gpmsa.ObsData or None"):
        gpmsa.plots.data(sim, [[1.0]])
    with pytest.raises(gpmsa.GPMSAError, match=r"color_by must be one of the inputs \['x0'"):
        gpmsa.plots.data(sim, color_by="GD")
    short = gpmsa.ObsData(x=[[0.3]], y=[np.ones(5)])
    with pytest.raises(gpmsa.GPMSAError, match="5 values on the simulation grid of 12"):
        gpmsa.plots.data(sim, short)
    with pytest.raises(gpmsa.GPMSAError, match="one value per experiment"):
        gpmsa.plots.data(_scalar(), gpmsa.ObsData(x=[[0.3]], y=[[1.0, 2.0]]))
    with pytest.raises(gpmsa.GPMSAError, match="obs has 2 known inputs, the runs 1"):
        gpmsa.plots.data(_scalar(), gpmsa.ObsData(x=[[0.3, 0.1]], y=[[1.0]]))
