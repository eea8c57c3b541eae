"""The symmetric two-mode case of the parallel-tempering tests: t on 11 runs of 10 (t - 0.5)^2,
eight observations at 0.9 (modes at t = 0.2 and 0.8, exact P(t > 0.5) = 1/2); its fit, and
the checks of a tempered fit's hot-copy record and of the continuation that resumes it."""

import warnings

import numpy as np

import gpmsa


def two_mode_case() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    t = np.linspace(0.0, 1.0, 11)[:, None]
    sim = gpmsa.SimData(t=t, y=10 * (t - 0.5) ** 2)
    obs = gpmsa.ObsData(y=0.9 + 0.002 * np.array([[1], [-1], [0.5], [-0.5]] * 2))
    return sim, obs


def fit_two_mode(**kw) -> gpmsa.Emulator:
    """``gpmsa.fit`` of the two-mode case, its ConvergenceWarnings (short chains) silenced."""
    sim, obs = two_mode_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(sim, obs, **kw)


def check_resumed_hot_copies(src, more, fit, path) -> None:
    """The checks of a tempered fit ``src`` (2 chains, ladder (1, 2, 4)) and its continuation
    ``more`` (``fit(n_iter=10, n_chains=2, init=src, seed=4)``): the source records each hot
    copy's state and widths, the continuation resumes them untuned and records where they
    stopped, a continuation of the saved file (at ``path``) or with ``tune=False`` draws the
    same."""
    s, m = src.settings, more.settings
    assert np.shape(s["hot_states"]["theta"]) == (2, 2, 1)  # (chains, hot copies, *shape)
    assert np.shape(s["hot_step_widths"]["betaU"]) == (2, 2, 1, 1)
    assert np.all(np.isfinite(s["hot_states"]["lamWOs"]))
    assert m["tune"] is False and m["temperatures"] == [1.0, 2.0, 4.0]
    assert m["step_widths"] == s["step_widths"]  # the T = 1 copy's, untuned
    assert m["hot_step_widths"] == s["hot_step_widths"]  # and every hot copy's
    assert m["hot_states"] != s["hot_states"]  # where they stopped now
    back = gpmsa.load(src.save(path))
    assert back.settings["hot_states"] == s["hot_states"]
    again = fit(n_iter=10, n_chains=2, init=back, seed=4)  # the file's: the same draws
    np.testing.assert_array_equal(again.log_post, more.log_post)
    resumed = fit(n_iter=10, n_chains=2, init=src, seed=4, tune=False)  # allowed now
    np.testing.assert_array_equal(resumed.log_post, more.log_post)
