"""The fast sampler's dense path (no Chebyshev series: two or more parameters and several
observations, a categorical theta, a GLS mean basis) gives the values of its reference bit for
bit: the emulator's full predictive (``FixedGP.predict``), scipy's triangular solves and
``np.linalg.eigh``, as before its per-proposal shortcuts (session 65: the same draws, faster)."""

import numpy as np
import pytest
from _calib_cases import categorical_emulator, two_param_emulator, with_draws
from scipy.linalg import solve_triangular
from threadpoolctl import threadpool_limits

import gpmsa
from gpmsa.calibration.observations import fixed_gp, reduce
from gpmsa.calibration.sampler import ThetaPredictive
from gpmsa.model.correlation import correlation, correlation_row


def _reference_at(pred: ThetaPredictive, theta) -> tuple[np.ndarray, np.ndarray]:
    """(e, y2) of ``ThetaPredictive.at`` from the full predictive, as the dense path computed it
    before session 64 (scipy's checked solves, numpy's eigh wrapper)."""
    mean, cov = pred._dense(np.array([theta], dtype=float))
    mean, cov = mean[0], cov[0]
    if pred.d == 1:
        r = (float(pred.z[0]) - float(mean[0])) / pred._sig
        return float(cov[0, 0]) / (pred._sig * pred._sig), r * r
    zw = solve_triangular(pred.L, pred.z - mean, lower=True)
    a = solve_triangular(pred.L, cov, lower=True)
    b = solve_triangular(pred.L, a.T, lower=True)
    e, vecs = np.linalg.eigh(0.5 * (b + b.T))
    y = vecs.T @ zw
    return np.maximum(e, 0.0), y * y


def _functional_two_parameters(mean_basis=None) -> gpmsa.Emulator:
    """l_sim 6, p_u 2, one x and two calibration parameters: a full (non-diagonal) Sigma_obs."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(0, 1, (40, 1)), rng.uniform(0, 1, (40, 2))
    s = np.linspace(0, 1, 6)
    y = np.sin(3.0 * x) * (1.0 + s) + np.outer(t[:, 0] ** 2, s) + 2.0 * x * t[:, 1:2]
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[2.0, 1.0], [0.5, 3.0], [1.0, 0.7]], "lamUz": [1.0, 2.0],
              "lamWs": [200.0, 50.0], "lamWOs": [300.0]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=2, mean_basis=mean_basis)


def _categorical() -> tuple[gpmsa.Emulator, np.ndarray, np.ndarray]:
    x_obs = np.linspace(0.1, 0.9, 5)[:, None]
    return categorical_emulator(), x_obs, x_obs[:, 0] + 0.5


def _case(name: str):
    """(emulator, x_obs, y_obs, unit-scale theta values to probe, emulator parameters or None
    for the point estimate)."""
    rng = np.random.default_rng(1)
    x3 = np.array([[0.2], [0.5], [0.8]])
    if name == "two, 3 obs":
        y = np.sin(2 * x3 + 0.6) + 0.48 * x3
        return two_param_emulator(), x3, y, rng.random((12, 2)), None
    if name == "two, 1 obs, a draw":  # d = 1 at one of the retained parameter sets
        emu = with_draws(two_param_emulator())
        params = {k: v[2] for k, v in emu.draws.items()}
        return emu, x3[:1], np.sin(2 * x3[:1] + 0.6), rng.random((12, 2)), params
    if name in ("functional", "functional, mean basis"):
        emu = _functional_two_parameters("linear" if "mean" in name else None)
        s = np.linspace(0, 1, 6)
        y = np.sin(3.0 * x3) * (1.0 + s) + 0.25 * s + 0.8 * x3
        return emu, x3, y, rng.random((12, 2)), None
    emu, x, y = _categorical()
    return emu, x, y, np.array([[0.0], [0.5], [1.0]]), None


@pytest.mark.parametrize(
    "name",
    ["two, 3 obs", "two, 1 obs, a draw", "functional", "functional, mean basis", "categorical"],
)
def test_dense_proposal_equals_its_reference_bit_for_bit(name):
    emu, x, y, thetas, params = _case(name)
    pred = ThetaPredictive(fixed_gp(emu, params), reduce(emu, x, y), expand=False)  # dense
    assert pred.cheb is None and pred.cheb2 is None
    with threadpool_limits(1):  # as calibrate runs (threaded BLAS is slow at these sizes)
        for theta in thetas.tolist():
            got, want = pred.at(theta), _reference_at(pred, theta)
            for g, w in zip(got, want, strict=True):
                assert np.asarray(g).tobytes() == np.asarray(w).tobytes(), (name, theta)


def test_dense_path_draws_equal_the_reference_predictives(monkeypatch):
    """A seeded calibration on the dense path: the same draws with the reference in place of
    ``ThetaPredictive.at`` (the sampler's every other step unchanged)."""
    emu, x, y, _, _ = _case("two, 3 obs")
    kw = {"n_samples": 300, "n_burn": 50, "tune_rounds": 5, "seed": 4}
    post = gpmsa.calibrate(emu, x, y, **kw)
    assert post.info["chebyshev"] is False
    monkeypatch.setattr(ThetaPredictive, "at", _reference_at)
    ref = gpmsa.calibrate(emu, x, y, **kw)
    for name in ("a", "b", "lamOs"):
        assert post.samples[name].tobytes() == ref.samples[name].tobytes(), name


def test_correlation_row_equals_correlation_bit_for_bit():
    rng = np.random.default_rng(2)
    b = np.column_stack([rng.random(37), rng.integers(0, 3, 37), rng.random(37)])
    beta = [1.3, 0.7, 4.1]
    for cat in (None, [False, True, False]):
        flags = [False] * 3 if cat is None else cat
        for a in [rng.random(3).tolist(), [0.5, 2.0, 0.0], b[4].tolist()]:
            want = correlation(np.array([a]), b, np.array(beta), cat)[0]
            got = correlation_row(a, [np.ascontiguousarray(c) for c in b.T], beta, flags)
            assert got.tobytes() == want.tobytes()


def test_the_public_eigh_gives_the_same_proposals(monkeypatch):
    """Where numpy's private eigh kernel is missing or differs (``_eigh_kernel`` returns None),
    ``np.linalg.eigh`` serves, with the same values; a non-finite input is a GPMSAError."""
    from gpmsa.calibration import sampler

    emu, x, y, thetas, params = _case("two, 3 obs")
    pred = ThetaPredictive(fixed_gp(emu, params), reduce(emu, x, y), expand=False)
    kernel = [pred.at(theta) for theta in thetas.tolist()]
    monkeypatch.setattr(sampler, "_eigh_lo", None)
    public = [pred.at(theta) for theta in thetas.tolist()]
    for got, want in zip(kernel, public, strict=True):
        for g, w in zip(got, want, strict=True):
            assert np.asarray(g).tobytes() == np.asarray(w).tobytes()
    monkeypatch.undo()
    if sampler._eigh_lo is not None:
        with np.errstate(invalid="ignore"), pytest.raises(gpmsa.GPMSAError, match="eigendecomp"):
            sampler._eigh(np.full((3, 3), np.nan))
