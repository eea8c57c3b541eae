"""Bad input to the workflows after a fit (study predictions, Posterior, plots): refused with a
GPMSAError naming the problem, never silently wrong."""

import warnings
from functools import cache

import matplotlib
import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError

matplotlib.use("Agg")

GRID = np.linspace(0.0, 1.0, 8)


@cache
def _study():
    """Two models of one simulator with a linear discrepancy, their observations apart."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.outer(x[:, 0] + t[:, 0], 1 + GRID), index=GRID,
                        x_names=["x"], t_names=["t"])  # fmt: skip
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    obs_a = gpmsa.ObsData(x=xo, y=np.outer(xo[:, 0] + 0.4, 1 + GRID) + 0.1, index=GRID)
    obs_b = gpmsa.ObsData(x=xo, y=np.outer(xo[:, 0] + 0.6, 1 + GRID) + 5.0, index=GRID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a short run: not converged
        study = gpmsa.fit_study([sim, sim], [obs_a, obs_b], shared=["t"], n_iter=150, seed=0,
                                tune_rounds=3, discrepancy="linear")  # fmt: skip
    return study, obs_a, obs_b


def test_a_study_model_predicts_with_its_own_discrepancy_and_observations_only(tmp_path):
    study, obs_a, obs_b = _study()
    model = study.members[0]
    assert model.settings["discrepancy"] == "linear"
    assert model.settings["obs_sha256"] == obs_a.digest()
    by_default = gpmsa.full_prediction(model, obs_a, [[0.5]], n_draws=5, seed=0)
    given = gpmsa.full_prediction(model, obs_a, [[0.5]], discrepancy="linear", n_draws=5, seed=0)
    np.testing.assert_array_equal(by_default.y, given.y)
    with pytest.raises(GPMSAError, match="obs holds other observations .* than the joint fit's"):
        gpmsa.full_prediction(model, obs_b, [[0.5]])  # model 1's: they read 5 units higher
    with pytest.raises(GPMSAError, match=r"discrepancy='constant' differs from the joint fit's"):
        gpmsa.full_prediction(model, obs_a, [[0.5]], discrepancy="constant")
    # a saved and loaded study's models keep both records
    study.save(tmp_path / "two.gpmsa")
    loaded = gpmsa.load_study(tmp_path / "two.gpmsa").members[1]
    assert loaded.settings["obs_sha256"] == obs_b.digest()
    with pytest.raises(GPMSAError, match="obs holds other observations"):
        gpmsa.full_prediction(loaded, obs_a, [[0.5]])


def test_a_study_models_posterior_carries_its_discrepancy_draws():
    study, obs_a, _ = _study()
    post = study.member_posterior(0)
    assert set(post.names) == {"t", "lamOs", "betaV", "lamVz"}
    cal = study.members[0].calibration
    np.testing.assert_array_equal(post.samples["betaV"], np.ravel(cal["betaV"]))
    np.testing.assert_array_equal(post.samples["lamVz"], np.ravel(cal["lamVz"]))
    pred = gpmsa.full_prediction(study.members[0], obs_a, [[0.5]], posterior=post,
                                 discrepancy="linear", n_draws=5, seed=0)  # fmt: skip
    joint = gpmsa.full_prediction(study.members[0], obs_a, [[0.5]], n_draws=5, seed=0)
    assert pred.p_v == 2
    # the same theta and discrepancy draws; only the emulator's parameters differ (point vs draws)
    np.testing.assert_allclose(pred.mean("y"), joint.mean("y"), rtol=1e-3)


def test_plots_take_a_study():
    study, _, _ = _study()
    assert len(gpmsa.plots.traces(study).axes) == 2 * len(study.posterior.names)
    assert len(gpmsa.plots.theta_pairs(study).axes) == 1  # t; not lamOs[LABEL]


def test_samples_are_joint_draws_and_chains_are_them_split():
    with pytest.raises(GPMSAError, match=r"same number of draws of every parameter .* "
                                         r"\{'t': 3, 'lamOs': 1\}"):  # fmt: skip
        gpmsa.Posterior({"t": [0.5, 0.6, 0.7], "lamOs": [100.0]})
    with pytest.raises(GPMSAError, match=r"chains\['a'\] of shape \(1, 2\) are not samples\['a'\]"):
        gpmsa.Posterior({"a": [1.0, 2.0, 3.0, 4.0]}, chains={"a": [[10.0, 20.0]]})
    with pytest.raises(GPMSAError, match="are not samples"):  # the same count, other values
        gpmsa.Posterior({"a": [1.0, 2.0]}, chains={"a": [[2.0, 1.0]]})
    post = gpmsa.Posterior({"a": [1.0, 2.0, 3.0, 4.0]}, chains={"a": [[1.0, 2.0], [3.0, 4.0]]})
    assert post.mean("a") == 2.5


def test_theta_pairs_hides_exactly_the_reserved_names():
    rng = np.random.default_rng(1)
    names = ("betaVel", "a.lam", "lamOs", "betaV[0]", "lamVz", "g.mu", "g.sd", "g.lam")
    draws = {name: rng.normal(size=50) for name in names}
    fig = gpmsa.plots.theta_pairs(gpmsa.Posterior(draws))
    shown = {ax.get_xlabel() for ax in fig.axes if ax.get_xlabel()}
    assert shown == {"betaVel", "a.lam", "g.mu", "g.sd"}  # g.lam: the group's precision
    with pytest.raises(GPMSAError, match="names is empty"):
        gpmsa.plots.theta_pairs(gpmsa.Posterior(draws), names=[])
    with pytest.raises(GPMSAError, match="no calibration parameter to plot"):
        gpmsa.plots.theta_pairs(gpmsa.Posterior({"lamOs": draws["lamOs"]}))


def test_plot_counts_and_flags_are_checked():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
    obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])
    emu = gpmsa.fit(data, obs, n_iter=50, tune=False, seed=0, discrepancy="constant")
    pred = gpmsa.full_prediction(emu, obs, np.linspace(0.1, 0.9, 5)[:, None], seed=1)
    for kwargs, match in (
        ({"max_panels": 0}, "max_panels must be an integer >= 1, got 0"),
        ({"max_panels": "3"}, "max_panels must be an integer >= 1, got '3'"),
        ({"x_column": 1}, r"x_column must be an integer in \[0, 0\], got 1"),
        ({"x_column": 0.5}, r"x_column must be an integer in \[0, 0\], got 0.5"),
    ):
        with pytest.raises(GPMSAError, match=match):
            gpmsa.plots.prediction_bands(pred, **kwargs)
    held_out = gpmsa.SimData(x=x[:5], t=t[:5], y=(x + t)[:5], x_names=["x"], t_names=["t"])
    with pytest.raises(GPMSAError, match="draws must be"):
        gpmsa.plots.emulator_fit(emu, held_out, draws="no")
    for call in (
        lambda: gpmsa.plots.emulator_fit(emu, held_out, draws=False, n_draws=-1),
        lambda: gpmsa.sensitivity(emu, draws=False, n_draws=0),
        lambda: gpmsa.emulator_prediction(emu, [[0.5]], [[0.5]], draws=False, n_draws=-5),
    ):
        with pytest.raises(GPMSAError, match="n_draws must be an integer >= 1"):
            call()


def test_a_study_models_posterior_refuses_other_observations(tmp_path):
    """``full_prediction(posterior=study.member_posterior(i))`` conditions on ``obs``: another
    model's observations were taken silently (the member posterior lacked the record that
    ``calibration_posterior`` and ``gpmsa.calibrate`` posteriors carry)."""
    study, obs_a, obs_b = _study()
    post = study.member_posterior(0)
    assert post.info["obs_sha256"] == obs_a.digest()
    with pytest.raises(GPMSAError, match="obs holds other observations .* than the joint fit's"):
        gpmsa.full_prediction(study.members[0], obs_b, [[0.5]], posterior=post,
                              discrepancy="linear", n_draws=5, seed=0)  # fmt: skip
    study.save(tmp_path / "two.gpmsa")
    loaded = gpmsa.load_study(tmp_path / "two.gpmsa")
    post = loaded.member_posterior(0)
    with pytest.raises(GPMSAError, match="obs holds other observations"):
        gpmsa.full_prediction(
            loaded.members[0], obs_b, [[0.5]], posterior=post, discrepancy="linear"
        )
