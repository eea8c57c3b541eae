"""Session 73's walkthrough of its new features from the docs (a categorical calibration
parameter, extrapolation), three defects found:

- ``Posterior.plot`` of a categorical parameter's draws (``calibrate``, a study: their
  ``info["levels"]``) drew a 50-bin density histogram (heights 36 and 13.5 for shares 0.73 and
  0.27, "density" on the axis) where the grid posterior draws a probability per level.
- ``gpmsa info`` of a joint fit with a held continuous theta element beside a categorical one
  whose draws all sat at one level (ESS and R-hat null) printed "ESS [held] R-hat [held]": one
  cell for two elements, the free one's dropped.
- A joint fit's x_obs outside the design was named on the unit scale ("x_obs column s reaches
  0.488..1.58 on the unit scale of the design"), the warning named no column; calibrate's
  same rule names the value given and the domain in native units.
"""

import contextlib
import io
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main


def test_a_categorical_posteriors_draws_plot_as_a_probability_per_level():
    draws = np.r_[np.zeros(73), np.ones(27)]
    post = gpmsa.Posterior({"kind": draws}, info={"levels": {"kind": [0.0, 1.0, 2.0]}})
    ax = post.plot("kind").axes[0]
    assert ax.get_ylabel() == "probability"  # before: "density", 50 bins
    heights = sorted(p.get_height() for p in ax.patches)
    np.testing.assert_allclose(heights, [0.0, 0.27, 0.73])
    # a record that holds no list of levels: the histogram, as before
    for info in ({"levels": "kind"}, {"levels": {"kind": "abc"}}, {}):
        ax = gpmsa.Posterior({"kind": draws}, info=info).plot("kind").axes[0]
        assert ax.get_ylabel() == "density" and len(ax.patches) == 50


def _data(m: int = 30):
    rng = np.random.default_rng(2)
    x = rng.random((m, 1))
    t = np.column_stack([rng.random(m), np.arange(m) % 3])
    y = np.sin(3 * x[:, 0]) + t[:, 0] + 0.5 * t[:, 1]
    return gpmsa.SimData(x, t, y, x_names=["s"], t_names=["k", "kind"], t_categorical=["kind"])


def test_gpmsa_info_keeps_a_free_elements_place_beside_a_held_one(tmp_path):
    xo = np.linspace(0.1, 0.9, 4)[:, None]
    obs = gpmsa.ObsData(x=xo, y=(np.sin(3 * xo[:, 0]) + 0.9)[:, None])  # kind 1 at k = 0.4
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(_data(), obs, n_iter=40, tune=False, seed=0,
                        fixed={"theta": {"k": 0.4}})  # fmt: skip
    assert set(emu.calibration["theta_native"][:, 1]) == {1.0}  # kind constant: no ESS
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(emu.save(tmp_path / "e.gpmsa"))])
    line = next(ln for ln in out.getvalue().splitlines() if ln.startswith("posterior theta"))
    assert "ESS [held, nan] R-hat [held, nan]" in line  # before: "ESS [held] R-hat [held]"


def test_a_joint_fits_x_obs_outside_the_design_is_named_in_native_units():
    data = _data()
    lo, hi = (f"{v:.6g}" for v in (data.x.min(), data.x.max()))
    with pytest.raises(gpmsa.GPMSAError) as err:
        gpmsa.prepare(data, gpmsa.ObsData(x=[[0.5], [1.5]], y=[[1.3], [0.3]]))
    msg = str(err.value)
    assert f"x_obs s=1.5 lies outside the simulation design's range [{lo}, {hi}]" in msg
    assert "cannot extrapolate that far" in msg and "extrapolate=True" in msg
    warned = rf"x_obs s=1.02 lies outside the simulation design's range \[{lo}"
    with pytest.warns(gpmsa.ExtrapolationWarning, match=warned):
        gpmsa.prepare(data, gpmsa.ObsData(x=[[0.5], [1.02]], y=[[1.3], [0.3]]))


def test_a_categorical_plot_draws_no_mean_between_levels():
    """The mean of the codes (0.27 here) lies between levels: no line for it (a continuous
    parameter keeps its mean line)."""
    draws = np.r_[np.zeros(73), np.ones(27)]
    post = gpmsa.Posterior({"kind": draws, "k": np.linspace(0, 1, 100)},
                           info={"levels": {"kind": [0.0, 1.0, 2.0]}})  # fmt: skip
    assert "mean" not in post.plot("kind").axes[0].get_legend_handles_labels()[1]
    assert "mean" in post.plot("k").axes[0].get_legend_handles_labels()[1]


def test_fit_with_extrapolate_says_where_the_option_is():
    rng = np.random.default_rng(0)
    x, t = rng.random((12, 1)), rng.random((12, 1))
    sim = gpmsa.SimData(x, t, x[:, 0] + t[:, 0])
    with pytest.raises(gpmsa.GPMSAError, match="calibrate of the fitted emulator takes "
                       "extrapolate=True"):  # fmt: skip
        gpmsa.fit(sim, n_iter=10, extrapolate=True)
