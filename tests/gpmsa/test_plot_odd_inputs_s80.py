"""The figures with odd but valid inputs (session 80 sweep): draws a few ulps apart, a
Posterior's hand-made ``info["units"]``, a dark matplotlib style, a scalar prediction at one x."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

import gpmsa  # noqa: E402
from gpmsa import GPMSAError, plots  # noqa: E402
from gpmsa.predictive.full import FullPrediction  # noqa: E402


def _ulp_draws(value: float, n: int = 200) -> np.ndarray:
    """``n`` draws of ``value`` and its next 3 floats: a stuck chain's rounding."""
    return value + np.spacing(value) * (np.arange(n) % 4)


@pytest.mark.parametrize("value", [1e-12, 1.0, 400.0, 1e12])
def test_draws_a_few_ulps_apart_are_drawn_not_refused_by_numpy(value):
    """numpy's "Too many bins for data range. Cannot create 50 finite-sized bins" came out of
    Posterior.plot, traces and theta_pairs for draws a few ulps apart."""
    draws = _ulp_draws(value)
    post = gpmsa.Posterior({"a": draws, "b": np.linspace(0.0, 1.0, draws.size)})
    hist = post.plot("a").axes[0]
    assert len(hist.patches) >= 1
    fig = plots.traces(post)
    counts = [p.get_width() for p in fig.axes[1].patches]  # horizontal bars: width = count
    assert sum(counts) == draws.size
    pairs = plots.theta_pairs(post)
    assert len(pairs.axes[0].patches) >= 1
    from gpmsa.mcmc.diagnostics import histogram_bins

    edges = histogram_bins(draws, 50)
    assert edges[0] == draws.min() and edges[-1] == draws.max() and np.all(np.diff(edges) > 0)


def test_histogram_bins_keep_the_count_where_numpy_takes_it():
    """Ordinary and equal draws keep ``bins``, so their figures are as before."""
    from gpmsa.mcmc.diagnostics import histogram_bins

    rng = np.random.default_rng(0)
    assert histogram_bins(rng.normal(size=100), 40) == 40
    assert histogram_bins(np.full(10, 400.0), 40) == 40
    assert histogram_bins(np.array([]), 40) == 40


def _post(info):
    return gpmsa.Posterior({"a": np.linspace(0.0, 1.0, 50)}, info=info)


def test_a_units_record_that_is_no_dict_is_refused_naming_it():
    """Posterior(info={"units": 3}).plot("a") failed with AttributeError: 'int' object has no
    attribute 'get'; traces ignored such a record silently."""
    for record in (3, "m", ["m"]):
        with pytest.raises(GPMSAError, match=r"info\['units'\] must be a dict parameter name"):
            _post({"units": record}).plot("a")
        with pytest.raises(GPMSAError, match=r"info\['units'\] must be a dict parameter name"):
            plots.traces(_post({"units": record}))
    fig = _post({"units": 3}).plot("a", unit="m")  # a unit given: the record is not read
    assert fig.axes[0].get_xlabel() == "a (m)"


def test_units_entries_read_as_simdata_reads_units():
    """A number is its text, in every figure (traces dropped it); a list, bytes or NaN is
    refused (Posterior.plot labelled the axis "a (['m'])"); None or "" is no unit."""
    assert _post({"units": {"a": 3}}).plot("a").axes[0].get_xlabel() == "a (3)"
    assert plots.traces(_post({"units": {"a": 3}})).axes[0].get_ylabel() == "a (3)"
    for entry in (None, ""):
        assert _post({"units": {"a": entry}}).plot("a").axes[0].get_xlabel() == "a"
    for entry in (["m"], b"m", float("nan")):
        with pytest.raises(GPMSAError, match=r"info\['units'\]\['a'\] must be a unit"):
            _post({"units": {"a": entry}}).plot("a")
        with pytest.raises(GPMSAError, match=r"info\['units'\]\['a'\] must be a unit"):
            plots.theta_pairs(_post({"units": {"a": entry}}))
    fig = _post({"units": {"a": "1e-6 m$^3$", "other": "s"}}).plot("a")  # as calibrate records
    assert fig.axes[0].get_xlabel() == "a (1e-6 m$^3$)"


def _scalar_data():
    x = np.linspace(0.0, 1.0, 12)[:, None]
    t = np.linspace(1.0, 0.0, 12)[:, None] ** 2
    sim = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["v"], t_names=["GD"])
    return sim, gpmsa.ObsData(x=[[0.3], [0.7]], y=[[0.9], [1.0]])


def test_observations_stay_visible_in_a_dark_style():
    """The observations were drawn in black, on dark_background's black axes."""
    sim, obs = _scalar_data()
    with plt.style.context("dark_background"):
        fig = plots.data(sim, obs)
    marks = [line for line in fig.axes[0].lines if line.get_label() == "observations"]
    assert to_rgba(marks[0].get_color()) == to_rgba("white")
    assert to_rgba(fig.axes[1].lines[-1].get_color()) == to_rgba("white")  # the t panel's line
    fig = plots.data(sim, obs)  # matplotlib's default style: black, as before
    marks = [line for line in fig.axes[0].lines if line.get_label() == "observations"]
    assert to_rgba(marks[0].get_color()) == to_rgba("k")


def _scalar_prediction(x: np.ndarray) -> FullPrediction:
    """A FullPrediction of a scalar output at ``x`` (N, 1) by hand: 400 draws, one basis
    vector each (K = D = [[1]], standardised scale = native), y wider than eta."""
    rng = np.random.default_rng(1)
    n, s = x.shape[0], 400
    v = 0.1 + 0.02 * rng.standard_normal((s, n, 1))
    u = 1.0 + 0.05 * rng.standard_normal((s, n, 1))
    y = u + v + 0.1 * rng.standard_normal((s, n, 1))
    return FullPrediction(
        x=x, grid=np.zeros(1), draw_index=np.arange(s), theta=np.zeros((s, 1)),
        lamOs=np.full(s, 100.0), mu=np.concatenate([v, u], axis=2),
        cov=np.zeros((s, n, 2, 2)), u=u, v=v, eta=u, delta=v, y=y, K=np.ones((1, 1)),
        D=np.ones((1, 1)), y_mean=np.zeros(1), y_sd=1.0, x_names=("v",), x_units=("m/s",),
    )  # fmt: skip


def test_a_scalar_prediction_at_one_x_draws_its_bands_as_bars():
    """At one x each band was filled between one point and itself: a hairline, unreadable."""
    from gpmsa.plots.prediction import BAR_WIDTHS

    pred = _scalar_prediction(np.array([[1.25]]))
    fig = plots.prediction_bands(pred, observed=[1.1])
    top, bottom = fig.axes
    bars = [c for c in top.collections if isinstance(c, LineCollection)]
    assert [b.get_linewidth()[0] for b in bars] == [BAR_WIDTHS[w] for w in ("y", "zeta", "eta")]
    lo, hi = pred.interval("y", 0.9)
    np.testing.assert_allclose(bars[0].get_segments()[0], [[1.25, lo[0, 0]], [1.25, hi[0, 0]]])
    assert [c for c in bottom.collections if isinstance(c, LineCollection)]
    assert top.get_legend() is not None and bottom.get_xlabel() == "v (m/s)"
    fig = plots.prediction_bands(_scalar_prediction(np.array([[0.5], [1.0], [1.5]])))
    assert len([c for c in fig.axes[0].collections if isinstance(c, PolyCollection)]) == 3
