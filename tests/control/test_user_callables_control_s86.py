"""``ChangePointSettings(prior=)`` as a callable that misbehaves: a mask (``lambda gd: gd < 500``)
was read as log densities 1 and 0, a prior that is not zero anywhere, silently; a complex value
lost its imaginary part with only numpy's ComplexWarning; an error raised by the user's own
code (a ValueError, a TypeError) was reported as "prior(gd) must return real log densities:
<its message>", its traceback dropped. Each is now named or propagates as raised; a
well-behaved prior's mass is unchanged."""

import warnings

import numpy as np
import pytest

from control.changepoint import ChangePointFilter, ChangePointSettings
from control.errors import ControlError

GRID = np.geomspace(200.0, 600.0, 41)


def _normal(gd):
    return -0.5 * ((np.log(gd) - np.log(350.0)) / 0.3) ** 2


def _filter(prior) -> ChangePointFilter:
    return ChangePointFilter(GRID, ChangePointSettings(prior=prior))


@pytest.mark.parametrize(
    ("prior", "named"),
    [
        (lambda gd: gd < 500.0, "bool"),
        (lambda gd: _normal(gd) + 1j, "complex"),
        (lambda gd: _normal(gd) + 0j, "complex"),
        (lambda gd: None, "None"),
        (lambda gd: np.full(gd.shape, "0.0"), "str"),  # before: read as numbers
        (lambda gd: ["0"] * gd.size, "str"),
        (lambda gd: np.zeros(gd.shape, dtype=object), "object"),
    ],
)
def test_a_prior_returning_no_real_log_densities_is_named(prior, named):
    with warnings.catch_warnings():
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        with pytest.raises(ControlError, match=rf"prior\(gd\) must return .*got .*{named}"):
            _filter(prior)


@pytest.mark.parametrize("error", [ValueError, TypeError, ZeroDivisionError, KeyError])
def test_an_error_of_the_prior_itself_propagates_as_raised(error):
    def prior(gd):
        raise error("a bug in the user's prior")

    with pytest.raises(error, match="a bug in the user's prior") as info:
        _filter(prior)
    assert not isinstance(info.value, ControlError)


@pytest.mark.parametrize(
    "shaped",
    [
        lambda v: v.tolist(),
        lambda v: tuple(v),
        lambda v: v.reshape(1, -1)[0],
    ],
)
def test_a_prior_of_numbers_in_any_form_gives_the_same_mass(shaped):
    np.testing.assert_array_equal(_filter(lambda gd: shaped(_normal(gd))).prior,
                                  _filter(_normal).prior)  # fmt: skip


def test_a_prior_that_edits_its_grid_leaves_the_filter_grid_as_given():
    def editing(gd):
        out = _normal(gd)
        gd *= 2.0
        return out

    flt = _filter(editing)
    np.testing.assert_array_equal(flt.gd, GRID)
    np.testing.assert_array_equal(flt.prior, _filter(_normal).prior)
