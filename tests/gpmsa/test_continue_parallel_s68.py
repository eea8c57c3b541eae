"""Continuations (``init=emu`` / ``init=study``, ``append=True``, a basis with its columns' signs
flipped) give the same draws, bit for bit, serially, in ``n_jobs=2`` processes, on a
``concurrent.futures`` executor and on a dask client; a source fitted in
one place continues in another (s68)."""

import functools
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from _basis_cases import GROUPS, D, basis_obs, basis_sim
from _continue_cases import continue_fit

import gpmsa

STUDY = {"labels": ["a", "b"], "shared": ["t"], "n_chains": 2, "tune_rounds": 3, "tune_levels": 3}


def _quiet(fn, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # short chains
        return fn(**kw)


def _basis_fit(**kw):
    kw = {"discrepancy": D, "discrepancy_groups": GROUPS, "n_chains": 2, "tune": False, **kw}
    return _quiet(gpmsa.fit, data=basis_sim(), obs=basis_obs(), **kw)


def _study(**kw):
    obs = [basis_obs(0.05 * k) for k in range(2)]
    return _quiet(gpmsa.fit_study, sims=[basis_sim()] * 2, obs=obs, **{**STUDY, **kw})


@functools.cache
def _sources():
    """Each workflow's source, fitted serially."""
    return {
        "fit": _quiet(continue_fit, n_iter=20, n_keep=10, n_burn=0, tune=False, n_jobs=1),
        "basis": _basis_fit(n_iter=20, seed=0, n_burn=0, n_keep=10, n_jobs=1),
        "study": _study(n_iter=40, n_keep=10, seed=0, n_jobs=1),
    }


def _continuations(where: dict, src: dict) -> dict:
    """Each workflow's continuation of ``src``, run ``where`` (n_jobs= or executor=)."""
    return {
        "fit": _quiet(continue_fit, n_iter=8, tune=False, init=src["fit"], **where),
        "fit append": _quiet(
            continue_fit, n_iter=8, tune=False, init=src["fit"], append=True, **where
        ),
        "-D append": _basis_fit(
            n_iter=8, seed=1, init=src["basis"], append=True, discrepancy=-D, **where
        ),
        "study append": _study(
            n_iter=16,
            seed=1,
            init=src["study"],
            append=True,
            basis=src["study"].members[0].K * [-1.0, 1.0],
            **where,
        ),
    }


def _draws(fitted) -> dict[str, np.ndarray]:
    members = getattr(fitted, "members", [fitted])
    out = {f"study.{k}": v for k, v in (fitted.draws if hasattr(fitted, "members") else {}).items()}
    for i, m in enumerate(members):
        out |= {f"{i}.{k}": v for k, v in {**m.draws, **m.calibration}.items()}
        out[f"{i}.log_post"] = m.log_post
    return out


def _assert_same(ref: dict, got: dict) -> None:
    for name in ref:
        a, b = _draws(ref[name]), _draws(got[name])
        assert a.keys() == b.keys(), name
        for k, v in a.items():
            np.testing.assert_array_equal(b[k], v, err_msg=f"{name}: {k}")


@functools.cache
def _serial():
    return _continuations({"n_jobs": 1}, _sources())


def test_continuations_in_processes_match_serial():
    _assert_same(_serial(), _continuations({"n_jobs": 2}, _sources()))


def test_continuations_on_a_process_pool_executor_match_serial():
    with ProcessPoolExecutor(2) as pool:
        _assert_same(_serial(), _continuations({"executor": pool}, _sources()))


def test_a_source_fitted_in_processes_continues_serially_as_a_serial_one():
    src = {
        "fit": _quiet(continue_fit, n_iter=20, n_keep=10, n_burn=0, tune=False, n_jobs=2),
        "basis": _basis_fit(n_iter=20, seed=0, n_burn=0, n_keep=10, n_jobs=2),
        "study": _study(n_iter=40, n_keep=10, seed=0, n_jobs=2),
    }
    _assert_same(_sources(), src)
    _assert_same(_serial(), _continuations({"n_jobs": 1}, src))


def test_continuations_on_a_dask_client_match_serial(dask_client):
    """Threads here (a cluster of worker processes took ~3 s to start; the pickling is the
    process pool's above)."""
    _assert_same(_serial(), _continuations({"executor": dask_client}, _sources()))
