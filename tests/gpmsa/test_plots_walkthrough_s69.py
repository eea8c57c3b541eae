"""The figures as a user calls them with their own data (session 69 walkthrough): the axes of
calibration parameters carry the units the data have, and a pair plot of many draws stays a
small file in the vector formats."""

import numpy as np

import gpmsa
from gpmsa import plots

PARAMS = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}


def _sim() -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    return gpmsa.SimData(x=x, t=t, y=x + t, x_names=["v"], t_names=["GD"], x_units=["m/s"],
                         t_units=["1e-6 m^3"], y_units=["m"])  # fmt: skip


def test_parameter_axes_carry_the_units_of_the_data():
    """plots.data and Posterior.plot labelled "GD (1e-6 m^3)"; traces, theta_pairs and
    pc_basis labelled the same axis "GD"."""
    sim = _sim()
    emu = gpmsa.Emulator.from_params(sim, PARAMS)
    post = gpmsa.calibrate(emu, [[0.5]], [[1.0]], n_samples=60, n_burn=10, seed=0)
    grid = gpmsa.Calibrator(emu).update([[0.5]], [[1.0]])
    for source in (post, grid):
        assert [ax.get_ylabel() for ax in plots.traces(source).axes[::2]] == [
            "GD (1e-6 m^3)",
            "lamOs",
        ]
        assert plots.theta_pairs(source).axes[0].get_xlabel() == "GD (1e-6 m^3)"
    assert [ax.get_xlabel() for ax in plots.pc_basis(emu).axes] == ["v (m/s)", "GD (1e-6 m^3)"]
    obs = gpmsa.ObsData(x=[[0.3], [0.6]], y=[[0.9], [1.2]])
    joint = gpmsa.fit(sim, obs, n_iter=20, tune=False, seed=0)
    assert plots.traces(joint, names="GD").axes[0].get_ylabel() == "GD (1e-6 m^3)"
    assert plots.theta_pairs(joint).axes[0].get_xlabel() == "GD (1e-6 m^3)"
    bare = gpmsa.Posterior({"GD": np.arange(5.0)})  # no units recorded: the name alone
    assert plots.theta_pairs(bare).axes[0].get_xlabel() == "GD"


def test_a_pair_plot_of_many_draws_is_rasterised_in_vector_formats(tmp_path):
    """Six parameters of 1e5 draws wrote a 220 MB SVG (22 MB PDF) in 18 s: every draw a vector
    marker. The scatter is rasterised; its data stay every draw."""
    rng = np.random.default_rng(0)
    post = gpmsa.Posterior({n: rng.normal(size=20_000) for n in ("a", "b", "c")})
    fig = plots.theta_pairs(post)
    scatter = fig.axes[3]  # b against a
    assert scatter.lines[0].get_rasterized()
    np.testing.assert_array_equal(scatter.lines[0].get_xdata(), post.samples["a"])
    fig.savefig(tmp_path / "pairs.svg")
    assert (tmp_path / "pairs.svg").stat().st_size < 1_000_000
