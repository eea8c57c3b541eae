"""Array-likes of other libraries and odd numpy forms given to gpmsa's public entry points.

A torch tensor that records gradients (``requires_grad=True``) stopped every entry point with
torch's RuntimeError "Can't call numpy() on Tensor that requires grad" (raised inside numpy's
conversion); gpmsa reads only the values, so such a tensor now gives the plain array's results.
Functional observations as a list of tensors, one per experiment, failed inside ObsData with
"TypeError: '>' not supported between instances of 'builtin_function_or_method' and 'int'"
(``np.size`` of a tensor is its ``size`` method). The other forms below already gave the
float64 array's model to the bit; they are kept so.
"""

from __future__ import annotations

import array
import importlib.util
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.fitting.emulator import Emulator


@pytest.fixture
def torch():
    """torch, imported by the tests that use it: without the torch extra they skip alone."""
    return pytest.importorskip("torch")


PARAMS = {"betaU": [[1.0], [1.5]], "lamUz": [1.0], "lamWs": [2000.0], "lamWOs": [2000.0]}
_rng = np.random.default_rng(86)
X, T = _rng.uniform(0.0, 10.0, 12), _rng.uniform(1.0, 5.0, 12)
Y = np.sin(X / 3.0) + (T / 3.0) ** 2
X_OBS = np.array([2.0, 6.0])
Y_OBS = np.sin(X_OBS / 3.0) + 1.0


def _model(x=X, t=T, y=Y) -> Emulator:
    return Emulator.from_params(gpmsa.SimData(x=x, t=t, y=y), PARAMS)


@pytest.fixture(scope="module")
def emulator() -> Emulator:
    return _model()


def _grad(values):
    """A float64 tensor of ``values`` that records gradients (called by tests that have torch)."""
    import torch

    return torch.tensor(np.asarray(values, dtype=float), requires_grad=True)


def test_a_tensor_that_requires_grad_gives_the_plain_arrays_results(emulator, torch):
    assert _model(_grad(X), _grad(T), _grad(Y)).model_sha256 == emulator.model_sha256
    xs, ts = np.array([[2.0], [7.0]]), np.array([[2.0], [4.0]])
    for got, want in zip(emulator.predict(_grad(xs), _grad(ts)), emulator.predict(xs, ts),
                         strict=True):  # fmt: skip
        np.testing.assert_array_equal(got, want)
    cal = gpmsa.Calibrator(emulator, seed=0)
    ref = cal.update(X_OBS, Y_OBS).mean("t0")
    assert cal.update(_grad(X_OBS), _grad(Y_OBS)).mean("t0") == ref
    obs = gpmsa.ObsData(x=_grad(X_OBS), y=_grad(Y_OBS))
    assert obs.digest() == gpmsa.ObsData(x=X_OBS, y=Y_OBS).digest()
    fixed = torch.tensor(4.0, requires_grad=True)
    got = gpmsa.sensitivity(emulator, draws=False, fixed={"x0": fixed})
    want = gpmsa.sensitivity(emulator, draws=False, fixed={"x0": 4.0})
    np.testing.assert_array_equal(got.total, want.total)


def test_functional_experiments_as_a_list_of_tensors_make_the_observations(torch):
    y = [np.array([1.0, 2.0, 3.0]), np.array([1.5, 2.5, 3.5])]
    want = gpmsa.ObsData(x=X_OBS, y=y).digest()
    assert gpmsa.ObsData(x=X_OBS, y=[torch.tensor(e) for e in y]).digest() == want
    assert gpmsa.ObsData(x=X_OBS, y=[_grad(e) for e in y]).digest() == want
    grids = [torch.tensor([0.0, 1.0, 2.0]), torch.tensor([0.0, 1.0, 2.0])]
    assert (
        gpmsa.ObsData(x=X_OBS, y=y, index=grids).digest()
        == gpmsa.ObsData(x=X_OBS, y=y, index=[g.numpy() for g in grids]).digest()
    )


def test_experiments_of_different_lengths_as_tensors_are_named(emulator, torch):
    ragged = [torch.tensor([1.0, 2.0]), torch.tensor([1.0, 2.0, 3.0])]
    with pytest.raises(GPMSAError, match=r"y_obs holds experiments of different lengths \[2, 3\]"):
        gpmsa.calibrate(emulator, x_obs=X_OBS, y_obs=ragged, n_samples=10, n_burn=5)


def _tensor(values):
    import torch

    return torch.tensor(values)


def _same_forms():
    """The design's x in forms of other libraries and numpy's odd layouts and types."""
    xr = pytest.importorskip("xarray")
    ro = X.copy()
    ro.flags.writeable = False
    return {
        **({"torch float64": _tensor(X)} if importlib.util.find_spec("torch") else {}),
        "xarray": xr.DataArray(X, dims="run", coords={"run": np.arange(12) + 5}),
        "np.matrix": np.matrix(X).T,
        "longdouble": X.astype(np.longdouble),
        "big-endian": X.astype(">f8"),
        "read-only": ro,
        "negative stride": X[::-1].copy()[::-1],
        "memoryview": memoryview(X.copy()),
        "array.array": array.array("d", X),
        "Decimal objects": np.array([Decimal(repr(float(v))) for v in X], dtype=object),
        "Fraction objects": [Fraction(v) for v in X],
        "record array": np.rec.fromarrays([X], names="x0"),
    }


@pytest.mark.filterwarnings("ignore:the matrix subclass:PendingDeprecationWarning")
def test_the_same_values_in_other_forms_make_the_same_emulator(emulator):
    for name, x in _same_forms().items():
        assert _model(x=x).model_sha256 == emulator.model_sha256, name


def test_nested_lists_of_scalar_tensors_that_require_grad_are_read_as_values(emulator, torch):
    """Before: "RuntimeError: Can't call numpy() on Tensor that requires grad" from np.ndim in
    ObsData and in calibrate's ragged check, and a GPMSAError for a flat list of them."""
    y = [[1.0, 2.0], [1.0, 3.0]]
    grads = [[_grad(v) for v in row] for row in y]
    assert (gpmsa.ObsData(x=X_OBS, y=grads, index=[0.0, 1.0]).digest()
            == gpmsa.ObsData(x=X_OBS, y=y, index=[0.0, 1.0]).digest())  # fmt: skip
    assert (gpmsa.ObsData(y=[_grad(1.0), _grad(2.0)]).digest()
            == gpmsa.ObsData(y=[1.0, 2.0]).digest())  # fmt: skip
    cal = gpmsa.Calibrator(emulator, seed=0)
    ref = cal.update([[X_OBS[0]]], [[Y_OBS[0]]]).mean("t0")
    assert cal.update([[X_OBS[0]]], [[_grad(Y_OBS[0])]]).mean("t0") == ref
