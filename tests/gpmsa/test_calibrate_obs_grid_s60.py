"""Calibration with a fixed emulator of observations on their own index grids, with their own
precisions (a ``gpmsa.ObsData`` given to ``calibrate``, ``Calibrator`` and ``calibrate_study``),
as SEPIA's y_ind_obs: checked against the un-reduced likelihood, the arrays' draws and every
backend; the predictions conditioned on it refuse the same values placed otherwise."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, vector_emulator
from scipy.special import logsumexp

import gpmsa
from gpmsa.calibration.observations import fixed_gp
from gpmsa.errors import GPMSAError
from gpmsa.model.basis import interpolate_basis

T_TRUE = 0.4
GRID_A = np.linspace(0.05, 0.95, 23)
GRID_B = np.linspace(0.8, 0.1, 9)  # decreasing: any order is allowed


def vector_truth(x: np.ndarray, grid: np.ndarray, t: float = T_TRUE) -> np.ndarray:
    """The vector emulator's simulator (``_calib_cases.vector_emulator``) at (x, t) on ``grid``."""
    return (1.0 + t) * np.sin(np.pi * grid[None, :] * (0.5 + x[:, None])) + 0.3 * t


def ragged_obs(precision=None, noise: float = 0.02, seed: int = 0) -> gpmsa.ObsData:
    """Two experiments of the vector emulator on grids of 23 and 9 points, neither the
    simulation grid (8 points): the simulator's output interpolated linearly there (as the
    emulator's basis is), plus noise of sd ``noise``."""
    rng = np.random.default_rng(seed)
    x = np.array([0.3, 0.7])
    sim_grid = vector_emulator().standardizer.grid
    on_sim = vector_truth(x, sim_grid)
    ys = [np.interp(g, sim_grid, on_sim[k]) + noise * rng.standard_normal(g.size)
          for k, g in enumerate((GRID_A, GRID_B))]  # fmt: skip
    return gpmsa.ObsData(x[:, None], ys, index=[GRID_A, GRID_B], precision=precision)


def unreduced_log_posterior(emu, obs: gpmsa.ObsData, theta_unit: np.ndarray) -> np.ndarray:
    """log p(theta | y) (unnormalised) on unit-scale nodes (G,) from the full likelihood of
    every observed value on its own grid: y_std = sum_c K_c(grid) u_c + e, u the emulator's
    predictive at (x, theta), e ~ N(0, P^-1 / lamOs) (P the precision in standardised units,
    the identity where none is given), lamOs integrated against its Gamma prior on a fine log
    grid; times the emulator's theta prior. No GPM/SA reduction."""
    std, K = emu.standardizer, emu.K
    xu = std.x_to_unit(obs.x)
    mean, cov = fixed_gp(emu).predict(xu, theta_unit[:, None])  # (G, p_u, n), (G, p_u, n, n)
    bases = [interpolate_basis(K, std.grid, g) for g in obs.grids]
    y = np.concatenate(
        [(e - std.mean_on(g)) / std.y_sd for e, g in zip(obs.experiments, obs.grids, strict=True)]
    )
    L = y.size
    starts = np.cumsum([0] + [b.shape[0] for b in bases])
    B = np.zeros((L, K.shape[1], len(bases)))  # value <- (component, experiment)
    for j, b in enumerate(bases):
        B[starts[j] : starts[j + 1], :, j] = b
    prec = np.zeros((L, L))
    for j, b in enumerate(bases):
        block = np.eye(b.shape[0]) if obs.precisions is None else obs.precisions[j] * std.y_sd**2
        prec[starts[j] : starts[j + 1], starts[j] : starts[j + 1]] = block
    R = np.linalg.cholesky(prec).T  # prec = R^T R: R y has noise I / lamOs
    log_det_r = np.sum(np.log(np.diag(R)))
    Bf = B.reshape(L, -1)  # columns (component, experiment)
    lam = np.exp(np.linspace(np.log(1e-4), np.log(1e6), 6001))
    pri = emu.priors.lamOs
    log_prior_lam = (pri.a - 1) * np.log(lam) - pri.b * lam + np.log(lam)  # d log lamOs
    n_c, n_e = K.shape[1], len(bases)
    C = np.zeros((theta_unit.size, n_c * n_e, n_c * n_e))
    for c in range(n_c):
        sl = slice(c * n_e, (c + 1) * n_e)
        C[:, sl, sl] = cov[:, c]
    A = R @ Bf
    Cw = A @ C @ A.T  # (G, L, L), of rank n_c * n_e at most
    ev, V = np.linalg.eigh(0.5 * (Cw + np.swapaxes(Cw, 1, 2)))
    resid = R @ (y[None, :] - mean.reshape(theta_unit.size, -1) @ Bf.T).T  # (L, G)
    r2 = np.einsum("gij,ig->gj", V, resid) ** 2  # (G, L)
    # the eigenvalues beyond that rank are rounding (~1e-16 of the largest): directions of the
    # noise alone (variance 1 / lamOs), summed in closed form; eigh puts them first
    null = ev <= 1e-10 * ev.max(axis=1, keepdims=True)
    k = int((~null).sum(axis=1).max())
    n_null, r2_null = null[:, :-k].sum(axis=1), np.where(null, r2, 0.0).sum(axis=1)
    ev, r2 = (np.where(null, 0.0, v)[:, -k:] for v in (ev, r2))  # a null one: 1 / lamOs
    out = np.empty(theta_unit.size)
    for g in range(0, theta_unit.size, 64):  # 64 nodes at a time: (64, 6001) arrays
        sl = slice(g, g + 64)
        ll = r2_null[sl, None] * lam - n_null[sl, None] * np.log(lam)
        for j in range(k):
            var = ev[sl, j, None] + 1.0 / lam
            ll += np.log(var) + r2[sl, j, None] / var
        out[sl] = logsumexp(log_det_r - 0.5 * ll + log_prior_lam, axis=1)
    mu, sd = (float(np.ravel(v)[0]) for v in (emu.priors.theta_mean, emu.priors.theta_sd))
    return out - 0.5 * ((theta_unit - mu) / sd) ** 2


def reference_summaries(emu, obs) -> dict[str, float]:
    """Mean, sd and quantiles of theta (native) from `unreduced_log_posterior` on a fine grid
    over its mass (where a coarse grid's log density is within 40 of its peak)."""
    coarse = np.linspace(0.0, 1.0, 401)
    lp = unreduced_log_posterior(emu, obs, coarse)
    mass = coarse[lp > lp.max() - 40.0]
    fine = np.linspace(max(0.0, mass[0] - 0.0025), min(1.0, mass[-1] + 0.0025), 2001)
    lp = unreduced_log_posterior(emu, obs, fine)
    w = np.exp(lp - lp.max())
    w /= w.sum()
    t = emu.standardizer.t_from_unit(fine[:, None])[:, 0]
    mean = float(w @ t)
    sd = float(np.sqrt(w @ (t - mean) ** 2))
    cdf = np.cumsum(w)
    q = {p: float(np.interp(p, cdf, t)) for p in (0.05, 0.5, 0.95)}
    return {"mean": mean, "sd": sd, **q}


@pytest.mark.parametrize(
    "precision",
    [None, [1e4, 2.5e3], [np.diag(np.linspace(1e3, 4e3, 23)), 0.5e4 * np.eye(9)]],
    ids=["none", "scalars", "matrices"],
)
# the emulator's 2 components leave part of the output unexplained on GRID_B's part of the
# range: 5.0 predictive sds without precisions, a right warning that is not checked here
@pytest.mark.filterwarnings("ignore::gpmsa.OutsideEmulatorWarning")
def test_calibrator_on_own_grids_matches_the_unreduced_likelihood(precision):
    """The Calibrator's grid posterior of ObsData on ragged grids of their own (23 and 9
    points, one decreasing, against a simulation grid of 8) equals the posterior of the full
    likelihood of every observed value, no reduction, to a small fraction of an sd."""
    emu = vector_emulator()
    obs = ragged_obs(precision)
    ref = reference_summaries(emu, obs)
    post = gpmsa.Calibrator(emu).update(obs)
    sd = ref["sd"]
    assert abs(post.mean("t") - ref["mean"]) < 0.02 * sd
    assert abs(post.sd("t") / sd - 1.0) < 0.02
    for p in (0.05, 0.5, 0.95):
        assert abs(float(post.quantile("t", p)) - ref[p]) < 0.03 * sd


def test_the_posterior_depends_on_the_index_given():
    """The same values placed on grids 10 % shorter give another posterior (the index is
    used, not dropped): they misfit there, so lamOs falls and theta widens."""
    emu = vector_emulator()
    obs = ragged_obs([1e4, 2.5e3])
    shifted = gpmsa.ObsData(obs.x, obs.experiments, index=[GRID_A * 0.9, GRID_B * 0.9],
                            precision=[1e4, 2.5e3])  # fmt: skip
    a = gpmsa.Calibrator(emu).update(obs)
    with pytest.warns(gpmsa.OutsideEmulatorWarning):
        b = gpmsa.Calibrator(emu).update(shifted)
    assert abs(a.mean("t") - T_TRUE) < 4 * a.sd("t")
    assert b.mean("lamOs") < a.mean("lamOs") / 5  # the values misfit there
    assert b.sd("t") > 2 * a.sd("t")


def test_obsdata_on_the_simulation_grid_gives_the_arrays_draws():
    """An ObsData without index or precision is the arrays (x_obs, y_obs): the same draws from
    the fast and the generic numpy sampler, with a discrepancy, and the same grid posterior;
    an index equal to the simulation grid is the same too."""
    emu = vector_emulator()
    grid = emu.standardizer.grid
    x = np.array([[0.3], [0.7]])
    y = vector_truth(x[:, 0], grid) + 0.01 * np.random.default_rng(1).standard_normal((2, 8))
    kw = {"n_samples": 300, "n_burn": 50, "seed": 3}
    for extra in ({}, {"fast": False}, {"discrepancy": "constant"}):
        a = gpmsa.calibrate(emu, x, y, **kw, **extra)
        for obs in (gpmsa.ObsData(x, y), gpmsa.ObsData(x, y, index=grid)):
            b = gpmsa.calibrate(emu, obs, **kw, **extra)
            for name in a.names:
                np.testing.assert_array_equal(a.samples[name], b.samples[name])
            assert a.info["obs_values_sha256"] == b.info["obs_values_sha256"]
            assert a.info["obs_layout_sha256"] == b.info["obs_layout_sha256"]
    ga = gpmsa.Calibrator(emu).update(x, y)
    gb = gpmsa.Calibrator(emu).update(y_obs=gpmsa.ObsData(x, y))
    assert ga.mean("t") == gb.mean("t") and ga.sd("t") == gb.sd("t")


@pytest.mark.parametrize(
    ("sampler", "opts"),
    [
        ("numpy", {}),
        ("numpy-generic", {"fast": False}),
        # 10 tuning rounds, not the 50 of one chain's default: 3.5 s, not 6.5 s; over seeds
        # 0-11 the mean within 0.09 sd of the exact one, the sd within 7 %, ESS 340-560
        ("torch", {"backend": "torch", "tune_rounds": 10}),
    ],
    ids=["numpy", "numpy-generic", "torch"],
)  # fmt: skip
def test_every_sampler_agrees_with_the_grid_on_own_grids(sampler, opts):
    """calibrate's samplers on ragged grids with precisions: within Monte-Carlo error of the
    exact grid posterior (the fast numpy sampler, the generic one, torch). Equal precisions
    would move the exact mean by 0.32 sd."""
    if sampler == "torch":
        pytest.importorskip("torch")
    emu = vector_emulator()
    obs = ragged_obs([1e4, 2.5e3])
    exact = gpmsa.Calibrator(emu).update(obs)
    post = gpmsa.calibrate(emu, obs, n_samples=2000, n_burn=200, seed=5, **opts)
    assert abs(post.mean("t") - exact.mean("t")) < 0.25 * exact.sd("t")
    assert abs(post.sd("t") / exact.sd("t") - 1.0) < 0.25


def test_full_prediction_conditions_on_the_calibrated_layout_and_refuses_another():
    """full_prediction(posterior=) of a calibration on own grids takes that ObsData; the same
    values on other grids, with other precisions, or as the arrays on the simulation grid are
    refused, naming the layout. The Calibrator's posterior records the same digests."""
    emu = vector_emulator()
    obs = ragged_obs([1e4, 2.5e3])
    post = gpmsa.calibrate(emu, obs, n_samples=300, n_burn=50, seed=2)
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy=None, seed=0)
    assert pred.y.shape[1:] == (1, emu.l_sim)
    others = [
        gpmsa.ObsData(obs.x, obs.experiments, index=[GRID_A, GRID_B * 0.99],
                      precision=[1e4, 2.5e3]),
        gpmsa.ObsData(obs.x, obs.experiments, index=[GRID_A, GRID_B], precision=[1e4, 1e3]),
        gpmsa.ObsData(obs.x, obs.experiments, index=[GRID_A, GRID_B]),
    ]  # fmt: skip
    for other in others:
        with pytest.raises(GPMSAError, match="other index grids or gives them other precisions"):
            gpmsa.full_prediction(emu, other, [[0.5]], posterior=post, discrepancy=None)
    grid_post = gpmsa.Calibrator(emu).update(obs)
    for key in ("obs_values_sha256", "obs_layout_sha256"):
        assert grid_post.info[key] == post.info[key]


def test_a_scalar_output_takes_precisions_and_refuses_an_index():
    """A scalar output: per-experiment precisions weight the observations as the unreduced
    likelihood does (a precision 4x another halves that value's noise sd); an index other than
    its one point is refused (as gpmsa.fit refuses it), as is more than one value per
    experiment."""
    emu = road_emulator()
    x, y = road_obs()
    xs, ys = [x[0], [1.5]], [y[0], [y[0][0] * 1.1]]
    obs = gpmsa.ObsData(xs, ys, precision=[4e3, 1e3])
    ref = reference_summaries(emu, obs)
    post = gpmsa.Calibrator(emu).update(obs)
    assert abs(post.mean("GD") - ref["mean"]) < 0.02 * ref["sd"]
    assert abs(post.sd("GD") / ref["sd"] - 1.0) < 0.02
    with pytest.raises(GPMSAError, match="index of experiment 0 is 1, but the simulation output "
                                         "is scalar, one value at index 0"):  # fmt: skip
        gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, y, index=[1.0]))
    with pytest.raises(GPMSAError, match="each ObsData experiment needs one value, got 2"):
        gpmsa.calibrate(emu, gpmsa.ObsData(x, [[1.0, 2.0]]), n_samples=10, n_burn=0)


def test_an_obsdata_given_with_other_arrays_is_refused():
    """An ObsData holds x and y: given with y_obs (or x_obs) too, it is refused naming that;
    a study takes one ObsData per model with y_obs left out, and arrays need y_obs."""
    emu = vector_emulator()
    obs = ragged_obs()
    with pytest.raises(GPMSAError, match=r"x_obs is a gpmsa.ObsData, which holds both x and y"):
        gpmsa.calibrate(emu, obs, obs.experiments[0], n_samples=10, n_burn=0)
    with pytest.raises(GPMSAError, match=r"y_obs is a gpmsa.ObsData, which holds both x and y"):
        gpmsa.Calibrator(emu).update([[0.3]], obs)
    with pytest.raises(GPMSAError, match="x_new is a gpmsa.ObsData"):
        gpmsa.predictive.calibrated_predict(emu, gpmsa.Calibrator(emu).update(obs), obs)
    with pytest.raises(GPMSAError, match="y_obs is required unless every x_obs entry"):
        gpmsa.calibrate_study([emu, emu], [obs, [[0.3]]], n_samples=10, n_burn=0)


def test_a_study_takes_obsdata_per_model():
    """calibrate_study with one ObsData per model on its own grids: each member posterior
    records its layout, so full_prediction refuses the arrays on the simulation grid; a
    shared parameter lands near the truth."""
    emu = vector_emulator()
    a, b = ragged_obs([1e4, 2.5e3], seed=1), ragged_obs([1e4, 2.5e3], seed=2)
    study = gpmsa.calibrate_study([emu, emu], [a, b], shared=["t"], n_samples=600, n_burn=100,
                                  seed=4)  # fmt: skip
    assert abs(study.posterior.mean("t") - T_TRUE) < 0.05
    member = study.member_posterior(0)
    assert (
        member.info["obs_layout_sha256"]
        == gpmsa.Calibrator(emu).update(a).info["obs_layout_sha256"]
    )
    plain = gpmsa.ObsData(a.x, a.experiments, index=[GRID_A, GRID_B])
    with pytest.raises(GPMSAError, match="other index grids or gives them other precisions"):
        gpmsa.full_prediction(emu, plain, [[0.5]], posterior=member, discrepancy=None)


def test_a_named_y_table_in_obsdata_is_read_by_the_emulator_y_names():
    """A y table with named columns inside an ObsData (no index) is read by the emulator's
    y_names, as calibrate reads a table y_obs: its columns reversed give the arrays' posterior
    (they gave t 0.16 for 0.40, read by position), and full_prediction takes that ObsData with
    the arrays' posterior. Other names are refused; a frame's default labels 0, 1, ... are no
    names (by position)."""
    pd = pytest.importorskip("pandas")
    emu = vector_emulator()
    grid = emu.standardizer.grid
    x = np.array([[0.3], [0.7]])
    y = vector_truth(x[:, 0], grid) + 0.01 * np.random.default_rng(4).standard_normal((2, 8))
    table = pd.DataFrame(y, columns=list(emu.y_names))[list(emu.y_names)[::-1]]
    arrays = gpmsa.Calibrator(emu).update(x, y)
    named = gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, table))
    assert named.mean("t") == arrays.mean("t") and named.sd("t") == arrays.sd("t")
    post = gpmsa.calibrate(emu, x, table, n_samples=200, n_burn=50, seed=1)
    gpmsa.full_prediction(emu, gpmsa.ObsData(x, table), [[0.5]], posterior=post, discrepancy=None)
    plain = gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, pd.DataFrame(y)))
    assert plain.mean("t") == arrays.mean("t")
    with pytest.raises(GPMSAError, match=r"ObsData y has the columns \['a0'"):
        gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, table.set_axis(
            [f"a{k}" for k in range(8)], axis=1)))  # fmt: skip


def test_full_rank_experiments_do_not_warn():
    """(Experiments with fewer values than basis vectors: tests/gpmsa/test_sparse_obs_s61.py.)"""
    emu = vector_emulator()
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ReductionWarning)
        gpmsa.Calibrator(emu).update(ragged_obs([1e4, 2.5e3]))


def test_precisions_declaring_errors_beyond_the_outputs_spread_warn():
    """A variance passed where a precision belongs (4e-4 for 2,500) declares errors far larger
    than the simulation outputs' spread: a ReductionWarning says so (lamOs, held by its prior,
    cannot undo it: theta's sd came out 12 times wider); the right precision does not warn."""
    emu = vector_emulator()
    with pytest.warns(gpmsa.ReductionWarning, match="a variance given for a precision"):
        gpmsa.Calibrator(emu).update(ragged_obs([4e-4, 4e-4]))
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ReductionWarning)
        gpmsa.Calibrator(emu).update(ragged_obs([2.5e3, 2.5e3]))


def test_a_linear_discrepancy_of_different_scales_per_experiment_is_refused_up_front():
    """discrepancy='linear' is normalised on each experiment's grid by its largest |index|;
    grids that reach different ones would give the same weights a different meaning in each
    (and full_prediction refused it only after the calibration): calibrate and the joint fit
    refuse it naming both; grids of the same reach are taken."""
    emu = vector_emulator()
    obs = gpmsa.ObsData([[0.3], [0.7]], [np.ones(5), np.ones(9)],
                        index=[np.linspace(0, 0.8, 5), GRID_B])  # fmt: skip
    want = r"largest \|index\|, which differs .* \(experiment 1: 0.8, experiment 0: 0.95\)"
    with pytest.raises(GPMSAError, match=want):
        gpmsa.calibrate(emu, ragged_obs(), discrepancy="linear", n_samples=10, n_burn=0)
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=20), rng.uniform(size=20)
    grid = np.linspace(0, 1, 8)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=vector_truth(x, grid, t[:, None]),
                        index=grid, x_names=["x"], t_names=["t"])  # fmt: skip
    with pytest.raises(GPMSAError, match=want):
        gpmsa.fit(sim, ragged_obs(), discrepancy="linear", n_iter=10, tune=False, seed=0)
    same = gpmsa.calibrate(emu, obs, discrepancy="linear", n_samples=20, n_burn=0, tune=False)
    assert "lamVz" in same.names


def test_malformed_indexes_and_precisions_are_named():
    """A list of grids of the wrong count, an index of three dimensions, an index beyond the
    simulation grid and a precision list of the wrong length are refused, each naming the
    experiment or the counts (they were flattened, or named no experiment)."""
    emu = vector_emulator()
    x, y = [[0.3], [0.7]], np.ones((2, 5))
    g = np.linspace(0, 1, 5)
    with pytest.raises(GPMSAError, match=r"^index has 3 grids for 2 experiment"):
        gpmsa.ObsData(x, y, index=[g, g, g])
    with pytest.raises(GPMSAError, match=r"one grid \(l,\) or one per experiment"):
        gpmsa.ObsData(x, y, index=np.zeros((2, 2, 2)))
    rows = gpmsa.ObsData(x, y, index=np.vstack([g, g]))  # one row per experiment
    assert all(np.array_equal(r, g) for r in rows.grids)
    with pytest.raises(GPMSAError, match=r"index of experiment 1 reaches \[0, 1.2\]"):
        gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, y, index=[g, 1.2 * g]))
    with pytest.raises(GPMSAError, match=r"one entry per experiment \(2\), got 3"):
        gpmsa.ObsData(x, y, precision=[1.0, 1.0, 1.0])


def test_precisions_follow_a_named_y_table_reordered_by_name():
    """A matrix precision belongs to y's columns as given: reordering a named table by the
    emulator's y_names reorders its rows and columns too (a review found the values reordered
    and the precision not: t 0.418 +- 0.049 for 0.398 +- 0.010)."""
    pd = pytest.importorskip("pandas")
    emu = vector_emulator()
    grid, names = emu.standardizer.grid, list(emu.y_names)
    x = np.array([[0.3], [0.7]])
    y = vector_truth(x[:, 0], grid)
    y[:, 0] += 0.5  # one column far off, weighted down by its precision
    lam = np.diag([1.0] + [1e4] * 7)
    natural = gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, y, precision=[lam, lam]))
    rev = names[::-1]
    table = pd.DataFrame(y, columns=names)[rev]
    lam_rev = lam[::-1, ::-1]
    reordered = gpmsa.Calibrator(emu).update(gpmsa.ObsData(x, table, precision=[lam_rev, lam_rev]))
    assert reordered.mean("t") == pytest.approx(natural.mean("t"), rel=1e-12)
    assert reordered.sd("t") == pytest.approx(natural.sd("t"), rel=1e-12)
    assert reordered.info["obs_layout_sha256"] == natural.info["obs_layout_sha256"]
    with pytest.raises(GPMSAError, match="names in another order, and an index"):
        gpmsa.ObsData(x, table, index=grid).outputs(emu.y_names)


def test_review_regressions_index_as_a_column_and_a_reach_of_rounding():
    """A 2-D index with one dimension of 1 is one grid (as before this session, and as
    SimData takes it); grids whose largest |index| differ by rounding (0.3 and 0.1 + 0.2)
    share a 'linear' discrepancy's scale."""
    g = np.linspace(0, 1, 5)
    for index in (g[:, None], g[None, :]):
        obs = gpmsa.ObsData(np.zeros((3, 1)), np.ones((3, 5)), index=index)
        assert all(np.array_equal(r, g) for r in obs.grids)
    emu = vector_emulator()
    a, b = np.linspace(0.0, 0.3, 4), np.array([0.0, 0.1, 0.2, 0.1 + 0.2])
    assert a[-1] != b[-1]
    obs = gpmsa.ObsData([[0.3], [0.7]], [np.ones(4), np.ones(4)], index=[a, b])
    gpmsa.calibrate(emu, obs, discrepancy="linear", n_samples=20, n_burn=0, tune=False)


def test_calibrator_records_the_observations_unless_a_prior_may_hold_others():
    """A posterior of one window records its observations; one updated with prior= values
    (another window's log-likelihood, say) rests on more than them and records none, so that
    full_prediction takes the windows together as before."""
    emu = vector_emulator()
    obs = ragged_obs([1e4, 2.5e3])
    cal = gpmsa.Calibrator(emu)
    assert "obs_values_sha256" in cal.update(obs).info
    _, loglik = cal.log_likelihood_grid(obs)
    chained = cal.update(ragged_obs([1e4, 2.5e3], seed=3), prior=loglik)
    assert "obs_values_sha256" not in chained.info
    assert "obs_layout_sha256" not in chained.info


def test_a_reduction_warning_comes_once_and_names_the_callers_line():
    """calibrate with a discrepancy reduces twice (without it for the probe, with it for the
    sampler): the warning comes once, from the reduction with the basis, and points at the
    caller's line, not into the library."""
    emu = vector_emulator()
    vague = ragged_obs([1e-6, 1e-6])  # a variance given for a precision
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gpmsa.calibrate(emu, vague, discrepancy="constant", n_samples=20, n_burn=0, tune=False)
    mine = [w for w in caught if issubclass(w.category, gpmsa.ReductionWarning)]
    assert len(mine) == 1 and "declare errors of sd" in str(mine[0].message)
    assert mine[0].filename == __file__


def test_data_from_the_simulator_on_a_partial_grid_are_not_outside_but_wrong_units_are():
    """The outside check's predictive sd includes the observation error the values beyond the
    basis estimate: the simulator's output with noise on grids of 23 and 9 points (one over
    part of the range) no longer reads as outside (it read 6.8 sds), while the same data 10
    times too large still do."""
    emu = vector_emulator()
    obs = ragged_obs([1e4, 2.5e3])
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.Calibrator(emu).update(obs)
    assert post.info["outside_sds"] < 5.0
    big = gpmsa.ObsData(obs.x, [10.0 * e for e in obs.experiments], index=obs.grids,
                        precision=[1e2, 25.0])  # fmt: skip
    with pytest.warns(gpmsa.OutsideEmulatorWarning):
        assert gpmsa.Calibrator(emu).update(big).info["outside_sds"] > 20.0


def test_the_chains_find_lamos_where_precisions_are_declared_far_too_large():
    """Precisions declared 1e12 times too large put lamOs near 3e-9, where the data's values
    beyond the basis (the prior's correction) say it lies; the chains started at 1 /
    excess_var (3.6e-6 here), decades above, and never came down (theta 0.3980 +- 0.0029
    against the exact 0.4029 +- 0.0038). They now start at the corrected prior's mean and
    agree with the grid within Monte-Carlo error. A 30-point output with 3 components,
    three experiments on grids of 12, 20 and 25 points."""
    grid = np.linspace(0.0, 1.0, 30)
    rng = np.random.default_rng(0)
    x = (rng.permutation(50) + rng.uniform(size=50)) / 50
    t = (rng.permutation(50) + rng.uniform(size=50)) / 50
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=vector_truth(x, grid, t[:, None]),
                        index=grid, x_names=["x"], t_names=["t"])  # fmt: skip
    prm = {"betaU": [[1.0] * 3] * 2, "lamUz": [1.0] * 3, "lamWs": [5e3] * 3, "lamWOs": [5e3]}
    emu = gpmsa.Emulator.from_params(sim, prm, n_pc=3)
    xs = np.array([0.25, 0.6, 0.85])
    grids = [np.linspace(0, 1, 12), np.linspace(0.1, 0.9, 20), np.linspace(0.05, 0.95, 25)]
    noise = [
        0.02 * np.random.default_rng(10 + k).standard_normal(g.size) for k, g in enumerate(grids)
    ]
    ys = [vector_truth(xs[k : k + 1], g)[0] + noise[k] for k, g in enumerate(grids)]
    obs = gpmsa.ObsData(xs[:, None], ys, index=grids, precision=1e12)
    exact = gpmsa.Calibrator(emu).update(obs)
    assert exact.mean("lamOs") < 1e-7
    for kw in ({}, {"fast": False}):
        post = gpmsa.calibrate(emu, obs, n_samples=2000, n_burn=200, seed=5, **kw)
        assert abs(post.mean("t") - exact.mean("t")) < 0.25 * exact.sd("t")
        assert abs(post.sd("t") / exact.sd("t") - 1.0) < 0.25
        assert abs(post.mean("lamOs") / exact.mean("lamOs") - 1.0) < 0.25
