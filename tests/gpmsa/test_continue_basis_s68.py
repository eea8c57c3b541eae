"""A continuation (``gpmsa.fit(..., init=emu)``, ``append=True``) across a basis whose columns are
the source's up to their signs and order: the same model, its state mapped (s68)."""

import functools
import warnings

import numpy as np
import pytest
from _basis_cases import GROUPS, D, basis_obs, basis_sim

import gpmsa
from gpmsa.fitting.continuation import continued_starts
from gpmsa.model.basis import basis_digest, reordered_basis
from gpmsa.model.likelihood import log_posterior
from gpmsa.model.problem import prepare


@functools.cache
def _data():
    return basis_sim(), basis_obs()


def _fit(backend="numpy", **kw):
    data, obs = _data()
    kw = {"discrepancy": D, "discrepancy_groups": GROUPS, **kw}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, obs, n_chains=2, tune=False, backend=backend, **kw)


@functools.cache
def _source(backend="numpy"):
    return _fit(backend, n_iter=20, seed=0, n_burn=0, n_keep=10)  # 5 draws a chain, thin 4


def _draws(emu):
    return {**{k: v for k, v in emu.draws.items()}, **emu.calibration}


@pytest.mark.parametrize("backend", ["numpy", "torch"])
@pytest.mark.parametrize("append", [False, True])
def test_discrepancy_signs_and_order_continue_bit_for_bit(backend, append):
    if backend != "numpy":
        pytest.importorskip(backend)
    src = _source(backend)
    ref = _draws(_fit(backend, n_iter=8, seed=1, init=src, append=append))
    # -D, and D's columns reordered (each keeping its group) with a sign flipped
    for d, groups in ((-D, GROUPS), (D[:, [2, 0, 1]] * [1, -1, 1], [1, 0, 0])):
        got = _draws(_fit(backend, n_iter=8, seed=1, init=src, append=append,
                          discrepancy=d, discrepancy_groups=groups))  # fmt: skip
        assert got.keys() == ref.keys()
        for k, v in ref.items():
            np.testing.assert_array_equal(got[k], v, err_msg=k)


def test_pca_basis_sign_continues_bit_for_bit():
    src = _source()
    ref = _draws(_fit(n_iter=8, seed=1, init=src, basis=src.K, append=True))
    got = _draws(_fit(n_iter=8, seed=1, init=src, basis=src.K * [-1.0, 1.0], append=True))
    for k, v in ref.items():
        np.testing.assert_array_equal(got[k], v, err_msg=k)


def test_pca_basis_order_maps_the_source_state():
    src = _source()
    data, obs = _data()
    K = src.K[:, ::-1] * [1.0, -1.0]  # components swapped, one sign flipped
    prep = prepare(data, obs, discrepancy=D, discrepancy_groups=GROUPS, basis=K)
    starts = continued_starts(src, prep.problem, prep.K, obs, 2)
    last = src.draws["betaU"][[4, 9]]  # each chain's last kept draw
    np.testing.assert_array_equal(starts["betaU"], last[..., ::-1])
    np.testing.assert_array_equal(starts["lamWs"], src.draws["lamWs"][[4, 9]][..., ::-1])
    old = prepare(data, obs, discrepancy=D, discrepancy_groups=GROUPS, basis=src.K).problem
    for c in range(2):  # the same model: the same log posterior at the mapped state
        here = {k: v[c] for k, v in starts.items()}
        there = {k: src.draws[k][[4, 9][c]] if k in src.draws else src.calibration[k][
            [4, 9][c]] for k in here}  # fmt: skip
        assert log_posterior(prep.problem, here) == pytest.approx(
            log_posterior(old, there), rel=1e-10
        )
    emu = _fit(n_iter=8, seed=1, init=src, basis=K, append=True)
    pooled = emu.draws["betaU"].reshape(2, -1, 2, 2)[:, :5]  # each chain's source part first
    np.testing.assert_array_equal(pooled, src.draws["betaU"].reshape(2, 5, 2, 2)[..., ::-1])
    assert emu.settings["step_widths"]["lamUz"][0] == src.settings["step_widths"]["lamUz"][0][::-1]


@pytest.mark.parametrize("kw", [
    {"discrepancy": D**2},  # another basis
    {"discrepancy": D[:, [1, 0, 2]], "discrepancy_groups": [0, 1, 1]},  # columns change groups
    {"discrepancy": D, "discrepancy_groups": [0, 1, 1]},
])  # fmt: skip
def test_another_discrepancy_is_still_refused(kw):
    with pytest.raises(
        gpmsa.GPMSAError,
        match=r"init=emulator was another model: its .*"
        r"discrepancy differ from this fit's; continue it with the same",
    ):
        _fit(n_iter=4, seed=1, init=_source(), **kw)


def test_another_pca_basis_or_held_component_is_still_refused():
    src = _source()
    with pytest.raises(gpmsa.GPMSAError, match=r"fitted to other simulation runs \(or another "
                       r"n_pc or basis\)"):  # fmt: skip
        _fit(n_iter=4, seed=1, init=src, basis=src.K * [1.0, 1.01])
    with pytest.raises(gpmsa.GPMSAError, match="its fixed parameters differ"):
        _fit(n_iter=4, seed=1, init=src, basis=src.K[:, ::-1], fixed={"lamUz": {0: 1.0}})


def test_reordered_basis_search():
    rng = np.random.default_rng(0)
    bases = [rng.standard_normal((7, 4)), rng.standard_normal((5, 4))]
    digest = basis_digest(bases, (0, 1, 0, 1))
    moved = [b[:, [2, 1, 0, 3]] * [1, -1, -1, 1] for b in bases]
    assert reordered_basis(digest, [0, 1, 0, 1], moved, (0, 1, 0, 1))
    assert not reordered_basis(digest, [0, 1, 0, 1], moved, (1, 0, 0, 1))
    assert not reordered_basis(digest, [0, 1, 0, 1], [b + 1e-3 for b in moved], (0, 1, 0, 1))
    wide = rng.standard_normal((6, 14))  # 2^14 signs: beyond the search
    assert not reordered_basis(basis_digest([wide]), None, [-wide], None)
    assert reordered_basis(basis_digest([wide[:, :13]]), None, [-wide[:, :13]], None)
