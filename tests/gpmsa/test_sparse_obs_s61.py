"""Experiments with fewer values than basis vectors (sparse field data of a functional output):
GPM/SA's reduction gives each unobserved direction a datum of variance ~1e6 / lamOs, which adds
log(lamOs) / 2 to the log-likelihood; every likelihood takes it off again
(``ObsProblem.null_term``), so the posterior is that of the values' own likelihood."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from _calib_cases import vector_emulator
from test_calibrate_obs_grid_s60 import reference_summaries

import gpmsa
from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.calibration.observations import fixed_gp
from gpmsa.model.basis import interpolate_basis
from gpmsa.model.likelihood import IncrementalLikelihood, log_likelihood

X = np.array([[0.3], [0.7]])
CASES = {
    "two one-point": dict(y=[[1.0], [1.2]], index=[[0.5], [0.5]]),
    "two-point and one-point": dict(y=[[1.0, 0.6], [1.2]], index=[[0.5, 0.2], [0.5]]),
    "one-point, precisions": dict(y=[[1.0], [1.2]], index=[[0.5], [0.5]], precision=[1e4, 1e4]),
}


def _obs(case: str) -> gpmsa.ObsData:
    return gpmsa.ObsData(X, **CASES[case])


@functools.cache
def _reference(case: str) -> dict[str, float]:
    """`reference_summaries` of a case, made once for the tests that read it (none changes it)."""
    return reference_summaries(vector_emulator(), _obs(case))


def _unreduced_loglik(emu, obs, theta_unit: float, lam: float) -> float:
    """log N(y; B m, B C B^T + P^-1 / lamOs) of every observed value (standardised), m, C the
    emulator's predictive of the basis weights at (x, theta): no reduction."""
    std = emu.standardizer
    mean, cov = fixed_gp(emu).predict(std.x_to_unit(obs.x), np.array([[theta_unit]]))
    bases = [interpolate_basis(emu.K, std.grid, g) for g in obs.grids]
    y = np.concatenate(
        [(e - std.mean_on(g)) / std.y_sd for e, g in zip(obs.experiments, obs.grids, strict=True)]
    )
    rows = np.cumsum([0] + [b.shape[0] for b in bases])
    n, p_u = len(bases), emu.p_u
    B = np.zeros((y.size, p_u * n))  # columns (component, experiment)
    noise = np.zeros((y.size, y.size))
    for j, b in enumerate(bases):
        sl = slice(rows[j], rows[j + 1])
        B[sl, j::n] = b
        prec = np.eye(b.shape[0]) if obs.precisions is None else obs.precisions[j] * std.y_sd**2
        noise[sl, sl] = np.linalg.inv(prec) / lam
    C = np.zeros((p_u * n, p_u * n))
    for c in range(p_u):
        C[c * n : (c + 1) * n, c * n : (c + 1) * n] = cov[0, c]
    S = B @ C @ B.T + noise
    r = y - B @ mean[0].reshape(-1)
    return float(-0.5 * np.linalg.slogdet(S)[1] - 0.5 * r @ np.linalg.solve(S, r))


@pytest.mark.parametrize("case", list(CASES))
def test_reduced_likelihood_depends_on_lamos_and_theta_as_the_values_do(case):
    """Differences of the reduced log-likelihood over lamOs and theta equal those of the
    unreduced one (the constants differ); the reduction's null directions are counted."""
    emu, obs = vector_emulator(), _obs(case)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)  # values made up
        problem = calibration_problem(emu, obs, None)
    assert problem.obs.n_null > 0
    points = [(t, lam) for t in (0.2, 0.5, 0.8) for lam in (3.0, 30.0, 300.0)]
    reduced, full = [], []
    for t, lam in points:
        prm = dict(problem.init, theta=np.array([t]), lamOs=np.array([lam]))
        reduced.append(log_likelihood(problem, prm))
        # (the phantom variance 1e6 / lamOs against 1e-4: conditioning limits the agreement)
        assert IncrementalLikelihood(problem, prm).loglik == pytest.approx(reduced[-1], rel=1e-6)
        full.append(_unreduced_loglik(emu, obs, t, lam))
    d_red, d_full = np.diff(reduced), np.diff(full)
    np.testing.assert_allclose(d_red, d_full, atol=2e-3)


def test_torch_likelihood_counts_the_null_directions():
    torch = pytest.importorskip("torch")
    tb = pytest.importorskip("gpmsa.backends.torch_backend")
    emu, obs = vector_emulator(), _obs("two one-point")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        problem = calibration_problem(emu, obs, None)
    lams = np.array([[2.0], [20.0], [200.0]])
    params = {k: torch.as_tensor(np.repeat(v[None], 3, axis=0)) for k, v in problem.init.items()}
    params["lamOs"] = torch.as_tensor(lams)
    with tb.torch_threads(1):
        state = tb.BatchState(problem, 3, torch.float64, "cpu")
        state.reset(params)
        got = state.log_post().numpy()
    from gpmsa.model.likelihood import log_posterior

    want = [log_posterior(problem, dict(problem.init, lamOs=lam)) for lam in lams]
    np.testing.assert_allclose(got, want, rtol=1e-10)


@pytest.mark.parametrize("case", list(CASES))
def test_grid_posterior_is_the_values_own_and_warns_nothing(case):
    """Before the null term: sd 0.050 against 0.072 (two one-point experiments); now within
    0.02 sd in mean, sd and quantiles, and no ReductionWarning."""
    emu, obs = vector_emulator(), _obs(case)
    ref = _reference(case)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        warnings.simplefilter("error", gpmsa.ReductionWarning)
        post = gpmsa.Calibrator(emu).update(obs)
    tol = 0.02 * ref["sd"]
    assert post.mean("t") == pytest.approx(ref["mean"], abs=tol)
    assert post.sd("t") == pytest.approx(ref["sd"], abs=tol)
    for p in (0.05, 0.5, 0.95):
        assert post.quantile("t", p) == pytest.approx(ref[p], abs=tol)


def test_fast_sampler_agrees_with_the_values_own_posterior():
    emu, obs = vector_emulator(), _obs("two one-point")
    ref = _reference("two one-point")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.calibrate(emu, obs, n_samples=40_000, n_burn=2_000, seed=3)
    assert post.info["engine"] == "fast"
    assert post.mean("t") == pytest.approx(ref["mean"], abs=0.1 * ref["sd"])
    assert post.sd("t") == pytest.approx(ref["sd"], rel=0.1)


def _own_mean_obs(scale: float = 1.0) -> gpmsa.ObsData:
    """One point per experiment at the emulator's own predictive mean at t = 0.5 (times
    ``scale``)."""
    emu = vector_emulator()
    x = np.array([[0.3], [0.7], [0.5]])
    mean, _ = emu.predict(x, np.full((3, 1), 0.5))
    index = [[0.1], [0.9], [0.3]]
    y = [scale * np.interp(index[i], emu.index, mean[i]) for i in range(3)]
    return gpmsa.ObsData(x, y=y, index=index)


def test_sparse_data_from_the_emulator_are_not_outside_it_and_wrong_units_are():
    """The outside check read the reduction's stand-in 0 of each unobserved direction as a miss
    (51.8 sds for the emulator's own mean); it now looks at the observed directions only."""
    emu = vector_emulator()
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.Calibrator(emu).update(_own_mean_obs())
        gpmsa.calibrate(emu, _own_mean_obs(), n_samples=200, n_burn=50, seed=0)
        gpmsa.calibrate(emu, _own_mean_obs(), discrepancy="constant", n_samples=50, n_burn=10,
                        tune=False, seed=0)  # fmt: skip
    assert post.mean("t") == pytest.approx(0.5, abs=0.05)
    with pytest.warns(gpmsa.OutsideEmulatorWarning, match="predictive sds"):
        gpmsa.Calibrator(emu).update(_own_mean_obs(10.0))
