"""What gpmsa prints for a person, fed odd but valid values: two distinct numbers never read
alike (a span [1e6 + 0.02, 1e6 + 0.99] printed "[1e+06, 1e+06]"), many or long names keep a
repr short and say how many it leaves out (an Emulator of 20 parameters printed 700
characters; a Posterior named 3 of 20 and hid the rest), and ``gpmsa calibrate`` echoes the
observation it was given and the posterior's figures as distinct as they are, with units."""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.cli.main import main

NEAR = 1e6 + 0.02 + 0.97 * np.linspace(0.0, 1.0, 12)[:, None]  # 1000000.02 .. 1000000.99


def _sim(x=NEAR, t_names=None, **kw) -> gpmsa.SimData:
    order = np.random.default_rng(3).permutation(x.shape[0])  # t not a linear function of x
    t = np.linspace(0.1, 0.9, x.shape[0])[order, None] * np.ones((1, len(t_names or "t")))
    return gpmsa.SimData(x=x, t=t, y=x - x.mean() + t[:, :1], t_names=t_names, **kw)


def test_the_data_reprs_print_distinct_ends_distinctly():
    text = repr(_sim())
    assert "[1e+06, 1e+06]" not in text, text
    assert "x0 [1000000.02, 1000000.99]" in text, text
    obs = gpmsa.ObsData(x=[[1e6 + 0.25], [1e6 + 0.75]], y=[[1.0], [2.0]])
    assert "x_obs[:, 0] [1000000.25, 1000000.75]" in repr(obs), repr(obs)


def test_the_data_repr_keeps_its_four_digits_and_prints_no_negative_zero():
    x = np.linspace(0.0, 0.9351, 12)[:, None]
    x[0] = -0.0
    text = repr(_sim(x=x))
    assert "x0 [0, 0.9351]" in text, text  # as before: 4 significant digits; not "-0"


def test_a_grid_marginal_on_a_narrow_span_names_its_ends_distinctly():
    nodes = np.linspace(1e6, 1e6 + 1.0, 65)
    gm = GridMarginal.from_log_density(nodes, -0.5 * ((nodes - nodes.mean()) / 0.2) ** 2)
    assert "65 nodes on [1000000, 1000001]" in repr(gm), repr(gm)


@cache
def _many() -> gpmsa.Emulator:
    """An emulator of 20 calibration parameters with long names (a short, untuned fit)."""
    rng = np.random.default_rng(0)
    names = [f"parameter_with_a_rather_long_name_number_{k}" for k in range(20)]
    t = rng.uniform(size=(40, 20))
    data = gpmsa.SimData(x=np.empty((40, 0)), t=t, y=t.sum(axis=1, keepdims=True), t_names=names)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: unconverged
        return gpmsa.fit(data, n_iter=10, tune=False, seed=1)


def test_the_emulator_repr_stays_short_with_many_long_names():
    text = repr(_many())
    assert len(text) < 400 and "\n" not in text, text
    assert "+14 more" in text and "parameter_with_a_rather_long_name_num..." in text, text
    assert "y=1 output," in text, text  # not "1 outputs"
    assert "m=40" in text and "draws=8" in text, text


def test_the_emulator_repr_with_few_names_is_as_before():
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t * np.linspace(0.0, 1.0, 3), x_names=["v"],
                         t_names=["GD"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, n_iter=10, tune=False, seed=1, n_pc=2)
    assert repr(emu) == "Emulator(m=10, x=['v'], t=['GD'], y=3 outputs, p_u=2, draws=8)"


def test_the_posterior_repr_counts_the_parameters_it_leaves_out():
    post = gpmsa.Posterior({f"{'p' * 60}{k}": np.arange(5.0) + k for k in range(20)})
    text = repr(post)
    assert "+17 more" in text and len(text) < 300, text
    assert f"{'p' * 37}...=2±1.58" in text, text
    assert repr(gpmsa.Posterior({"a": [1.0]})) == "Posterior(a=1, method=?)"  # as before


@cache
def _near_file(folder) -> str:
    """An emulator of x in [1e6 + 0.02, 1e6 + 0.99] (unit "m/s") and t in (0.1, 0.9) ("kg"),
    saved."""
    data = _sim(x_names=["v"], t_names=["E"], x_units=["m/s"], t_units=["kg"], y_names=["f"],
                y_units=["N"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, n_iter=20, tune=False, seed=1)
    return str(emu.save(folder / "near.gpmsa"))


@pytest.fixture(scope="module")
def near_file(tmp_path_factory):
    return _near_file(tmp_path_factory.mktemp("near"))


def test_calibrate_echoes_the_observation_as_given(near_file, capsys):
    assert main(["calibrate", near_file, "--x", "v=1000000.5", "--y", "f=0.3"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert head.endswith(" given v=1000000.5; f=0.3"), head  # not "v=1e+06"


def test_calibrate_prints_a_row_of_distinct_figures_distinctly_with_its_unit(tmp_path, capsys):
    """A posterior of theta near 1e6: its mean, quantiles and median no longer all read
    "1e+06"; each row ends with the parameter's unit."""
    rng = np.random.default_rng(2)
    t = 1e6 + rng.uniform(size=(15, 1))
    data = gpmsa.SimData(x=np.empty((15, 0)), t=t, y=t - 1e6, t_names=["E"], t_units=["kg"],
                         y_names=["f"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, n_iter=20, tune=False, seed=1)
    post = gpmsa.Calibrator(emu).update(np.empty((1, 0)), [[0.5]])
    summary = post.summary(0.9)["E"]
    path = str(emu.save(tmp_path / "e.gpmsa"))
    assert main(["calibrate", path, "--y", "f=0.5"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].split() == ["name", "mean", "sd", "q5", "median", "q95", "unit"], out[1]
    row = next(line for line in out if line.split()[0] == "E").split()
    figures = [row[1], row[3], row[4], row[5]]  # mean, q5, median, q95: all near 1e6
    assert len(set(figures)) == 4 and "1e+06" not in figures, row
    for text, key in zip(figures, ("mean", "q5", "median", "q95"), strict=True):
        assert float(text) == pytest.approx(summary[key], abs=5e-4), (text, key)
    assert row[-1] == "[kg]", row  # in brackets, as `gpmsa info` prints it
    lam = next(line for line in out if line.split()[0] == "lamOs").split()
    assert len(lam) == 6, lam  # a precision: no unit recorded, none printed
