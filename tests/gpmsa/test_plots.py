"""The figures: each a matplotlib Figure with the content it promises; nothing shown; matplotlib
not imported by ``import gpmsa``."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _calib_cases import two_param_emulator
from _predict_cases import known_truth_case, vector_fit
from matplotlib.figure import Figure

import gpmsa
from gpmsa import GPMSAError, plots
from gpmsa.model.problem import GLS_RIDGE

REPO = Path(__file__).resolve().parents[2]


def test_import_gpmsa_does_not_import_matplotlib():
    code = "import sys, gpmsa, gpmsa.plots; print('matplotlib' in sys.modules)"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"


def test_traces_of_an_emulator_joint_fit_and_a_selection():
    emu, *_ = known_truth_case()
    fig = plots.traces(emu)
    assert isinstance(fig, Figure)
    labels = [ax.get_ylabel() for ax in fig.axes[::2]]
    n_scalars = 4 + 2 * emu.p_u + 2 * emu.p_u + 1  # t lamOs lamVz betaV, betaU, lamUz lamWs, lamWOs
    assert labels[:4] == ["t", "lamOs", "betaV", "lamVz"] and len(labels) == min(12, n_scalars)
    line = fig.axes[0].lines[0]
    np.testing.assert_array_equal(line.get_ydata(), emu.calibration["theta_native"][:, 0])
    fig = plots.traces(emu, names=["betaU"])
    assert [ax.get_ylabel() for ax in fig.axes[::2]] == [
        f"betaU[{i},{j}]" for i in range(2) for j in range(emu.p_u)
    ]
    with pytest.raises(GPMSAError, match="unknown parameter 'beta'"):
        plots.traces(emu, names="beta")
    with pytest.raises(GPMSAError, match="kept no posterior draws"):
        plots.traces(two_param_emulator())
    with pytest.raises(GPMSAError, match="source must be"):
        plots.traces({"t": [1, 2]})


def test_traces_of_chains_show_each_chain():
    chains = gpmsa.Chains(
        draws={"theta": np.random.default_rng(0).normal(size=(3, 50, 1))},
        log_post=np.zeros((3, 50)), accept_rate={}, step_widths={}, info={},
    )  # fmt: skip
    fig = plots.traces(chains)
    assert len(fig.axes[0].lines) == 3 and fig.axes[0].get_legend() is not None


def test_huge_bin_counts_are_refused_before_drawing():
    """bins=10**9 asked matplotlib for ~10 TB of Rectangle patches."""
    post = gpmsa.Posterior({"a": np.arange(10.0), "b": np.arange(10.0)})
    with pytest.raises(gpmsa.ResourceLimitError, match=r"plots.traces: 2 histogram\(s\) of "
                       r"1000000000 bins .*gpmsa.limits.MAX_MEMORY_BYTES"):  # fmt: skip
        plots.traces(post, bins=10**9)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"plots.theta_pairs: 2 histogram"):
        plots.theta_pairs(post, bins=10**9)
    with pytest.raises(GPMSAError, match="bins must be an integer >= 1, got 0"):
        plots.traces(post, bins=0)


def test_empty_or_uncountable_selections_are_named():
    post = gpmsa.Posterior({"a": np.arange(10.0), "b": np.arange(10.0)})
    with pytest.raises(GPMSAError, match="names is empty; available"):
        plots.traces(post, names=[])
    for bad in (0, -1, 2.5, "3"):
        with pytest.raises(GPMSAError, match="max_params must be an integer >= 1"):
            plots.traces(post, max_params=bad)
        with pytest.raises(GPMSAError, match="max_pc must be an integer >= 1"):
            plots.pc_basis(two_param_emulator(), max_pc=bad)


def test_theta_pairs_marks_the_truth():
    rng = np.random.default_rng(0)
    post = gpmsa.Posterior({"a": rng.normal(size=100), "b": rng.normal(size=100),
                            "lamOs": rng.gamma(2.0, size=100)})  # fmt: skip
    fig = plots.theta_pairs(post, truth={"a": 0.5, "b": -0.5})
    assert len(fig.axes) == 4  # lamOs is not a calibration parameter
    scatter = fig.axes[2]
    assert scatter.get_xlabel() == "a" and scatter.get_ylabel() == "b"
    np.testing.assert_array_equal(scatter.lines[0].get_xdata(), post.samples["a"])
    assert tuple(scatter.lines[1].get_xydata()[0]) == (0.5, -0.5)
    emu, *_ = known_truth_case()
    assert len(plots.theta_pairs(emu).axes) == 1
    with pytest.raises(GPMSAError, match="unknown parameters"):
        plots.theta_pairs(post, names=["c"])
    with pytest.raises(GPMSAError, match="joint fit"):
        plots.theta_pairs(vector_fit())


def test_theta_pairs_of_a_study_shows_its_calibration_parameters_only():
    rng = np.random.default_rng(0)
    names = ("t[m0]", "t[m1]", "lamOs[m0]", "lamOs[m1]", "t.mu", "t.sd", "t.lam", "betaV[m0]")
    post = gpmsa.Posterior({n: rng.normal(size=50) for n in names})
    fig = plots.theta_pairs(post)
    assert len(fig.axes) == 16  # t[m0], t[m1], t.mu, t.sd: no noise, discrepancy or precision
    assert [ax.get_xlabel() for ax in fig.axes[-4:]] == ["t[m0]", "t[m1]", "t.mu", "t.sd"]


def test_pc_basis_draws_the_basis_and_weights():
    emu = vector_fit()
    fig = plots.pc_basis(emu)
    assert len(fig.axes) == emu.p_u * 3
    std = emu.standardizer
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(), std.y_sd * emu.K[:, 0])
    np.testing.assert_allclose(fig.axes[1].lines[0].get_ydata(), emu.w[:, 0])
    shares = [float(ax.get_title().split("(")[1].split(" %")[0]) for ax in fig.axes[::3]]
    assert shares[0] > shares[1] and 99.0 < sum(shares) <= 100.0
    assert len(plots.pc_basis(two_param_emulator()).axes) == 3  # scalar: weights only


def test_emulator_fit_against_held_out_runs_and_cross_validation():
    emu = vector_fit()
    rng = np.random.default_rng(1)
    x, t = rng.uniform(0.1, 1.9, (8, 1)), rng.uniform(-0.9, 0.9, (8, 1))
    s = np.linspace(0.0, 1.0, 10)
    y = np.sin(2.0 * x) * (1.0 + s) + np.outer(t[:, 0] ** 2 + 0.3 * t[:, 0], s**2)
    test = gpmsa.SimData(x=x, t=t, y=y, index=s)
    fig = plots.emulator_fit(emu, test)
    assert len(fig.axes) == 2 and "8 held-out runs" in fig.axes[0].get_title()
    fig_title = fig.axes[0].get_title()
    cv = gpmsa.cross_validate(emu, n_draws=5)
    fig = plots.emulator_fit(emu, cv, level=0.5)
    assert "cross-validation" in fig.axes[0].get_title()
    assert plots.emulator_fit(emu, (x, t, y)).axes[0].get_title() == fig_title  # the arrays
    with pytest.raises(GPMSAError, match="held_out must be"):
        plots.emulator_fit(emu, {"x": x, "t": t, "y": y})
    for bad in (0, -1, 2.5):  # 0 and -1 drew nothing, silently
        with pytest.raises(GPMSAError, match="max_runs must be an integer >= 1"):
            plots.emulator_fit(emu, test, max_runs=bad)


def test_emulator_fit_reads_held_out_columns_by_name_and_checks_what_it_is_given():
    """Held-out runs with the emulator's names in another order are read by name (the same
    figure); other names, another output grid, another emulator's cross-validation and a
    basis plot of something other than an emulator are refused."""
    emu = two_param_emulator()
    rng = np.random.default_rng(2)
    x, t = rng.uniform(0.1, 0.9, (8, 1)), rng.uniform(0.1, 0.9, (8, 2))
    y = np.sin(2.0 * x[:, 0] + 1.5 * t[:, 0]) + 0.8 * t[:, 1] * x[:, 0]
    kept = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["a", "b"])
    swapped = gpmsa.SimData(x=x, t=t[:, ::-1], y=y, x_names=["x"], t_names=["b", "a"])
    unnamed = gpmsa.SimData(x=x, t=t, y=y)  # x0, t0, t1: read by position
    misread = gpmsa.SimData(x=x, t=t[:, ::-1], y=y)  # what reading "swapped" by position gave
    titles = [plots.emulator_fit(emu, d, draws=False).axes[0].get_title()
              for d in (kept, swapped, unnamed, misread)]  # fmt: skip
    assert titles[0] == titles[1] == titles[2] != titles[3]
    other = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["a", "c"])
    with pytest.raises(GPMSAError, match=r"name their t columns \['a', 'c'\], the emulator"):
        plots.emulator_fit(emu, other)
    vec = vector_fit()
    s = np.linspace(0.0, 1.0, 10)
    y10 = np.sin(2.0 * x) * (1.0 + s)
    with pytest.raises(GPMSAError, match="another output grid"):
        plots.emulator_fit(vec, gpmsa.SimData(x=x, t=t[:, :1], y=y10, index=3 * s))
    with pytest.raises(GPMSAError, match="cross-validation of another emulator"):
        plots.emulator_fit(emu, gpmsa.cross_validate(vec, draws=False))
    with pytest.raises(GPMSAError, match="emulator must be a gpmsa.Emulator, got CrossValidation"):
        plots.pc_basis(gpmsa.cross_validate(vec, draws=False))


def test_prediction_bands_functional_and_scalar():
    emu, obs, x_new, y_new = known_truth_case()
    pred = gpmsa.full_prediction(emu, obs, x_new[::10], n_draws=50, seed=0)
    fig = plots.prediction_bands(pred, observed=y_new[::10])
    assert len(fig.axes) == 12  # 6 x values, bands and discrepancy
    top = fig.axes[0]
    assert len(top.collections) == 3
    np.testing.assert_allclose(top.lines[0].get_ydata(), pred.mean("eta")[0])
    np.testing.assert_array_equal(top.lines[1].get_ydata(), y_new[0])
    rel = plots.prediction_bands(pred, observed=y_new[::10], relative=True).axes[0]
    np.testing.assert_allclose(rel.lines[1].get_ydata(), y_new[0] - pred.mean("y")[0])
    assert "minus predicted mean" in rel.get_ylabel()
    with pytest.raises(GPMSAError, match=r"observed must have shape \(6, 12\)"):
        plots.prediction_bands(pred, observed=y_new)
    for junk in ("x", {"y": 1.0}):  # were raw numpy errors
        with pytest.raises(GPMSAError, match="observed must be a numeric array"):
            plots.prediction_bands(pred, observed=junk)
    with pytest.raises(GPMSAError, match="relative must be True or False, got 'yes'"):
        plots.prediction_bands(pred, relative="yes")
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
    obs1 = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])
    emu1 = gpmsa.fit(data, obs1, n_iter=50, tune=False, seed=0, discrepancy="constant")
    pred1 = gpmsa.full_prediction(emu1, obs1, [[0.7], [0.3]], seed=1)
    fig = plots.prediction_bands(pred1, observed=[1.2, 0.8])
    assert len(fig.axes) == 2
    np.testing.assert_array_equal(fig.axes[0].lines[-1].get_xdata(), [0.3, 0.7])  # sorted by x


def test_sensitivity_bars():
    emu = vector_fit()
    sens = gpmsa.sensitivity(emu, n_draws=10)
    fig = plots.sensitivity_bars(sens)
    assert len(fig.axes) == 2
    heights = [p.get_height() for p in fig.axes[0].patches]
    np.testing.assert_allclose(heights[:2], sens.main_aggregated.mean(axis=0))
    np.testing.assert_allclose(heights[2:], sens.total_aggregated.mean(axis=0))
    with pytest.raises(GPMSAError, match="sens must be a Sensitivity"):
        plots.sensitivity_bars({"x": 1})


def test_no_pyplot_figure_is_left_open():
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    plots.sensitivity_bars(gpmsa.sensitivity(vector_fit(), n_draws=3)).savefig(
        os.devnull, format="png"
    )
    assert plt.get_fignums() == before


def test_theta_pairs_truth_and_prediction_observations_are_checked():
    post = gpmsa.Posterior({"a": np.arange(10.0), "b": np.arange(10.0)})
    plots.theta_pairs(post, names=["a"], truth={"a": 1.0, "b": 2.0})  # b: not shown, not a typo
    for truth, match in (
        ({"c": 1.0}, r"truth: unknown parameter\(s\) \['c'\]"),
        ({"a": np.nan}, r"truth\['a'\] must be one finite number"),
        ({"a": "x"}, r"truth\['a'\] must be a numeric array"),
        ({"a": [1.0, 2.0]}, r"truth\['a'\] must be one finite number"),
        ([1.0], "truth must be a dict"),
    ):
        with pytest.raises(GPMSAError, match=match):
            plots.theta_pairs(post, truth=truth)


def test_autocorrelation_draws_each_chains_acf_with_its_ess():
    """SEPIA's plot_acf: an AR(1) chain of coefficient 0.8 shows 0.8 ** lag; the title gives its
    bulk ESS; a constant chain is named, not drawn as NaN noise."""
    rng = np.random.default_rng(1)
    ar = np.zeros((2, 4000, 1))
    for i in range(1, 4000):
        ar[:, i] = 0.8 * ar[:, i - 1] + rng.normal(size=(2, 1))
    draws = {"theta": ar, "lamOs": np.ones((2, 4000, 1))}
    chains = gpmsa.Chains(draws=draws, log_post=np.zeros((2, 4000)), accept_rate={},
                          step_widths={}, info={})  # fmt: skip
    fig = plots.autocorrelation(chains, max_lag=10)
    first = fig.axes[0]
    assert len(first.lines) == 2 + 1 and first.get_legend() is not None  # 2 chains + zero line
    lags, acf = first.lines[0].get_data()
    np.testing.assert_array_equal(lags, np.arange(11))
    np.testing.assert_allclose(acf, 0.8 ** np.arange(11), atol=0.05)
    ess = gpmsa.mcmc.diagnostics.ess(ar[:, :, 0])
    assert 700 < ess < 1100  # (1 - 0.8) / (1 + 0.8) x 8000 = 889
    assert first.get_title() == f"theta: ESS {ess:.0f} of 8000"
    assert fig.axes[1].get_title() == "lamOs: ESS constant"
    emu, *_ = known_truth_case()
    fig = plots.autocorrelation(emu, names=["t", "betaU"], max_lag=5000)
    per_chain = emu.n_draws // emu.settings["n_chains"]
    assert [ax.get_title().split(":")[0] for ax in fig.axes if ax.axison] == [
        "t",
        *[f"betaU[{i},{j}]" for i in range(2) for j in range(emu.p_u)],
    ]
    assert fig.axes[0].lines[0].get_xdata()[-1] == per_chain - 1  # max_lag capped
    with pytest.raises(GPMSAError, match="max_lag must be an integer >= 1"):
        plots.autocorrelation(emu, max_lag=0)
    with pytest.raises(GPMSAError, match="needs >= 2 draws per chain"):
        plots.autocorrelation(gpmsa.Posterior({"t": np.array([0.5])}))


def test_obs_projection_shows_each_experiments_weights_and_what_the_basis_misses():
    """SEPIA's plot_K_weights / plot_K_residuals: the lines are the weights calibration fits
    (GLS on the basis interpolated to an experiment's own index), the residual panel what that
    basis leaves of the runs and of each experiment, in native units."""
    emu = vector_fit()
    s = emu.standardizer.grid
    own = np.linspace(0.1, 0.9, 7)  # an experiment on its own index
    y_in = np.sin(1.0) * (1.0 + s) + 0.2 * s**2
    y_own = np.sin(1.0) * (1.0 + own) + 5.0 * own**2 + 0.05 * np.sin(20 * own)
    obs = gpmsa.ObsData(x=[[0.5], [0.5]], y=[y_in, y_own], index=[s, own])
    fig = plots.obs_projection(emu, obs)
    hist = fig.axes[:2]
    std, K = emu.standardizer, emu.K
    for e, (y, grid) in enumerate([(y_in, s), (y_own, own)]):
        Ke = np.column_stack([np.interp(grid, s, K[:, j]) for j in range(2)])
        y_std = (y - np.interp(grid, s, std.y_mean)) / std.y_sd
        u = np.linalg.solve(Ke.T @ Ke + GLS_RIDGE * np.eye(2), Ke.T @ y_std)  # GPM/SA's ridge
        for j in range(2):
            np.testing.assert_allclose(hist[j].lines[e].get_xdata()[0], u[j], rtol=1e-9)
        line = fig.axes[2].lines[emu.m + e]
        np.testing.assert_array_equal(line.get_xdata(), grid)
        np.testing.assert_allclose(line.get_ydata(), std.y_sd * (y_std - Ke @ u), atol=1e-9)
    w = emu.w
    for j in range(2):
        u = [hist[j].lines[e].get_xdata()[0] for e in range(2)]
        outside = sum(not w[:, j].min() <= v <= w[:, j].max() for v in u)
        assert hist[j].get_title() == f"PC {j + 1}: {outside} of 2 outside the runs"
    assert "outside the runs" in hist[1].get_title() and hist[1].get_title().startswith("PC 2: 1")
    runs = (emu.y - std.y_mean) - std.y_sd * w @ K.T
    np.testing.assert_allclose(fig.axes[2].lines[0].get_ydata(), runs[0])
    scalar = plots.obs_projection(two_param_emulator(), gpmsa.ObsData(x=[[0.3]], y=[[1.0]]))
    assert len(scalar.axes) == 1 and scalar.axes[0].get_title() == "PC 1: 0 of 1 outside the runs"
    with pytest.raises(GPMSAError, match="obs must be a gpmsa.ObsData, got tuple"):
        plots.obs_projection(emu, ([[0.5]], [y_in]))
    with pytest.raises(GPMSAError, match="max_pc must be an integer >= 1"):
        plots.obs_projection(emu, obs, max_pc=0)
