"""Session 70 walkthrough of the post-fit figures: their labels name what they show.

prediction_bands labelled a scalar output's known input "x[0]" and titled a functional output's
panels "x = (0.3)", whatever the input's name and unit (docs/prediction.md: axes of inputs read
"name (unit)"); sensitivity_bars titled the point estimate's bars "90 % over 1 draws".
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import gpmsa  # noqa: E402


def _joint(l_sim: int):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    grid = np.linspace(0.0, 1.0, l_sim)
    y = x + t * grid if l_sim > 1 else x + t
    data = gpmsa.SimData(x=x, t=t, y=y, index=grid if l_sim > 1 else None,
                         x_names=["v"], t_names=["GD"], x_units=["m/s"])  # fmt: skip
    x_obs = np.array([[0.2], [0.5], [0.8]])
    obs = gpmsa.ObsData(x=x_obs, y=x_obs + 0.4 * (grid if l_sim > 1 else 1.0),
                        index=grid if l_sim > 1 else None)  # fmt: skip
    emu = gpmsa.fit(data, obs, n_iter=20, tune=False, seed=0, discrepancy="constant")
    return emu, obs


@pytest.mark.parametrize("l_sim", [1, 4])
def test_prediction_bands_name_the_known_input(l_sim):
    emu, obs = _joint(l_sim)
    pred = gpmsa.full_prediction(emu, obs, [[0.3], [0.6]], n_draws=4, n_rlz=5, seed=1)
    assert pred.x_names == ("v",) and pred.x_units == ("m/s",)
    fig = gpmsa.plots.prediction_bands(pred)
    if l_sim == 1:
        assert fig.axes[-1].get_xlabel() == "v (m/s)"
    else:
        assert [ax.get_title() for ax in fig.axes[:2]] == ["v = 0.3 m/s", "v = 0.6 m/s"]


def test_sensitivity_bars_title_the_point_estimate():
    emu, _ = _joint(1)
    title = gpmsa.plots.sensitivity_bars(gpmsa.sensitivity(emu, draws=False)).axes[0].get_title()
    assert "point estimate" in title and "draws" not in title
    title = gpmsa.plots.sensitivity_bars(gpmsa.sensitivity(emu, n_draws=3)).axes[0].get_title()
    assert "90 % over 3 draws" in title
