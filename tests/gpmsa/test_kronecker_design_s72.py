"""Kronecker-separable simulation designs (``SimData(separable=)``, SEPIA's xt_sim_sep): the
declaration and its checks, the factored likelihood against the dense one, seeded fits equal to
the dense fit's draws, prediction and leave-one-out through the factors, the file field, and
the dense operations refused at large m."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.model import kronecker
from gpmsa.model.kronecker import KroneckerLikelihood, kron_matvec
from gpmsa.model.likelihood import log_likelihood
from gpmsa.model.problem import prepare

FIT = {"n_iter": 30, "seed": 3, "tune_rounds": 2, "tune_levels": 3}


def _design(nx: int = 6, nt: int = 7, l_sim: int = 4, seed: int = 0):
    """x (nx points) x t (nt points, 2 columns): the product in Kronecker order."""
    rng = np.random.default_rng(seed)
    xs, ts = np.linspace(0.0, 1.0, nx), rng.random((nt, 2))
    x, t = np.repeat(xs, nt)[:, None], np.tile(ts, (nx, 1))
    y = np.sin(3 * x) * np.linspace(1.0, 2.0, l_sim) + t[:, :1] ** 2 + 0.3 * t[:, 1:]
    y = y + 0.01 * rng.standard_normal(y.shape)
    return x, t, y


def _pair(n_pc=2, **kw):
    x, t, y = _design(**kw)
    return gpmsa.SimData(x=x, t=t, y=y), gpmsa.SimData(x=x, t=t, y=y, separable=[[0], [1, 2]])


def test_declaration_normalised_and_checked():
    x, t, y = _design()
    assert gpmsa.SimData(x=x, t=t, y=y, separable=["x0", ["t0", "t1"]]).separable == (
        (0,), (1, 2))  # fmt: skip
    assert gpmsa.SimData(x=x, t=t, y=y).separable is None
    with pytest.raises(GPMSAError, match="not the product of its factors"):
        gpmsa.SimData(x=x, t=t, y=y, separable=True)  # t0 and t1 vary together
    with pytest.raises(GPMSAError, match=r"run 1 has \[t0, t1\]"):  # wrong nesting order
        gpmsa.SimData(x=x, t=t, y=y, separable=[["t0", "t1"], ["x0"]])
    order = np.random.default_rng(1).permutation(x.shape[0])
    with pytest.raises(GPMSAError, match="Kronecker order"):
        gpmsa.SimData(x=x[order], t=t[order], y=y[order], separable=[[0], [1, 2]])
    with pytest.raises(GPMSAError, match="not the product"):  # a run missing
        gpmsa.SimData(x=x[:-1], t=t[:-1], y=y[:-1], separable=[[0], [1, 2]])
    with pytest.raises(GPMSAError, match="at least two non-empty factors"):
        gpmsa.SimData(x=x, t=t, y=y, separable=[[0, 1]])
    with pytest.raises(GPMSAError, match="'v' is not an input"):
        gpmsa.SimData(x=x, t=t, y=y, separable=[["v"], [1, 2]])


def test_kron_matvec_is_the_kronecker_product():
    rng = np.random.default_rng(2)
    a, b, c = rng.random((3, 3)), rng.random((4, 4)), rng.random((2, 2))
    v = rng.random((24, 2))
    assert np.allclose(kron_matvec([a, b, c], v), np.kron(np.kron(a, b), c) @ v, rtol=1e-13)


@pytest.mark.parametrize("categorical", [False, True])
def test_likelihood_matches_dense(categorical):
    rng = np.random.default_rng(4)
    x, t, y = _design(nx=5, nt=6, l_sim=3)
    if categorical:  # x as 5 level codes: the categorical kernel is a product too
        x = np.round(x * 4)
    sim = gpmsa.SimData(x=x, t=t, y=y, separable=[[0], [1, 2]],
                        x_categorical=[0] if categorical else None)  # fmt: skip
    prob = prepare(sim, n_pc=2).problem
    for _ in range(4):
        prm = dict(prob.init, betaU=rng.uniform(0.05, 8.0, prob.init["betaU"].shape),
                   lamUz=rng.uniform(0.3, 3.0, 2), lamWs=rng.uniform(30.0, 3e4, 2))  # fmt: skip
        dense = log_likelihood(dataclasses.replace(prob, separable=None), prm)
        lik = KroneckerLikelihood(prob, prm)
        assert lik.loglik == pytest.approx(dense, rel=1e-10)
        for name, idx, value in (("betaU", (2, 1), 1.3), ("lamWOs", (0,), 321.0)):
            prm2 = {**prm, name: prm[name].copy()}
            prm2[name][idx] = value
            want = log_likelihood(dataclasses.replace(prob, separable=None), prm2)
            assert lik.propose(name, idx, value) == pytest.approx(want, rel=1e-10)


@pytest.mark.parametrize("n_pc", [1, 2])  # one component: with the nugget-ridge moves
def test_seeded_fit_equals_dense_fit(n_pc):
    dense, sep = _pair()
    a, b = gpmsa.fit(dense, n_pc=n_pc, **FIT), gpmsa.fit(sep, n_pc=n_pc, **FIT)
    for k, v in a.draws.items():
        np.testing.assert_allclose(b.draws[k], v, rtol=1e-9, atol=0)
    np.testing.assert_allclose(b.log_post, a.log_post, rtol=1e-10)
    rng = np.random.default_rng(5)
    x, t = rng.random((7, 1)), 0.2 + 0.5 * rng.random((7, 2))
    for draws in (False, True):
        ma, va = a.predict(x, t, draws=draws)
        mb, vb = b.predict(x, t, draws=draws)
        np.testing.assert_allclose(mb, ma, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(vb, va, rtol=1e-8)
        np.testing.assert_array_equal(b.predict_mean(x, t, draws=draws), mb)
    la, lb = a.loo(), b.loo()
    np.testing.assert_allclose(lb.mean, la.mean, rtol=1e-9)
    np.testing.assert_allclose(lb.var, la.var, rtol=1e-8)


def test_file_keeps_the_declaration(tmp_path):
    dense, sep = _pair()
    a, b = gpmsa.fit(dense, n_pc=1, **FIT), gpmsa.fit(sep, n_pc=1, **FIT)
    a.save(tmp_path / "a.gpmsa")
    b.save(tmp_path / "b.gpmsa")
    assert "kron_factor" not in a.to_record()[1]  # other files as before
    np.testing.assert_array_equal(b.to_record()[1]["kron_factor"], [0, 1, 1])
    b2 = gpmsa.load(tmp_path / "b.gpmsa")
    assert b2.separable == b.separable and b2.model_sha256 == b.model_sha256
    assert gpmsa.load(tmp_path / "a.gpmsa").separable is None
    manifest, arrays = b.to_record()
    for bad in ([0, 0, 0], [0, 2, 2], [1, 0, 0]):  # [1, 0, 0]: the product breaks
        with pytest.raises(EmulatorFileError, match="kron_factor|Kronecker order|product"):
            gpmsa.Emulator.from_record(manifest, {**arrays, "kron_factor": np.array(bad, float)})


def test_refusals_by_name():
    _, sep = _pair()
    obs = gpmsa.ObsData(x=[[0.5]], y=[np.ones(4)])
    with pytest.raises(GPMSAError, match=r"observations \(obs=\) is not supported"):
        gpmsa.fit(sep, obs, n_iter=5)
    with pytest.raises(GPMSAError, match="a mean_basis is not supported"):
        gpmsa.fit(sep, n_iter=5, mean_basis="constant")
    with pytest.raises(GPMSAError, match="backend='torch' is not supported"):
        gpmsa.fit(sep, n_iter=5, backend="torch")


def test_large_design_predicts_and_refuses_dense(monkeypatch):
    rng = np.random.default_rng(6)
    xs, ts = np.linspace(0, 1, 80), np.sort(rng.random(60))  # m = 4,800 runs
    x, t = np.repeat(xs, 60)[:, None], np.tile(ts, 80)[:, None]
    y = np.sin(3 * x) + t**2
    sim = gpmsa.SimData(x=x, t=t, y=y, separable=True)
    prm = {"betaU": [[1.0], [2.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    emu = gpmsa.Emulator.from_params(sim, prm)
    z = np.array([[0.31], [0.77]]), np.array([[0.4], [0.6]])
    mean, var = emu.predict(*z)
    np.testing.assert_allclose(mean[:, 0], np.sin(3 * z[0][:, 0]) + z[1][:, 0] ** 2, atol=1e-3)
    assert np.all(var > 0) and np.all(var < 1e-3)
    assert emu.loo().rmse[0] < 1e-3
    monkeypatch.setattr(kronecker, "MAX_DENSE_RUNS", 1000)
    with pytest.raises(GPMSAError, match=r"calibration .* builds the dense 4800 x 4800"):
        gpmsa.calibrate(emu, x_obs=[[0.5]], y_obs=[[1.0]], n_samples=10, n_burn=2, seed=1)
    for dense_op in (gpmsa.sensitivity, gpmsa.cross_validate):
        with pytest.raises(GPMSAError, match="builds the dense 4800 x 4800"):
            dense_op(emu, draws=False)
