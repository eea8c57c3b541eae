"""Paths of chain starts, mean bases, categorical inputs and the version record that no test ran
(session 84 coverage sweep, second part)."""

import sys
import warnings
from importlib import metadata

import numpy as np
import pytest

import gpmsa
from gpmsa._version import library_versions
from gpmsa.model.mean_basis import MeanBasis

G = gpmsa.GammaPrior


def _data(m: int = 8) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(m, 1)), rng.uniform(size=(m, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + t))


def _fit(data=None, **kw) -> gpmsa.Emulator:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data or _data(), n_iter=6, seed=0, **kw)


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_a_non_finite_given_start_is_named(value):
    """Before: "init: chain 0's start is not finite", naming neither parameter nor value."""
    with pytest.raises(gpmsa.GPMSAError, match=r"init\['lamUz'\] must be finite numbers, got "
                                               rf"\[{value}\] \(chain 0\)"):  # fmt: skip
        _fit(init={"lamUz": [[value]]})


def test_a_prior_start_inside_bounds_with_little_mass_takes_their_middle():
    # Gamma(5, 5) has no mass near (1e6, 1.0001e6): 1000 redraws miss, the bounds' middle serves
    lower, upper = 1e6, 1e6 * 1.0001
    emu = _fit(init="prior", priors=gpmsa.Priors(lamUz=G(5, 5, lower, upper)))
    lam = np.asarray(emu.draws["lamUz"])
    assert lam.size and np.all((lam > lower) & (lam < upper))


def test_a_prior_start_of_theta_far_outside_the_unit_interval_stays_inside():
    # Normal(40, 0.5) truncated to (0, 1): 1000 redraws miss, a uniform on (0.01, 0.99) serves
    rng = np.random.default_rng(1)
    xo = rng.uniform(size=(2, 1))
    obs = gpmsa.ObsData(x=xo, y=np.sin(3 * xo + 0.4))
    emu = _fit(obs=obs, init="prior", priors=gpmsa.Priors(theta_mean=40.0, theta_sd=0.5))
    assert all(np.all(np.isfinite(v)) for v in emu.draws.values())  # its chain ran


def test_a_jittered_start_within_narrow_bounds_stays_put():
    # bounds narrower than the jitter's margins: the start itself, inside them
    lower, upper = 1e3, 1e3 * (1 + 1e-5)
    emu = _fit(init="jitter", priors=gpmsa.Priors(lamUz=G(5, 5, lower, upper)))
    lam = np.asarray(emu.draws["lamUz"])
    assert np.all((lam > lower) & (lam < upper))


def test_mean_basis_refusals_name_the_problem():
    with pytest.raises(gpmsa.GPMSAError, match=r"mean_basis must be None, one of \('constant', "
                                               r"'linear'\) or a callable, got 5"):  # fmt: skip
        _fit(mean_basis=5)
    with pytest.raises(gpmsa.GPMSAError, match=r"mean_basis has 14 columns; it needs fewer "
                                               r"than the 8 runs"):  # fmt: skip
        _fit(mean_basis=lambda z: np.hstack([z**k for k in range(7)]))


def test_a_mean_basis_object_is_taken_as_it_is():
    twin = _fit(mean_basis="linear")
    emu = _fit(mean_basis=MeanBasis("linear", 2))
    for name, v in twin.draws.items():
        np.testing.assert_array_equal(emu.draws[name], v)


def test_categorical_columns_name_the_bad_item():
    x, t, y = (np.linspace(0.0, 1.0, 6)[:, None],) * 3
    with pytest.raises(gpmsa.GPMSAError, match=r"x_categorical: 'nope' is not an input; the "
                                               r"inputs are \('v',\)"):  # fmt: skip
        gpmsa.SimData(x=x, t=t, y=y, x_names=["v"], x_categorical=["nope"])
    with pytest.raises(gpmsa.GPMSAError, match=r"x_categorical must hold column indices or "
                                               r"names, got 1.5"):  # fmt: skip
        gpmsa.SimData(x=x, t=t, y=y, x_categorical=[1.5])


def test_library_versions_without_threadpoolctl_or_a_backend_package(monkeypatch):
    monkeypatch.setitem(sys.modules, "threadpoolctl", None)  # import fails

    def missing(name):
        raise metadata.PackageNotFoundError(name)

    monkeypatch.setattr(metadata, "version", missing)
    out = library_versions("torch")
    assert out["blas"] == "unknown"
    assert out["torch"] == out["gpytorch"] == "not installed"
