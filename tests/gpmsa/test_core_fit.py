"""gpmsa.fit end to end: sim-only, several chains, multivariate output with discrepancy."""

import numpy as np
import pytest

import gpmsa


def lhs(rng, m, d):
    return (np.argsort(rng.random((m, d)), axis=0) + rng.random((m, d))) / m


@pytest.fixture(scope="module")
def small_sim():
    rng = np.random.default_rng(1)
    z = lhs(rng, 30, 2)
    x, t = 1 + 2 * z[:, :1], 10 + 5 * z[:, 1:]
    y = np.sin(2 * x) * t / 10 + 0.01 * rng.standard_normal((30, 1))
    return gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["k"], x_units=["m"])


def test_sim_only_fit_gives_emulator_with_draws_and_diagnostics(small_sim):
    with pytest.warns(gpmsa.ConvergenceWarning, match="2 chains x 320 draws"):  # short chains
        emu = gpmsa.fit(small_sim, n_iter=400, n_chains=2, seed=3, tune=False, n_keep=100)
    assert emu.convergence["n_chains"] == 2 and not emu.convergence["converged"]
    assert emu.settings["thin"] == 7  # ceil(2 chains * 320 kept / 100)
    assert emu.n_draws == 2 * len(range(0, 320, 7)) <= 100
    assert set(emu.draws) == {"betaU", "lamUz", "lamWs", "lamWOs"}
    assert emu.draws["betaU"].shape == (92, 2, 1) and emu.calibration is None
    for k, v in emu.params.items():
        assert np.allclose(v, emu.draws[k].mean(axis=0))
    d = emu.diagnostics["betaU"]
    assert (
        len(d["ess"]) == 2 and all(e > 0 for e in d["ess"]) and all(0 < a < 1 for a in d["accept"])
    )
    assert np.isfinite(d["rhat"]).all()
    idata = emu.to_arviz()
    assert idata.posterior["betaU"].shape[:2] == (2, 46)
    mean, var = emu.predict(small_sim.x[:5], small_sim.t[:5])
    assert np.all(np.abs(mean - small_sim.y[:5]) < 4 * np.sqrt(var))
    m2, v2 = emu.predict(small_sim.x[:5], small_sim.t[:5], draws=True, n_draws=20)
    assert np.allclose(m2, mean, atol=0.05) and np.all(v2 > 0)


def test_same_seed_same_numbers_and_map_point(small_sim):
    a = gpmsa.fit(small_sim, n_iter=60, seed=11, tune=False)
    b = gpmsa.fit(small_sim, n_iter=60, seed=11, tune=False, point="map")
    assert np.array_equal(a.draws["betaU"], b.draws["betaU"])
    best = int(np.argmax(b.log_post))
    assert np.array_equal(b.params["lamUz"], b.draws["lamUz"][best])
    c = gpmsa.fit(small_sim, n_iter=60, seed=12, tune=False)
    assert not np.array_equal(a.draws["betaU"], c.draws["betaU"])


def test_fit_argument_errors(small_sim):
    with pytest.raises(gpmsa.GPMSAError, match="n_iter must be"):
        gpmsa.fit(small_sim, n_iter=1)
    for n_burn in (10, -1, 2.5, "2"):  # a float was truncated, a string a raw ValueError
        with pytest.raises(gpmsa.GPMSAError, match=r"n_burn must be an integer in \[0, 9\]"):
            gpmsa.fit(small_sim, n_iter=10, n_burn=n_burn)
    with pytest.raises(gpmsa.GPMSAError, match="n_keep must be an integer >= 1"):
        gpmsa.fit(small_sim, n_iter=10, n_keep=float("nan"))
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy='constant' needs observations"):
        gpmsa.fit(small_sim, n_iter=10, discrepancy="constant")  # was silently ignored
    with pytest.raises(gpmsa.GPMSAError, match="point must be"):
        gpmsa.fit(small_sim, n_iter=10, point="median")
    with pytest.raises(gpmsa.GPMSAError, match="unknown backend 'jax'"):
        gpmsa.fit(small_sim, n_iter=10, backend="jax")
    with pytest.raises(gpmsa.GPMSAError, match="data must be a gpmsa.SimData"):
        gpmsa.fit({"x": 1}, n_iter=10)


@pytest.mark.parametrize(
    ("widths", "match"),
    [({"lamWOs": np.nan}, r"step_widths\['lamWOs'\] must be finite and > 0, got \[nan\]"),
     ({"lamWOs": 0.0}, r"step_widths\['lamWOs'\] must be finite and > 0"),
     ({"betaU": -5.0}, r"step_widths\['betaU'\] must be finite and > 0"),
     ({"betaU": [[0.1], [np.inf]]}, r"step_widths\['betaU'\] must be finite and > 0"),
     ({"betaU": [0.1, 0.1, 0.1]}, r"\['betaU'\] must be a scalar or have shape \(2, 1\)"),
     ({"lamOs": 1.0}, r"step_widths: unknown parameter 'lamOs'; this model has"),
     ({"lamWOs": "wide"}, r"step_widths\['lamWOs'\] must be a numeric array"),
     ({"lamWOs": 1 + 1j}, r"step_widths\['lamWOs'\] must hold real numbers"),
     ([("lamWOs", 1.0)], "step_widths must be None or a dict name -> widths, got list"),
     ("lamWOs", "step_widths must be None or a dict name -> widths, got str")],
)  # fmt: skip
def test_fit_step_widths_are_checked(small_sim, widths, match):
    """A zero, negative or NaN width froze the chain silently; others raised deep inside."""
    for tune in (False, True):
        with pytest.raises(gpmsa.GPMSAError, match=match):
            gpmsa.fit(small_sim, n_iter=10, tune=tune, step_widths=widths)


def test_fit_step_widths_in_the_parameters_shape_are_used(small_sim):
    emu = gpmsa.fit(small_sim, n_iter=10, tune=False, seed=0,
                    step_widths={"betaU": [[0.2], [0.3]], "lamWOs": [50.0]})  # fmt: skip
    assert emu.settings["step_widths"]["betaU"] == [[[0.2], [0.3]]]
    assert emu.settings["step_widths"]["lamWOs"] == [[50.0]]


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"tune_rounds": 0}, r"tune_rounds must be an integer in \[1, 1000000\], got 0"),
     ({"tune_rounds": 2.5}, "tune_rounds must be an integer"),
     ({"tune_rounds": "5"}, "tune_rounds must be an integer"),
     ({"tune_levels": 1}, r"tune_levels must be an integer in \[2, 1000\], got 1"),
     ({"tune_levels": -2}, "tune_levels must be an integer"),
     ({"tune_levels": 10**9}, r"tune_levels must be an integer in \[2, 1000\]"),
     ({"tune_rounds": 10**7}, "tune_rounds must be an integer in"),
     ({"tune_rounds": 10**5, "tune_levels": 20}, r"100000 x 20 tuning sweeps per chain, above")],
)  # fmt: skip
def test_fit_tuning_options_are_bounded_counts(small_sim, kw, match):
    """tune_rounds=10**7 ran for hours; 0 or 1 level gave a silent GLM on nothing."""
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.fit(small_sim, n_iter=10, **kw)


def test_multivariate_output_with_discrepancy_recovers_true_theta():
    """p_u > 1, constant discrepancy, three experiments; theta_true = 0.6 (native 1.6)."""
    rng = np.random.default_rng(5)
    s = np.linspace(0, 1, 25)

    def sim_fn(x, t):
        return t[:, None] * np.sin(2 * np.pi * s[None, :] + x[:, None]) + x[:, None] * s[None, :]

    z = lhs(rng, 40, 2)
    x, t = z[:, 0], 1 + z[:, 1]
    sim = gpmsa.SimData(x=x, t=t, y=sim_fn(x, t), index=s, t_names=["amp"])
    xo = np.array([0.2, 0.5, 0.8])
    yo = sim_fn(xo, np.full(3, 1.6)) + 0.1 + 0.01 * rng.standard_normal((3, 25))
    obs = gpmsa.ObsData(x=xo[:, None], y=yo, index=s)
    emu = gpmsa.fit(sim, obs=obs, n_iter=800, seed=1, discrepancy="constant")
    assert emu.p_u >= 2 and emu.K.shape == (25, emu.p_u)
    assert {"theta", "lamOs", "betaV", "lamVz", "theta_native"} <= set(emu.calibration)
    summary = emu.theta_summary()["amp"]
    assert abs(summary["mean"] - 1.6) < 3 * summary["sd"] + 0.02, summary
    assert summary["sd"] < 0.15
    mean, var = emu.predict(xo[:, None], np.full((3, 1), 1.6))
    assert mean.shape == (3, 25) and np.all(var > 0)
    truth = sim_fn(xo, np.full(3, 1.6))
    assert np.sqrt(np.mean((mean - truth) ** 2)) < 0.1


def test_an_unknown_fit_option_is_named_with_the_backends_options():
    t = np.linspace(1, 0, 8)[[1, 0, 3, 2, 5, 4, 7, 6], None]  # not collinear with x
    sim = gpmsa.SimData(x=np.linspace(0, 1, 8)[:, None], t=t, y=np.linspace(0, 1, 8) ** 2)
    with pytest.raises(gpmsa.GPMSAError, match=r"unknown option\(s\) \['tune_round'\] .* takes \["):
        gpmsa.fit(sim, n_iter=5, tune_round=3)
