"""Edges of gpmsa/model found by the audit of session 56: categorical column specs, a pandas
theta_init, the discrepancy basis's normalisation, Priors.from_dict."""

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.model import constraints
from gpmsa.model.basis import discrepancy_basis
from gpmsa.model.priors import Priors


def _sim(**kw):
    rng = np.random.default_rng(0)
    m = 12
    x = np.column_stack([rng.random(m), np.arange(m) % 3])
    t = rng.random((m, 1))
    return gpmsa.SimData(x, t, x[:, :1] + t + x[:, 1:], **kw)


@pytest.mark.parametrize("spec", [1.0, np.float64(1.0), b"x1"])
def test_categorical_spec_that_is_no_column_list_is_refused_by_name(spec):
    with pytest.raises(GPMSAError, match="x_categorical must hold column indices or names"):
        _sim(x_categorical=spec)


def test_categorical_spec_as_a_0d_integer_array_is_one_column():
    assert _sim(x_categorical=np.array(1)).x_categorical == (1,)


def test_theta_init_as_a_pandas_series_is_read_by_its_labels():
    pd = pytest.importorskip("pandas")
    lo, hi = np.zeros(2), np.full(2, 10.0)
    unit = constraints.theta_init_unit(pd.Series({"b": 2.0, "a": 7.0}), lo, hi, ("a", "b"))
    assert unit.tolist() == pytest.approx([0.7, 0.2])
    table = pd.DataFrame({"b": [2.0], "a": [7.0]})
    assert constraints.theta_init_unit(table, lo, hi, ("a", "b")).tolist() == pytest.approx(
        [0.7, 0.2]
    )
    with pytest.raises(GPMSAError, match="theta_init is a pandas Series"):
        constraints.theta_init_unit(pd.Series({"c": 2.0, "a": 7.0}), lo, hi, ("a", "b"))


@pytest.mark.parametrize("size", [1e200, 1e-170])
def test_discrepancy_basis_whose_squares_overflow_or_underflow_is_normalised(size):
    grid = np.linspace(0.0, 1.0, 5)
    D = np.column_stack([np.full(5, size), np.linspace(0.5, 1.0, 5) * size])
    expected = discrepancy_basis(D / size, grid)
    assert np.allclose(discrepancy_basis(D, grid), expected, rtol=1e-12, atol=0)
    assert np.max(np.sum(expected**2, axis=1)) == pytest.approx(1.0)


def test_linear_discrepancy_on_a_huge_index_keeps_its_slope():
    D = discrepancy_basis("linear", np.linspace(1e200, 1.5e200, 5))
    assert D[-1, 1] == pytest.approx(1.0) and np.all(D[:, 0] > 0)


def test_priors_from_dict_names_a_missing_or_unknown_field():
    good = Priors().with_data((3.0, 4.0), (1.0, 2.0))
    assert Priors.from_dict(good.to_dict()) == good
    bad = {**good.to_dict(), "zzz": 1}
    with pytest.raises(GPMSAError, match=r"unknown fields \['zzz'\]"):
        Priors.from_dict(bad)
    missing = {k: v for k, v in good.to_dict().items() if k != "lamVz"}
    with pytest.raises(GPMSAError, match="lamVz must be a dict"):
        Priors.from_dict(missing)
    text = {**good.to_dict(), "lamUz": {"a": "x", "b": 1.0}}
    with pytest.raises(GPMSAError, match="lamUz.a must be a number, got 'x'"):
        Priors.from_dict(text)
