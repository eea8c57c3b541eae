"""gpmsa.Calibrator: the exact grid path against MCMC, references, and its contract."""

import tracemalloc
import warnings

import numpy as np
import pytest
from _calib_cases import (
    road_case,
    road_emulator,
    road_obs,
    two_param_emulator,
    vector_emulator,
    with_draws,
)

import gpmsa
import gpmsa.calibration.calibrator as calibrator
from gpmsa import Calibrator, GPMSAError, calibrate
from gpmsa.calibration.posterior import trapezoid_weights
from gpmsa.mcmc.diagnostics import ess
from tests.gpmsa._emulator_edit import replaced


def kurtosis(post, name):
    g = post.grids[name]
    d = g.nodes - g.mean()
    w = g.weights * g.density
    return float(w @ d**4) / float(w @ d**2) ** 2


def mc_tolerance(post, name, n_eff, k=4.0):
    """k Monte-Carlo standard errors of a mean and an sd estimated from n_eff effective draws."""
    sd = post.sd(name)
    return k * sd / np.sqrt(n_eff), k * sd * np.sqrt((kurtosis(post, name) - 1) / (4 * n_eff))


@pytest.fixture(scope="module")
def road_grid():
    x, y = road_obs()
    return Calibrator(road_emulator(), seed=0).update(x, y)


def test_road_case_matches_sepia_calibration_only(road_grid):
    """GD mean and sd within Monte-Carlo error of SEPIA's 4,000-draw run (ESS 947)."""
    ref = road_case()["sepia_calibration_only"]
    tol_mean, tol_sd = mc_tolerance(road_grid, "GD", ref["ess"], k=3.0)
    assert abs(road_grid.mean("GD") - ref["mean"]) < tol_mean
    assert abs(road_grid.sd("GD") - ref["sd"]) < tol_sd
    for q in (0.05, 0.5, 0.95):
        assert abs(road_grid.quantile("GD", q) - ref["quantiles"][str(q)]) < 3.5 * tol_mean


def test_grid_agrees_with_fast_mcmc(road_grid):
    x, y = road_obs()
    mc = calibrate(road_emulator(), x, y, n_samples=41_000, n_burn=1000, seed=3)
    n_eff = ess(mc.chains["GD"])
    tol_mean, tol_sd = mc_tolerance(road_grid, "GD", n_eff)
    assert abs(mc.mean("GD") - road_grid.mean("GD")) < tol_mean
    assert abs(mc.sd("GD") - road_grid.sd("GD")) < tol_sd
    assert abs(mc.prob_above("GD", 450) - road_grid.prob_above("GD", 450)) < 4 * np.sqrt(
        0.25 / n_eff
    )
    for q in (0.1, 0.5, 0.9):  # lamOs draws of the grid posterior (from its conditional)
        lam_grid = np.quantile(road_grid.samples["lamOs"], q)
        assert np.quantile(mc.samples["lamOs"], q) == pytest.approx(lam_grid, rel=0.1)


def test_grid_agrees_with_generic_numpy_backend(road_grid):
    x, y = road_obs()
    mc = calibrate(road_emulator(), x, y, n_samples=4000, n_burn=500, seed=4, fast=False)
    assert mc.info["engine"] == "backend"
    tol_mean, tol_sd = mc_tolerance(road_grid, "GD", ess(mc.chains["GD"]))
    assert abs(mc.mean("GD") - road_grid.mean("GD")) < tol_mean
    assert abs(mc.sd("GD") - road_grid.sd("GD")) < tol_sd


@pytest.mark.slow
def test_grid_within_one_percent_of_a_200k_mcmc(road_grid):
    x, y = road_obs()
    mc = calibrate(road_emulator(), x, y, n_samples=201_000, n_burn=1000, seed=5)
    assert abs(mc.mean("GD") / road_grid.mean("GD") - 1) < 0.01
    assert abs(mc.sd("GD") / road_grid.sd("GD") - 1) < 0.01


def test_update_posterior_contract(road_grid):
    post = road_grid
    assert post.names == ("GD", "lamOs")
    assert post.info["method"] == "grid" and not post.info["refined"]
    s = post.samples
    assert s["GD"].shape == (4000,) and s["lamOs"].shape == (4000,)
    assert np.all((s["GD"] >= 200) & (s["GD"] <= 600)) and np.all(s["lamOs"] > 0)
    tol_mean = 4 * post.sd("GD") / np.sqrt(4000)
    assert abs(s["GD"].mean() - post.mean("GD")) < tol_mean
    lo, hi = post.interval("GD", 0.9)
    assert lo < post.quantile("GD", 0.5) < hi
    assert post.prob_above("GD", lo) == pytest.approx(0.95, abs=1e-9)
    again = Calibrator(road_emulator(), seed=0).update(*road_obs())
    np.testing.assert_array_equal(again.samples["GD"], s["GD"])  # seeded draws


def test_log_likelihood_grid_is_fixed_documented_and_additive():
    emu = road_emulator()
    cal = Calibrator(emu)
    grid, ll = cal.log_likelihood_grid([[1.0]], [[8.0]])
    lo, hi = emu.domain["GD"]
    np.testing.assert_allclose(grid, np.linspace(lo, hi, 129))
    assert ll.shape == (129,) and np.all(np.isfinite(ll))
    grid2, ll2 = cal.log_likelihood_grid([[1.6]], [[15.0]])
    np.testing.assert_array_equal(grid, grid2)
    # two windows as one update with a prior = the first window's likelihood
    post_seq = cal.update([[1.6]], [[15.0]], prior=ll)
    post_cb = cal.update([[1.6]], [[15.0]], prior=lambda gd: np.interp(gd, grid, ll))
    assert post_seq.mean("GD") == pytest.approx(post_cb.mean("GD"), rel=1e-9)
    w = np.exp(ll + ll2 - np.max(ll + ll2))
    w *= np.exp(-0.5 * ((cal._theta_unit[:, 0] - 0.5) / 10) ** 2)
    wt = trapezoid_weights(grid) * w
    assert post_seq.mean("GD") == pytest.approx(float(wt @ grid / wt.sum()), rel=1e-9)


def test_prior_moves_the_posterior():
    cal = Calibrator(road_emulator())
    x, y = road_obs()
    flat = cal.update(x, y)
    tilted = cal.update(x, y, prior=lambda gd: -0.5 * ((gd - 350.0) / 30.0) ** 2)
    assert tilted.mean("GD") < flat.mean("GD") - 20
    assert tilted.sd("GD") < flat.sd("GD")


def test_narrow_posterior_is_refined_and_matches_a_fine_grid():
    emu = road_emulator()
    rng = np.random.default_rng(0)
    v = np.linspace(0.6, 1.9, 40)[:, None]
    f = 0.02 * 410 * v**1.6 * (1 + 0.005 * rng.standard_normal(v.shape))
    post = Calibrator(emu).update(v, f)
    assert post.info["refined"]
    fine = Calibrator(emu, n_grid=4097).update(v, f)
    assert not fine.info["refined"]
    assert post.mean("GD") == pytest.approx(fine.mean("GD"), abs=1e-3 * post.sd("GD"))
    assert post.sd("GD") == pytest.approx(fine.sd("GD"), rel=2e-3)


@pytest.mark.parametrize(("n_obs", "n_samples", "chebyshev"), [(1, 10_000, True), (2, 2000, False)])
def test_two_parameters_grid_agrees_with_mcmc(n_obs, n_samples, chebyshev):
    emu = two_param_emulator()
    x = [[0.3], [0.7]][:n_obs]
    y = [[np.sin(0.6 + 0.6) + 0.8 * 0.6 * 0.3], [np.sin(1.4 + 0.6) + 0.8 * 0.6 * 0.7]][:n_obs]
    grid = Calibrator(emu).update(x, y)
    assert grid.names == ("a", "b", "lamOs")
    mc = calibrate(emu, x, y, n_samples=n_samples, n_burn=500, seed=1)
    assert mc.info["chebyshev"] is chebyshev
    for name in ("a", "b"):
        tol = 5 * grid.sd(name) / np.sqrt(ess(mc.chains[name]))
        assert abs(mc.mean(name) - grid.mean(name)) < tol


def test_vector_output_grid_agrees_with_mcmc():
    emu = vector_emulator()
    index = np.linspace(0, 1, 8)
    y = 1.55 * np.sin(np.pi * index * 0.9) + 0.3 * 0.55
    y = y + 0.01 * np.random.default_rng(0).standard_normal(8)
    grid = Calibrator(emu).update([[0.4]], [y])
    mc = calibrate(emu, [[0.4]], [y], n_samples=6000, n_burn=1000, seed=2)
    n_eff = ess(mc.chains["t"])
    assert abs(mc.mean("t") - grid.mean("t")) < 4 * grid.sd("t") / np.sqrt(n_eff)
    assert abs(mc.sd("t") / grid.sd("t") - 1) < 0.15


def test_emulator_draws_average_the_likelihood():
    emu = with_draws(road_emulator(), n=4)
    x, y = road_obs()
    cal = Calibrator(emu, emulator_params="draws")
    grid, ll = cal.log_likelihood_grid(x, y)
    singles = []
    for i in range(4):
        prm = {k: v[i] for k, v in emu.draws.items()}
        one = replaced(with_draws(road_emulator(), n=1), params=prm)
        singles.append(Calibrator(one).log_likelihood_grid(x, y)[1])
    expected = np.log(np.mean(np.exp(np.array(singles)), axis=0))
    np.testing.assert_allclose(ll, expected, rtol=0, atol=1e-9)
    post = cal.update(x, y)
    mc = calibrate(emu, x, y, emulator_params="draws", n_samples=21_000, seed=6)
    tol = 4 * post.sd("GD") / np.sqrt(ess(mc.chains["GD"]))
    assert abs(mc.mean("GD") - post.mean("GD")) < tol


def test_mcmc_method_and_auto():
    emu = road_emulator()
    cal = Calibrator(emu, method="mcmc", mcmc_options={"n_samples": 1500, "n_burn": 500})
    post = cal.update(*road_obs())
    assert post.info["method"] == "mcmc" and post.samples["GD"].shape == (1000,)
    assert Calibrator(emu).method == "grid"
    with pytest.raises(GPMSAError, match="no grid likelihood"):
        cal.log_likelihood_grid(*road_obs())


@pytest.mark.parametrize(
    ("x", "y", "match"),
    [
        ([[1.25]], [[np.nan]], r"y_obs must be finite, got nan at index \(0, 0\)"),
        ([[1.25]], [[np.inf]], "y_obs must be finite, got inf"),
        ([[np.nan]], [[12.0]], "x_obs must be finite"),
        ([[1.25, 3.0]], [[12.0]], r"x_obs must have shape \(n, 1\)"),
        ([[1.25]], [[12.0, 1.0]], r"y_obs must have shape \(n, 1\)"),
        ([[1.25], [1.5]], [[12.0], [1.0], [3.0]], "y_obs must have one row per x_obs row"),
        ([[3.0]], [[12.0]], r"x_obs v=3 lies outside the emulator's domain \[0.50"),
        ("fast", [[12.0]], "x_obs must be a numeric array, got str"),
        (
            [[1.25]],
            [[1e200]],
            r"y_obs lies 1.3e\+199 standard deviations .* allowed at most 1e\+06",
        ),
    ],
)
def test_bad_input_raises(x, y, match):
    cal = Calibrator(road_emulator())
    with pytest.raises(GPMSAError, match=match):
        cal.update(x, y)
    with pytest.raises(GPMSAError, match=match):
        cal.log_likelihood_grid(x, y)
    with pytest.raises(GPMSAError, match=match):
        calibrate(road_emulator(), x, y)


@pytest.mark.parametrize(
    ("x", "y", "match"),
    [(np.array([[1.25 + 0j]]), [[12.0]], "x_obs must hold real numbers, got complex values"),
     ([[1.25]], np.array([[12.0 + 1j]]), "y_obs must hold real numbers"),
     ([[1.25]], [[[12.0]]], r"y_obs must have shape \(n, 1\), got \(1, 1, 1\)"),
     ([[1.25], [1.5]], np.ones((2, 1, 1)), r"y_obs must have shape \(n, 1\)")],
)  # fmt: skip
def test_complex_or_3d_observations_are_refused(x, y, match):
    """A complex array was cast to its real part; a (1, 1, 1) y_obs was read as one value."""
    cal = Calibrator(road_emulator())
    with pytest.raises(GPMSAError, match=match):
        cal.update(x, y)
    with pytest.raises(GPMSAError, match=match):
        calibrate(road_emulator(), x, y, n_samples=10, n_burn=1)


def test_complex_prior_is_refused_on_the_grid():
    cal = Calibrator(road_emulator())
    with pytest.raises(GPMSAError, match="prior must hold real numbers"):
        cal.update(*road_obs(), prior=np.zeros(129, dtype=complex))
    with pytest.raises(GPMSAError, match=r"prior\(theta\) must hold real numbers"):
        cal.update(*road_obs(), prior=lambda gd: np.zeros(np.shape(gd), dtype=complex))


def test_huge_n_draws_is_refused_before_allocating():
    with pytest.raises(
        gpmsa.ResourceLimitError,
        match=r"Calibrator\(n_draws=1000000000000\).*gpmsa.limits.MAX_MEMORY_BYTES",
    ):
        Calibrator(road_emulator(), n_draws=10**12)


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"tune_rounds": 0}, r"tune_rounds must be an integer in \[1, 1000000\], got 0"),
     ({"tune_rounds": -1}, "tune_rounds must be an integer"),
     ({"tune_levels": 0}, r"tune_levels must be an integer in \[2, 1000\], got 0"),
     ({"tune_levels": 1}, "tune_levels must be an integer"),
     ({"tune_levels": 10**9}, "tune_levels must be an integer"),
     ({"tune_rounds": 10**9}, "tune_rounds must be an integer"),
     ({"tune_rounds": 1.5}, "tune_rounds must be an integer"),
     ({"tune_rounds": 10**4, "tune_levels": 1000}, "tuning sweeps per chain, above the most")],
)  # fmt: skip
def test_calibrate_tuning_options_are_bounded_counts(kw, match):
    """tune_rounds=10**9 hung; 0 rounds or levels left the widths untuned without a word."""
    for backend in ("numpy", "torch") if "torch" in gpmsa.backends.available() else ("numpy",):
        with pytest.raises(GPMSAError, match=match):
            calibrate(road_emulator(), *road_obs(), n_samples=50, n_burn=5, backend=backend, **kw)


def test_extrapolation_warns_when_allowed():
    cal = Calibrator(road_emulator(), extrapolate=True)
    with pytest.warns(UserWarning, match="outside the emulator's domain"):
        post = cal.update([[2.05]], [[25.0]])
    assert np.isfinite(post.mean("GD"))


def test_bad_settings_and_emulators():
    emu = road_emulator()
    with pytest.raises(GPMSAError, match="method must be one of"):
        Calibrator(emu, method="nuts")
    with pytest.raises(GPMSAError, match="emulator_params must be one of"):
        Calibrator(emu, emulator_params="mean")
    with pytest.raises(GPMSAError, match="needs retained draws"):
        Calibrator(emu, emulator_params="draws")
    with pytest.raises(GPMSAError, match="n_grid must be an integer >= 3"):
        Calibrator(emu, n_grid=2)
    with pytest.raises(GPMSAError, match=r"emulator lacks \['standardizer'"):
        Calibrator(object())
    cal = Calibrator(emu)
    with pytest.raises(GPMSAError, match=r"prior must be log densities on the Calibrator's grid"):
        cal.update(*road_obs(), prior=np.zeros(5))
    with pytest.raises(GPMSAError, match="must not be NaN"):
        cal.update(*road_obs(), prior=np.full(129, np.nan))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cal.update(*road_obs())  # valid input: no warning


@pytest.mark.filterwarnings("ignore::gpmsa.errors.OutsideEmulatorWarning")  # f spans far out
def test_evidence_is_a_normalised_density_of_the_observation():
    """exp(log_evidence) as a function of f_obs integrates to one: every normalising constant
    (theta prior, lamOs prior and its integral, the Gaussian) is accounted for."""
    emu = road_emulator()
    cal = Calibrator(emu)
    f = np.linspace(-60.0, 90.0, 1501)
    log_ev = np.array([cal.update([[1.25]], [[fi]]).info["log_evidence"] for fi in f])
    dens = np.exp(log_ev) / emu.standardizer.y_sd  # density of f (native) from that of u
    assert float(np.trapezoid(dens, f)) == pytest.approx(1.0, abs=1e-4)


def test_mcmc_with_extra_prior_matches_grid():
    emu = road_emulator()
    x, y = road_obs()

    def prior(gd):
        return -0.5 * ((np.asarray(gd) - 380.0) / 25.0) ** 2

    grid = Calibrator(emu).update(x, y, prior=prior)
    mc = calibrate(emu, x, y, log_prior=prior, n_samples=11_000, seed=8)
    tol_mean, tol_sd = mc_tolerance(grid, "GD", ess(mc.chains["GD"]))
    assert abs(mc.mean("GD") - grid.mean("GD")) < tol_mean
    assert abs(mc.sd("GD") - grid.sd("GD")) < tol_sd


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # 2 x 500 draws: R-hat ~1.01
def test_discrepancy_runs_on_the_backend_and_chains_pool():
    emu = road_emulator()
    x, y = [[1.0], [1.25], [1.5]], [[7.5], [12.1], [16.0]]
    post = calibrate(emu, x, y, discrepancy="constant", n_samples=600, n_burn=200, seed=1)
    assert post.names == ("GD", "lamOs", "betaV", "lamVz") and post.info["engine"] == "backend"
    assert np.all(np.isfinite(post.samples["betaV"])) and np.all(post.samples["lamVz"] > 0)
    with pytest.raises(GPMSAError, match="fast=True needs backend='numpy' and no discrepancy"):
        calibrate(emu, x, y, discrepancy="constant", fast=True)
    two = calibrate(emu, *road_obs(), n_chains=2, n_samples=800, n_burn=300, seed=2)
    assert two.chains["GD"].shape == (2, 500) and two.samples["GD"].shape == (1000,)
    assert "ess" in two.summary()["GD"]
    with pytest.raises(GPMSAError, match=r"n_burn must be an integer in \[0, n_samples - 1\)"):
        calibrate(emu, *road_obs(), n_samples=100, n_burn=100)
    with pytest.raises(GPMSAError, match="unknown backend 'jax'"):
        calibrate(emu, *road_obs(), backend="jax")


def test_two_parameter_gridded_prior_survives_refinement():
    emu = two_param_emulator()
    x = np.array([0.1, 0.3, 0.5, 0.7, 0.9])[:, None]
    y = np.sin(2 * x + 1.5 * 0.4) + 0.8 * 0.6 * x  # a = 0.4, b = 0.6
    cal = Calibrator(emu)
    flat = cal.update(x, y)
    assert flat.info["refined"]
    tilt = -0.5 * ((cal.theta_grid[:, 0] - 0.38) / 0.01) ** 2
    gridded = cal.update(x, y, prior=tilt)
    call = cal.update(x, y, prior=lambda t: -0.5 * ((t[:, 0] - 0.38) / 0.01) ** 2)
    assert gridded.info["refined"] and gridded.mean("a") < flat.mean("a") - flat.sd("a")
    assert gridded.mean("a") == pytest.approx(call.mean("a"), abs=0.1 * call.sd("a"))
    assert gridded.sd("a") == pytest.approx(call.sd("a"), rel=0.05)


def test_mcmc_options_are_checked_when_the_calibrator_is_made():
    """An unknown keyword used to fail only at the first update, as calibrate's TypeError."""
    emu = two_param_emulator()
    with pytest.raises(GPMSAError, match=r"mcmc_options: unknown keyword\(s\) \['n_sample'\]"):
        Calibrator(emu, method="mcmc", mcmc_options={"n_sample": 500})
    with pytest.raises(GPMSAError, match=r"unknown keyword\(s\) \['log_prior'\]"):
        Calibrator(emu, mcmc_options={"log_prior": None})  # the Calibrator passes its prior itself
    with pytest.raises(GPMSAError, match="mcmc_options must be None or a dict, got list"):
        Calibrator(emu, mcmc_options=[("n_samples", 500)])


@pytest.mark.parametrize("method", ["grid", "mcmc"])
def test_calib_a_refused_update_does_not_shift_the_next_draws(method):
    """A control loop's bad window (here NaN) is refused; it used to count as an update, so that
    every later default-seeded posterior's draws depended on how many windows had failed."""
    emu, (x, y) = road_emulator(), road_obs()
    opts = {"mcmc_options": {"n_samples": 300, "n_burn": 50}} if method == "mcmc" else {}
    clean, dirty = (Calibrator(emu, method=method, seed=4, **opts) for _ in range(2))
    with pytest.raises(GPMSAError, match="y_obs"):
        dirty.update(x, [[np.nan]])
    with pytest.raises(GPMSAError, match="prior"):
        dirty.update(x, y, prior=lambda t: np.full(t.shape, np.nan))
    for _ in range(2):
        a, b = clean.update(x, y).samples["GD"], dirty.update(x, y).samples["GD"]
        np.testing.assert_array_equal(a, b)


def _cached_bytes(cal: Calibrator) -> int:
    """Bytes of what a grid Calibrator keeps: Sigma_W's factors and the predictors' arrays."""
    preds = list(cal._predictors) + ([] if cal._refined is None else list(cal._refined[1]))
    kept = sum(p.rt_alpha.nbytes + sum(h.nbytes for h in p.H or []) for p in preds)
    return kept + sum(gp.chol.nbytes for gp in cal._gps)


def test_calibrator_memory_check_counts_every_parameter_set(monkeypatch):
    """Each grid predictor checked only its own memory, and the Calibrator's check left out
    their Chebyshev products H: 20 emulator parameter sets kept 41.6 MiB while no check saw
    more than 12.4 MiB, so a limit between the two passed (12 sets: 25 MiB). Now the whole
    is checked before anything is built, and the estimate is close (a limit 1.25x what is
    kept passes)."""
    emu = with_draws(vector_emulator(), 12)
    kw = {"emulator_params": "draws", "n_emulator_draws": 12}
    cached = _cached_bytes(Calibrator(emu, **kw))
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", int(0.9 * cached))
    with pytest.raises(
        gpmsa.ResourceLimitError, match=r"12 emulator parameter set\(s\), Chebyshev degree \d+"
    ):
        Calibrator(emu, **kw)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", int(1.25 * cached))
    assert _cached_bytes(Calibrator(emu, **kw)) == cached


def _checked_and_peak(monkeypatch, emu, **kw) -> tuple[float, int]:
    """The largest estimate Calibrator(emu, **kw) checked, and the peak memory it traced."""
    seen = []
    check = calibrator.check_memory
    monkeypatch.setattr(
        calibrator, "check_memory", lambda n, what: (seen.append(n), check(n, what))
    )
    tracemalloc.start()
    try:
        Calibrator(emu, **kw)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return max(seen), peak


def test_calibrator_memory_check_bounds_the_peak_of_building_the_predictors(monkeypatch):
    """The check bounds what the set-up needs at its peak: a two-component emulator's predictors
    kept one component's Chebyshev work arrays while the next one's were made (peak 1.17x the
    estimate), and predictors that solve densely (p > 1) needed R_t's correlation work arrays
    (1.44x)."""
    vec = vector_emulator()
    checked, peak = _checked_and_peak(monkeypatch, vec, n_grid=801)
    assert peak <= checked
    rng = np.random.default_rng(0)
    x, t = rng.random((60, 2)), rng.random(60)
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x[:, 0] + t) + x[:, 1])
    dense = gpmsa.Emulator.from_params(sim, {"betaU": [[2.0], [2.0], [2.0]], "lamUz": [1.0],
                                             "lamWs": [1e4], "lamWOs": [1e4]})  # fmt: skip
    checked, peak = _checked_and_peak(monkeypatch, dense, n_grid=4001)
    assert peak <= checked
