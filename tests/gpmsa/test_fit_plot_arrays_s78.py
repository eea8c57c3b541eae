"""``plots.emulator_fit(emu, (x, t, y))``: held-out runs as arrays, any number of them (a
SimData needs p + q + 2 runs), read as ``Emulator.predict`` reads x and t (tables by name); the
same figure as the SimData of the same runs; a bad tuple named."""

from __future__ import annotations

import matplotlib
import numpy as np
import pandas as pd
import pytest

import gpmsa

matplotlib.use("Agg")
S = np.linspace(0.0, 1.0, 5)


def _runs(rng, n):
    x, t = rng.uniform(0.1, 0.9, size=(n, 1)), rng.uniform(0.1, 0.9, size=(n, 2))
    return x, t, np.sin(3 * x) + t[:, :1] * S + t[:, 1:]


def _emu():
    x, t, y = _runs(np.random.default_rng(0), 30)
    data = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[2, 2], [1, 1], [1, 1]], "lamUz": [1, 1], "lamWs": [1e4] * 2,
              "lamWOs": [1e4]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=2)


def _title(fig) -> str:
    return fig.axes[0].get_title()


def test_held_out_arrays_give_the_simdata_figure_and_take_one_run():
    emu, (x, t, y) = _emu(), _runs(np.random.default_rng(1), 6)
    sim = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["a", "b"])
    assert _title(gpmsa.plots.emulator_fit(emu, (x, t, y))) == _title(
        gpmsa.plots.emulator_fit(emu, sim)
    )
    frames = (pd.DataFrame(x, columns=["x"]), pd.DataFrame(t[:, ::-1], columns=["b", "a"]), y)
    assert _title(gpmsa.plots.emulator_fit(emu, frames)) == _title(
        gpmsa.plots.emulator_fit(emu, sim)
    )
    one = gpmsa.plots.emulator_fit(emu, (x[0], t[0], y[0]))  # one run (a SimData needs 5)
    assert _title(one).startswith("1 held-out run: ")


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda x, t, y: (x, t), r"held_out as a tuple must be \(x, t, y\), got 2 items"),
        (lambda x, t, y: (x, t, y[:2]), "one row per run: y has 2 rows, t 3, x 3"),
        (lambda x, t, y: (x[:2], t, y), "one row per run: y has 3 rows, t 3, x 2"),
        (lambda x, t, y: (x, t, y[:, :3]), "held_out y must have 5 columns"),
        (lambda x, t, y: (x, t, np.where(y > 0.5, np.nan, y)), "held_out y must be finite"),
        (lambda x, t, y: (x, t[:, :1], y), "held_out t"),
    ],
)
def test_a_bad_tuple_is_named(edit, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.plots.emulator_fit(_emu(), edit(*_runs(np.random.default_rng(2), 3)))
