"""``gpmsa.calibrate(..., init=posterior, append=)``: a calibration's chains continue from their
last draws with the step widths they ended with, as ``gpmsa.fit(init=emulator)`` and
``calibrate_study(init=study)`` continue theirs; another emulator, observations or settings are
refused by name, and ``append=True`` pools the draws chain by chain."""

import pickle
import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, two_param_emulator, with_draws

import gpmsa

X2, Y2 = [[0.2], [0.5], [0.8]], [[0.6], [0.9], [1.2]]


def chains_sha256(post):
    """The digest a continuation records of its source (imported here: absent before)."""
    from gpmsa.calibration.continuation import chains_sha256 as digest

    return digest(post)


def _calibrate(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        return gpmsa.calibrate(*args, **kw)


@pytest.fixture(scope="module")
def road():
    emu = road_emulator()
    x, y = road_obs()
    return emu, x, y, _calibrate(emu, x, y, n_samples=600, n_burn=100, seed=1)


def test_a_continuation_starts_at_the_last_draw_with_its_widths(road):
    emu, x, y, src = road
    info = dict(src.info, step_widths=[[1e-9, src.info["step_widths"][0][1]]])
    chains = {k: v.copy() for k, v in src.chains.items()}
    chains["GD"][0, -1] = 0.37 * emu.standardizer.t_max[0]  # far from the centre it starts at
    moved = gpmsa.Posterior({k: v.reshape(-1) for k, v in chains.items()}, chains=chains,
                            info=info)  # fmt: skip
    more = _calibrate(emu, x, y, n_samples=50, seed=2, init=moved)
    assert np.ptp(more.samples["GD"]) < 1e-4  # no re-tuning: the 1e-9 (unit) width it ended with
    assert more.samples["GD"][0] == pytest.approx(chains["GD"][0, -1], abs=1e-4)
    assert more.info["tune"] is False and more.info["n_burn"] == 0
    assert more.info["continued_from"] == chains_sha256(moved)
    assert more.info["proportional_steps"] is False  # tuned source: uniform lamOs steps


def test_append_pools_chain_by_chain_and_judges_the_pool(road):
    emu, x, y, src = road
    plain = _calibrate(emu, x, y, n_samples=300, seed=2, init=src)
    pooled = _calibrate(emu, x, y, n_samples=300, seed=2, init=src, append=True)
    np.testing.assert_array_equal(pooled.chains["GD"][:, :500], src.chains["GD"])
    np.testing.assert_array_equal(pooled.chains["GD"][:, 500:], plain.chains["GD"])
    assert pooled.samples["lamOs"].size == 800
    info = pooled.info
    assert (info["appended_after"], info["pooled_sweeps"], info["sweeps_run"]) == (500, 800, 900)
    assert info["appended_to"] == chains_sha256(src)
    assert info["convergence"]["n_draws"] == 800  # judged over the pooled chain
    ess = np.ravel(info["diagnostics"]["GD"]["ess"])[0]
    assert ess == pytest.approx(pooled.summary()["GD"]["ess"])
    want = np.array(src.info["accept_rate"]) * 600 + np.array(plain.info["accept_rate"]) * 300
    np.testing.assert_allclose(info["accept_rate"], want / 900)
    again = _calibrate(emu, x, y, n_samples=300, seed=2, init=src, append=True)
    np.testing.assert_array_equal(again.chains["GD"], pooled.chains["GD"])  # seeded


def test_two_chains_and_emulator_draws_append():
    emu, (x, y) = with_draws(road_emulator()), road_obs()
    src = _calibrate(emu, x, y, n_samples=200, n_burn=50, seed=3, n_chains=2, n_jobs=1,
                     emulator_params="draws")  # fmt: skip
    out = _calibrate(emu, x, y, n_samples=100, seed=4, n_chains=2, n_jobs=1, init=src,
                     emulator_params="draws", append=True)  # fmt: skip
    assert out.chains["GD"].shape == (2, 250)
    np.testing.assert_array_equal(out.chains["lamOs"][:, :150], src.chains["lamOs"])
    drawn = out.info["emulator_draws"].reshape(2, 250)
    np.testing.assert_array_equal(drawn[:, :150], src.info["emulator_draws"].reshape(2, 150))
    with pytest.raises(gpmsa.GPMSAError, match="n_chains=2"):
        _calibrate(emu, x, y, n_samples=100, init=src, emulator_params="draws")
    with pytest.raises(gpmsa.GPMSAError, match="n_emulator_draws: 20 there, 3 here"):
        _calibrate(emu, x, y, n_samples=100, n_chains=2, init=src, emulator_params="draws",
                   n_emulator_draws=3)  # fmt: skip


def test_what_differs_is_refused_by_name(road):
    emu, x, y, src = road
    cases = [
        ({"y_obs": [[y[0][0] + 1.0]]}, "other observations \\(observations: "),
        ({"emulator": emu.with_calibration_priors(theta_sd=0.5)}, "other emulator \\(emulator: "),
        ({"constraint": lambda t: True}, "theta constraint: False there, True here"),
        ({"fixed": {"lamOs": 100.0}}, "fixed parameters: None there"),
        ({"theta_init": [1.0]}, "leave theta_init out"),
        ({"fast": False}, "ran on the fast numpy sampler"),
        ({"append": True, "tune": True}, "pass tune=False"),
        ({"append": True, "n_burn": 10}, "n_burn must be 0 or None"),
    ]
    for extra, match in cases:
        kw = {"emulator": emu, "x_obs": x, "y_obs": y, "n_samples": 50, "init": src, **extra}
        with pytest.raises(gpmsa.GPMSAError, match=match):
            _calibrate(**kw)
    for init, match in ((emu, "gpmsa.fit\\(\\.\\.\\., init=emulator\\)"),
                        (src.to_arviz(), "keep the Posterior itself")):  # fmt: skip
        with pytest.raises(gpmsa.GPMSAError, match=match):
            _calibrate(emu, x, y, n_samples=50, init=init)
    with pytest.raises(gpmsa.GPMSAError, match="pass init=that posterior"):
        _calibrate(emu, x, y, n_samples=50, append=True)


def test_held_values_must_match_and_stay_held():
    emu = two_param_emulator()
    src = _calibrate(emu, X2, Y2, n_samples=200, n_burn=20, seed=7, fixed={"theta": {"a": 0.4}})
    with pytest.raises(gpmsa.GPMSAError, match="fixed parameters"):
        _calibrate(emu, X2, Y2, n_samples=50, init=src, fixed={"theta": {"a": 0.5}})
    out = _calibrate(emu, X2, Y2, n_samples=100, seed=8, init=src, append=True,
                     fixed={"theta": {"a": 0.4}})  # fmt: skip
    assert np.all(out.samples["a"] == 0.4) and out.samples["b"].size == 280
    assert out.summary()["a"]["held"]


def test_a_pickled_posterior_continues(road):
    emu, x, y, src = road
    back = pickle.loads(pickle.dumps(src))
    a = _calibrate(emu, x, y, n_samples=60, seed=5, init=back)
    b = _calibrate(emu, x, y, n_samples=60, seed=5, init=src)
    np.testing.assert_array_equal(a.chains["GD"], b.chains["GD"])


def test_backend_and_tempered_continuations():
    emu, (x, y) = road_emulator(), road_obs()
    src = _calibrate(emu, x, y, n_samples=100, n_burn=20, seed=8, fast=False, tune_rounds=5)
    more = _calibrate(emu, x, y, n_samples=60, seed=9, init=src, append=True)  # its engine
    assert more.info["engine"] == "backend" and more.info["tune"] is False
    assert more.chains["GD"].shape == (1, 140)
    assert more.info["step_widths"]["theta"] == src.info["step_widths"]["theta"]
    hot = _calibrate(emu, x, y, n_samples=60, n_burn=10, seed=8, fast=False, tune_rounds=3,
                     temperatures=2)  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match="tempered continuation"):
        _calibrate(emu, x, y, n_samples=40, init=hot, tune=False)
    warm = _calibrate(emu, x, y, n_samples=40, seed=9, init=hot, tune_rounds=3)
    assert warm.info["temperatures"] == [1.0, 2.0] and warm.info["tune"] is True
    cold = _calibrate(emu, x, y, n_samples=40, seed=9, init=hot, temperatures=None)
    assert "temperatures" not in cold.info and cold.info["tune"] is False


def test_the_convergence_warning_advises_init():
    emu, (x, y) = road_emulator(), road_obs()
    with pytest.warns(gpmsa.ConvergenceWarning, match="init=the returned posterior\\)"):
        gpmsa.calibrate(emu, x, y, n_samples=30, n_burn=0, seed=1, tune=False)


def test_a_categorical_theta_continues_at_its_levels():
    rng = np.random.default_rng(2)
    x, kind = rng.random((45, 1)), np.arange(45) % 3
    sim = gpmsa.SimData(x, np.column_stack([rng.random(45), kind]),
                        np.sin(3 * x[:, 0]) + 0.5 * kind, x_names=["s"], t_names=["k", "kind"],
                        t_categorical=["kind"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = np.sin(3 * xo[:, 0]) + 0.5
    src = _calibrate(emu, xo, yo, n_samples=200, n_burn=50, seed=5)
    out = _calibrate(emu, xo, yo, n_samples=100, seed=6, init=src, append=True)
    assert set(np.unique(out.samples["kind"])) <= {0.0, 1.0, 2.0}
    np.testing.assert_array_equal(out.chains["kind"][:, :150], src.chains["kind"])
