"""The full calibrated prediction: eta, delta and y at new x (SEPIA's full prediction)."""

import warnings

import numpy as np
import pytest
from _predict_cases import (
    GRID,
    T_TRUE,
    known_truth_case,
    known_truth_discrepancy,
    known_truth_sim,
    mc_z,
    vector_fit,
)
from scipy.linalg import block_diag

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model.correlation import correlation as R
from gpmsa.model.problem import reduce_obs
from gpmsa.predictive import full_prediction
from gpmsa.predictive._common import gp_factors
from gpmsa.predictive.full import _conditional


def _draw(emu, i):
    prm = {k: emu.draws[k][i] for k in ("betaU", "lamUz", "lamWs", "lamWOs")}
    cal = emu.calibration
    prm.update(theta=cal["theta"][i], lamOs=float(cal["lamOs"][i][0]),
               betaV=cal["betaV"][i].reshape(emu.p, -1),
               lamVz=np.ravel(cal["lamVz"][i]))  # fmt: skip
    return prm


def _dense_reference(emu, ob, prm, xn):
    """SEPIA's uvPred written out: one dense Gaussian over [v_obs; u_obs; w] and [v*; u*]."""
    n, N, pu, pv, m = ob.n, xn.shape[0], emu.p_u, ob.p_v, emu.m
    th = prm["theta"]
    xto, xtn = np.hstack([ob.x, np.tile(th, (n, 1))]), np.hstack([xn, np.tile(th, (N, 1))])
    bu, luz, lws = prm["betaU"], prm["lamUz"], prm["lamWs"]
    bv, lvz, groups = prm["betaV"], prm["lamVz"], ob.block_groups
    SV = [R(ob.x, None, bv[:, g]) / lvz[g] for g in groups]  # per basis vector, by its group
    SU = [R(xto, None, bu[:, j]) / luz[j] + np.eye(n) / lws[j] for j in range(pu)]
    nug = [1 / (emu.lam_sim[j] * prm["lamWOs"][0]) + 1 / lws[j] for j in range(pu)]
    SW = [R(emu.zt, None, bu[:, j]) / luz[j] + nug[j] * np.eye(m) for j in range(pu)]
    SUW = block_diag(*[R(xto, emu.zt, bu[:, j]) / luz[j] for j in range(pu)])
    o = n * pv
    dim = o + n * pu + m * pu
    sig = np.zeros((dim, dim))
    sig[:o, :o] = block_diag(*SV)
    sig[o : o + n * pu, o : o + n * pu] = block_diag(*SU)
    sig[o + n * pu :, o + n * pu :] = block_diag(*SW)
    sig[o : o + n * pu, o + n * pu :] = SUW
    sig[o + n * pu :, o : o + n * pu] = SUW.T
    sig[: n * (pv + pu), : n * (pv + pu)] += ob.sig_obs / prm["lamOs"]
    data = np.concatenate([ob.z, emu.w.T.reshape(-1)])
    pred = block_diag(*([R(xn, None, bv[:, g]) / lvz[g] for g in groups]
                        + [R(xtn, None, bu[:, j]) / luz[j] + np.eye(N) / lws[j]
                           for j in range(pu)]))  # fmt: skip
    cross = np.zeros((dim, N * (pv + pu)))
    cross[:o, : N * pv] = block_diag(*[R(ob.x, xn, bv[:, g]) / lvz[g] for g in groups])
    cross[o : o + n * pu, N * pv :] = block_diag(*[R(xto, xtn, bu[:, j]) / luz[j]
                                                   for j in range(pu)])  # fmt: skip
    cross[o + n * pu :, N * pv :] = block_diag(*[R(emu.zt, xtn, bu[:, j]) / luz[j]
                                                 for j in range(pu)])  # fmt: skip
    W = np.linalg.solve(sig, cross)
    return W.T @ data, pred - W.T @ cross


@pytest.mark.parametrize("groups", [None, [1, 0]])
def test_conditional_equals_the_dense_joint_gaussian(groups):
    """The two-step conditioning (on w, then on the reduced observations) equals conditioning
    on everything at once, as SEPIA's uvPred does; with two discrepancy precision groups each
    basis vector takes its own group's betaV column and lamVz."""
    emu, obs, *_ = known_truth_case()
    ob, _ = reduce_obs(obs, emu.standardizer, emu.K, "linear", emu.x_names, groups=groups)
    xn = np.array([[0.1], [0.45], [0.9]])
    for i in (0, emu.n_draws // 2, emu.n_draws - 1):
        prm = _draw(emu, i)
        if groups is not None:  # a second group of other correlation and precision
            prm["betaV"] = np.hstack([prm["betaV"], 3.0 * prm["betaV"]])
            prm["lamVz"] = np.concatenate([prm["lamVz"], 0.2 * prm["lamVz"]])
        mean, cov = _conditional(emu, ob, prm, gp_factors(emu, prm), xn, ob.p_v, False)
        ref_mean, ref_cov = _dense_reference(emu, ob, prm, xn)
        np.testing.assert_allclose(mean, ref_mean, atol=1e-10 * np.abs(ref_mean).max())
        np.testing.assert_allclose(cov, ref_cov, atol=1e-10 * np.abs(ref_cov).max())


def test_realizations_match_the_gaussian_moments_within_monte_carlo_error():
    emu, obs, x_new, _ = known_truth_case()
    pred = full_prediction(emu, obs, x_new[::6], n_draws=400, n_rlz=25, seed=5)
    assert pred.y.shape == (400 * 25, 10, GRID.size)
    for what in ("eta", "delta", "zeta", "y"):
        z_mean, z_var = mc_z(getattr(pred, what), pred.mean(what), pred.var(what))
        # 4 x 240 statistics: |z| < 4.9 fails by chance with probability < 1e-3 in all
        assert z_mean < 4.9 and z_var < 4.9, (what, z_mean, z_var)
    # the pieces add up, on the native and in the basis space
    np.testing.assert_allclose(pred.zeta, pred.eta + pred.delta)
    std = emu.standardizer
    np.testing.assert_allclose(pred.eta, pred.u @ emu.K.T * std.y_sd + std.y_mean, rtol=1e-12)
    assert pred.u.shape[-1] == emu.p_u and pred.v.shape[-1] == 2
    assert np.all(pred.var("y") > pred.var("zeta"))


def _coverage(seed: int) -> float:
    emu, obs, x_new, y_new = known_truth_case(seed)
    pred = full_prediction(emu, obs, x_new, n_rlz=2, seed=seed)
    lo, hi = pred.interval("y", 0.9)
    return float(np.mean((y_new >= lo) & (y_new <= hi)))


def test_y_band_covers_held_out_observations_at_the_nominal_rate():
    """One dataset: 60 held-out x x 12 outputs = 720 noisy observations of a known truth (a
    simulator at theta = 1.2 plus a discrepancy linear in the output index, noise sd 0.02).

    Tolerance: the binomial sd of 720 independent 90 % events is 0.011, but the elements of one
    dataset share its estimated noise level, theta and discrepancy: over 12 datasets
    (``-m slow`` below) the coverage had mean 0.890 and sd 0.028 between datasets. One dataset
    is accepted within 2.5 such sd of 0.9, i.e. [0.83, 0.97]."""
    assert 0.83 <= _coverage(0) <= 0.97


@pytest.mark.slow
def test_y_band_coverage_over_twelve_datasets():
    """12 independent datasets (each a fresh design, observations and held-out set): the mean
    coverage of the 90 % y band must be 0.9 within 3 standard errors of the mean over datasets
    (sd between datasets 0.028 measured, so 3 x 0.028 / sqrt(12) = 0.024; the pure binomial
    sd of the 8,640 pooled events would be 0.0032)."""
    cov = np.array([_coverage(seed) for seed in range(12)])
    assert abs(cov.mean() - 0.9) <= 3 * 0.028 / np.sqrt(12), cov
    assert cov.std(ddof=1) < 0.05, cov


def test_known_truth_pieces_are_recovered():
    """The prediction's real process zeta = eta + delta is close to the truth (within its band),
    and delta is close to the true discrepancy where theta is well determined."""
    emu, obs, x_new, _ = known_truth_case()
    pred = full_prediction(emu, obs, x_new, n_draws=300, seed=0)
    truth = known_truth_sim(x_new[:, 0], np.full(60, T_TRUE)) + known_truth_discrepancy(x_new[:, 0])
    err = np.abs(pred.mean("zeta") - truth)
    assert np.sqrt(np.mean(err**2)) < 0.01  # noise sd 0.02; 144 observed values
    lo, hi = pred.interval("zeta", 0.98)
    assert np.mean((truth >= lo) & (truth <= hi)) > 0.9


def test_posterior_path_scalar_output_and_grid_option():
    """A Posterior from gpmsa.calibrate with a constant discrepancy (scalar output), and the
    output grid option of a functional output."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(2 * x) + t, x_names=["x"], t_names=["t"])
    emu = gpmsa.fit(data, n_iter=200, seed=0, tune_rounds=10)
    xo = np.linspace(0.1, 0.9, 8)[:, None]
    obs = gpmsa.ObsData(x=xo, y=np.sin(2 * xo) + 0.5 + 0.01 * rng.standard_normal((8, 1)))
    post = gpmsa.calibrate(emu, xo, obs.y, n_samples=600, n_burn=100, seed=0,
                           discrepancy="constant", tune_rounds=10)  # fmt: skip
    pred = full_prediction(emu, obs, [[0.2], [0.6]], posterior=post, discrepancy="constant",
                           n_draws=200, n_rlz=4, seed=1)  # fmt: skip
    assert pred.y.shape == (800, 2, 1) and pred.p_v == 1
    np.testing.assert_allclose(pred.theta[:, 0], post.samples["t"][pred.draw_index])
    z_mean, z_var = mc_z(pred.y, pred.mean("y"), pred.var("y"))
    assert z_mean < 4.0 and z_var < 4.0, (z_mean, z_var)
    # the observations were made at theta + discrepancy = 0.5: eta + delta is close to it
    truth = np.sin(2 * np.array([0.2, 0.6])) + 0.5
    assert np.all(np.abs(pred.mean("zeta")[:, 0] - truth) < 3 * np.sqrt(pred.var("zeta")[:, 0]))
    assert post.info["discrepancy"] == "constant"  # the default reads it
    same = full_prediction(emu, obs, [[0.2], [0.6]], posterior=post, n_draws=200, n_rlz=4, seed=1)
    assert np.array_equal(same.y, pred.y)
    kept = {k: v for k, v in post.info.items() if k != "discrepancy"}
    old = gpmsa.Posterior(post.samples, info=kept)
    with pytest.raises(GPMSAError, match="pass the discrepancy basis.*not its kind"):
        full_prediction(emu, obs, [[0.2]], posterior=old)  # made before the kind was recorded
    with pytest.raises(GPMSAError, match="have discrepancy parameters"):
        full_prediction(emu, obs, [[0.2]], posterior=post, discrepancy=None)
    with pytest.raises(GPMSAError, match="no output grid"):
        full_prediction(emu, obs, [[0.2]], posterior=post, discrepancy="constant", grid=[0.5])
    # the posterior records its observations' values: other ones are refused, the same accepted
    assert post.info["obs_values_sha256"] == obs.values_digest()
    for other in (gpmsa.ObsData(x=xo, y=obs.y + 0.5), gpmsa.ObsData(x=xo[:5], y=obs.y[:5])):
        with pytest.raises(GPMSAError, match="obs holds other observations .* than the calib"):
            full_prediction(emu, other, [[0.2]], posterior=post, discrepancy="constant")
    reordered = gpmsa.ObsData(x=xo[::-1], y=obs.y[::-1])  # its rows are its experiments
    with pytest.raises(GPMSAError, match="its experiments in the same order"):
        full_prediction(emu, reordered, [[0.2]], posterior=post, discrepancy="constant")
    again = gpmsa.ObsData(x=xo.tolist(), y=obs.y[:, 0])  # other containers, the same values
    full_prediction(emu, again, [[0.2]], posterior=post, discrepancy="constant", n_draws=2)

    emu_v, obs_v, *_ = known_truth_case()
    fine = np.linspace(0.0, 1.0, 34)  # every third node is a node of GRID (12 nodes)
    pred = full_prediction(emu_v, obs_v, [[0.5]], n_draws=20, grid=fine, seed=0)
    coarse = full_prediction(emu_v, obs_v, [[0.5]], n_draws=20, seed=0)
    assert pred.eta.shape == (20, 1, 34) and pred.D.shape == (34, 2)
    np.testing.assert_allclose(pred.D[::3], coarse.D, rtol=1e-12)
    for what in ("eta", "delta", "y"):
        np.testing.assert_allclose(pred.mean(what)[:, ::3], coarse.mean(what), rtol=1e-12)
    bare = gpmsa.calibrate(emu_v, obs_v, n_samples=50, n_burn=10, seed=0)  # no discrepancy
    with pytest.raises(GPMSAError, match=r"lack discrepancy .*=an array of shape \(12, 2\) gives"):
        full_prediction(emu_v, obs_v, [[0.5]], posterior=bare, discrepancy=np.ones((12, 2)))


# --- bad input ---------------------------------------------------------------------------------
def test_bad_input_names_the_problem():
    emu, obs, *_ = known_truth_case()
    with pytest.raises(GPMSAError, match="needs calibration draws"):
        full_prediction(vector_fit(), obs, [[0.5]])
    with pytest.raises(GPMSAError, match="obs must be the gpmsa.ObsData"):
        full_prediction(emu, (obs.x, obs.y), [[0.5]])
    with pytest.raises(GPMSAError, match=r"discrepancy=None differs from the joint fit's"):
        full_prediction(emu, obs, [[0.5]], discrepancy=None)
    with pytest.raises(GPMSAError, match=r"x reaches .* by more than 10%"):
        full_prediction(emu, obs, [[1.5]])
    with pytest.warns(UserWarning, match="outside the emulator's domain"):
        full_prediction(emu, obs, [[1.03]], n_draws=2)
    with pytest.raises(GPMSAError, match="x must have 1 columns"):
        full_prediction(emu, obs, [[0.5, 0.5]])
    with pytest.raises(GPMSAError, match="grid must be non-empty and lie within"):
        full_prediction(emu, obs, [[0.5]], grid=[-1.0, 0.5])
    with pytest.raises(GPMSAError, match=r"grid must be one row of output-grid points, got shape"):
        full_prediction(emu, obs, [[0.5]], grid=[[0.1, 0.2], [0.3, 0.4]])  # was flattened
    with pytest.raises(GPMSAError, match="what must be one of"):
        full_prediction(emu, obs, [[0.5]], n_draws=2).mean("ysim")
    with pytest.raises(GPMSAError, match="posterior must be a gpmsa.Posterior"):
        full_prediction(emu, obs, [[0.5]], posterior={"t": [1.0]}, discrepancy="linear")


def test_discrepancy_and_obs_must_be_the_joint_fits():
    """docs/prediction.md: a discrepancy other than the fit's is an error; so is other data."""
    emu, obs, *_ = known_truth_case()
    assert emu.settings["discrepancy"] == "linear" and emu.settings["obs_lengths"] == [12] * 12
    with pytest.raises(GPMSAError, match=r"discrepancy='constant' differs from the joint fit's "
                                         r"discrepancy \('linear'\)"):  # fmt: skip
        full_prediction(emu, obs, [[0.5]], discrepancy="constant")
    with pytest.raises(GPMSAError, match=r"discrepancy=an array differs from the joint fit's"):
        full_prediction(emu, obs, [[0.5]], discrepancy=np.ones((GRID.size, 1)))
    fewer = gpmsa.ObsData(x=obs.x[:3], y=obs.y[:3], index=GRID)
    with pytest.raises(GPMSAError, match=r"obs has 3 experiment\(s\) of lengths \[12, 12, 12\], "
                                         r"but the joint fit's had 12"):  # fmt: skip
        full_prediction(emu, fewer, [[0.5]])
    shorter = gpmsa.ObsData(x=obs.x, y=obs.y[:, ::2], index=GRID[::2])
    with pytest.raises(GPMSAError, match="pass the ObsData the fit used"):
        full_prediction(emu, shorter, [[0.5]])
    # the same shapes, other values: the fit's digest of its observations tells them apart
    others = (gpmsa.ObsData(x=obs.x, y=obs.y + 3.0, index=GRID),
              gpmsa.ObsData(x=obs.x, y=obs.y, index=0.5 * GRID),
              gpmsa.ObsData(x=obs.x, y=obs.y, index=GRID, precision=4.0))  # fmt: skip
    for other in others:
        with pytest.raises(GPMSAError, match="obs holds other observations .* than the joint"):
            full_prediction(emu, other, [[0.5]])
    reordered = gpmsa.ObsData(x=obs.x[::-1], y=obs.y[::-1], index=GRID)
    with pytest.raises(GPMSAError, match=r"the fit used \(its experiments in the same order\)"):
        full_prediction(emu, reordered, [[0.5]])
    again = gpmsa.ObsData(x=obs.x.copy(), y=np.array(obs.y), index=GRID.copy())
    assert again.digest() == obs.digest() == emu.settings["obs_sha256"]
    same = full_prediction(emu, obs, [[0.5]], discrepancy="linear", n_draws=2, seed=0)
    default = full_prediction(emu, obs, [[0.5]], n_draws=2, seed=0)
    np.testing.assert_array_equal(same.y, default.y)
    # the joint fit's draws passed as posterior= (calibration_posterior) carry the same record:
    # other observations were accepted there without a check
    post = gpmsa.calibration_posterior(emu)
    assert post.info["obs_sha256"] == emu.settings["obs_sha256"]
    for other in (*others, fewer):
        with pytest.raises(GPMSAError, match="pass the ObsData the fit used"):
            full_prediction(emu, other, [[0.5]], posterior=post, discrepancy="linear")
    assert full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy="linear",
                           n_draws=2, seed=0).y.shape[1:] == default.y.shape[1:]  # fmt: skip


def test_huge_realization_counts_are_refused_before_allocating():
    emu, obs, *_ = known_truth_case()
    with pytest.raises(gpmsa.ResourceLimitError, match=r"full_prediction\(n_rlz=1000000000\) "
                       r"at 1 points .*gpmsa.limits.MAX_MEMORY_BYTES"):  # fmt: skip
        full_prediction(emu, obs, [[0.5]], n_rlz=10**9)
    with pytest.raises(GPMSAError, match="grid must be a numeric array"):
        full_prediction(emu, obs, [[0.5]], grid=["a"])


def test_an_array_discrepancy_basis_must_be_given_again():
    emu, obs, *_ = known_truth_case()
    D = np.column_stack([np.ones(GRID.size), GRID])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu_d = gpmsa.fit(emu_data(emu), obs, n_iter=30, tune=False, seed=0, discrepancy=D)
    with pytest.raises(GPMSAError, match="pass it again as discrepancy="):
        full_prediction(emu_d, obs, [[0.5]])
    pred = full_prediction(emu_d, obs, [[0.5]], discrepancy=D, n_draws=3, seed=0)
    assert pred.D.shape == (GRID.size, 2)
    with pytest.raises(GPMSAError, match="known on the observations' grid only"):
        full_prediction(emu_d, obs, [[0.5]], discrepancy=D, grid=GRID[:5])


def emu_data(emu) -> gpmsa.SimData:
    std = emu.standardizer
    return gpmsa.SimData(x=std.x_from_unit(emu.x_unit), t=std.t_from_unit(emu.t_unit), y=emu.y,
                         index=emu.index, x_names=["x"], t_names=["t"])  # fmt: skip


def test_a_studys_pooled_posterior_is_refused_pointing_to_member_posterior():
    """A study's pooled posterior names each model's parameters "t[model]": full_prediction and
    calibrated_predict point to ``study.member_posterior(model)`` rather than only listing the
    names it lacks."""
    emu, obs, *_ = known_truth_case()
    draws = {"t[m0]": np.full(4, 1.2), "t[m1]": np.full(4, 1.1)}
    pooled = gpmsa.Posterior({**draws, "lamOs[m0]": np.ones(4), "lamOs[m1]": np.ones(4)})
    hint = r"lacks \['t', 'lamOs'\].*study.member_posterior\(model\)"
    with pytest.raises(GPMSAError, match=hint):
        full_prediction(emu, obs, [[0.5]], posterior=pooled, discrepancy=None)
    with pytest.raises(GPMSAError, match=r"lacks \['t'\].*study.member_posterior\(model\)"):
        gpmsa.predictive.calibrated_predict(emu, pooled, [[0.5]])
    with pytest.raises(GPMSAError, match=r"posterior lacks \['t', 'lamOs'\]; it has \('s',\)$"):
        full_prediction(emu, obs, [[0.5]], posterior=gpmsa.Posterior({"s": np.ones(4)}),
                        discrepancy=None)  # fmt: skip
