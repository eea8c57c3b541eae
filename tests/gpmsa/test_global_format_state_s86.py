"""The user's global display state (numpy print options, matplotlib's colour cycle) changes
neither what a message says about a value nor which series a legend tells apart."""

import re

import matplotlib as mpl
import numpy as np
import pytest
from cycler import cycler
from matplotlib.colors import to_rgba, to_rgba_array

import gpmsa
from gpmsa import plots

USER_PRINT = dict(precision=2, threshold=5, edgeitems=1, floatmode="fixed", suppress=True,
                  sign="+")  # fmt: skip


def _emulator(params=None):
    rng = np.random.default_rng(0)
    x, t, s = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1)), np.linspace(0, 1, 8)
    data = gpmsa.SimData(x=x, t=t, y=np.outer(x, s) + np.outer(t, s**2), index=s)
    given = {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1], "lamWs": [1e3, 1e3], "lamWOs": [1e3]}
    return gpmsa.Emulator.from_params(data, {**given, **(params or {})}), s


def _message(call) -> str:
    with pytest.raises(gpmsa.GPMSAError) as info:
        call()
    return str(info.value)


@pytest.mark.parametrize("legacy", [False, "1.13", "1.25"])
def test_a_message_about_a_given_array_keeps_its_digits_under_the_users_print_options(legacy):
    """precision=2 / suppress=True wrote lamUz = 1.23456e-9 (below 1e-8) as [+0.00 +1.00] and
    lamWs = -0.123456 as [-0.12 +1.00]."""
    cases = [{"lamUz": [1.23456e-9, 1.0]}, {"lamWs": [-0.123456, 1.0]}, {"lamWs": [1.0, np.nan]}]
    for params in cases:
        default = _message(lambda p=params: _emulator(p))
        with np.printoptions(**USER_PRINT, legacy=legacy):
            assert _message(lambda p=params: _emulator(p)) == default
    assert "[1.23456e-09 1.00000e+00]" in _message(lambda: _emulator(cases[0]))
    assert "[-0.123456  1.      ]" in _message(lambda: _emulator(cases[1]))


def test_a_fixed_value_outside_its_bounds_is_shown_in_full_under_the_users_print_options():
    emu, s = _emulator()

    def calibrate():
        gpmsa.calibrate(emu, [[0.5]], [s], fixed={"lamOs": -0.123456})

    default = _message(calibrate)
    assert re.search(r"fixed\['lamOs'\] = \[-0\.123456\] lies outside", default)
    with np.printoptions(**USER_PRINT):
        assert _message(calibrate) == default  # was [-0.12]


def _legend_colours(fig) -> list[tuple]:
    legend = next(ax.get_legend() for ax in fig.axes if ax.get_legend() is not None)
    return [to_rgba(h.get_color()) for h in legend.legend_handles if h.get_label() != "runs"]


def _figures():
    emu, s = _emulator()
    obs = gpmsa.ObsData(x=[[0.5], [0.5], [0.4]], y=[0.5 * s + 0.5 * s**2, 0.5 * s + 3 * s**2, s])
    draws = {"theta": np.random.default_rng(0).normal(size=(3, 40, 1))}
    chains = gpmsa.Chains(draws=draws, log_post=np.zeros((3, 40)), accept_rate={},
                          step_widths={}, info={})  # fmt: skip
    return {
        "traces": lambda: plots.traces(chains),
        "autocorrelation": lambda: plots.autocorrelation(chains),
        "obs_projection": lambda: plots.obs_projection(emu, obs),
        "weight_pairs": lambda: plots.weight_pairs(emu, obs),
    }


@pytest.mark.parametrize("name", ["traces", "autocorrelation", "obs_projection", "weight_pairs"])
def test_series_a_legend_names_differ_in_colour_under_a_one_colour_cycle(name):
    """With rcParams["axes.prop_cycle"] of one colour, chains 0-2 (experiments 0-2) were drawn,
    and listed in the legend, in that one colour."""
    draw = _figures()[name]
    with mpl.rc_context({"axes.prop_cycle": cycler(color=["#1f77b4"])}):
        before = dict(mpl.rcParams)
        colours = _legend_colours(draw())
        assert dict(mpl.rcParams) == before
    assert len(colours) == 3 and len(set(colours)) == 3
    with mpl.rc_context({"axes.prop_cycle": cycler(color=["r", "g", "b", "k"])}):
        assert _legend_colours(draw()) == [to_rgba(c) for c in "rgb"]  # the style's, as before
    assert _legend_colours(draw()) == [to_rgba(f"C{k}") for k in range(3)]


def _colours_of(axes, kinds=("lines", "collections", "patches")) -> set[tuple]:
    """The face or line colours (alpha dropped) of every artist of ``axes``."""
    out = set()
    for ax in axes:
        for kind in kinds:
            for artist in getattr(ax, kind):
                get = getattr(artist, "get_facecolor", None) if kind != "lines" else None
                colour = get() if get is not None else artist.get_color()
                colour = np.atleast_2d(to_rgba_array(colour))
                out.update(tuple(np.round(c[:3], 6)) for c in colour)
    return out


def _other_plots():
    """prediction_bands (eta + delta, eta, delta), sensitivity_bars (main and total effects,
    one curve per input), emulator_fit (one held-out run's band, mean and values per colour, in
    its right-hand axes), each as (draw, the axes drawn by colour, series)."""
    emu, s = _emulator()
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    scalar = gpmsa.SimData(x=x, t=t, y=x + t)
    obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])
    joint = gpmsa.fit(scalar, obs, n_iter=20, tune=False, seed=0, discrepancy="constant")
    pred = gpmsa.full_prediction(joint, obs, np.linspace(0.1, 0.9, 4)[:, None], seed=1)
    sens = gpmsa.sensitivity(emu, draws=False)
    held = gpmsa.cross_validate(emu, folds=4, draws=False)
    return {
        "prediction_bands": (lambda: plots.prediction_bands(pred).axes, 3),
        "sensitivity_bars": (lambda: plots.sensitivity_bars(sens).axes, 2),
        "emulator_fit": (
            lambda: plots.emulator_fit(emu, held, draws=False, max_runs=3).axes[1:],
            3,
        ),
    }


def test_other_plots_tell_their_series_apart_under_a_one_colour_cycle():
    """prediction_bands drew "eta + delta" and "simulator eta" (and delta), sensitivity_bars the
    main and total effects, emulator_fit each held-out run, all in a one-colour cycle's colour."""
    greys = {(0.8, 0.8, 0.8), (0.7, 0.7, 0.7), (0.6, 0.6, 0.6), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)}
    for name, (draw, series) in _other_plots().items():
        with mpl.rc_context({"axes.prop_cycle": cycler(color=["#1f77b4"])}):
            one = _colours_of(draw()) - greys
        default = _colours_of(draw()) - greys
        assert len(one) >= series, (name, one)
        assert one == default, name  # the default cycle's own colours, as drawn before
