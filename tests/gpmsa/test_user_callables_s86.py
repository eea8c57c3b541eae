"""``calibrate(log_prior=)`` (and a Calibrator's MCMC path, which passes its ``prior=`` there)
took what the callable returned through ``float()``: a mask (``lambda gd: gd > 400``) was read as
log densities 1 and 0, not as a zero prior outside, silently; a complex value lost its imaginary
part with only numpy's ComplexWarning; None was reported as "log_prior returned nan". The grid
path (``Calibrator.update(prior=)``) refused all three; now the MCMC path names them too. A
well-behaved log prior's draws are unchanged."""

import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa
from gpmsa.errors import GPMSAError

pytestmark = [
    pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning"),  # 25-draw chains
    pytest.mark.filterwarnings("ignore::PendingDeprecationWarning"),  # np.matrix
]

RUN = {"n_samples": 30, "n_burn": 5, "seed": 1, "tune": False}


def _normal(gd):
    return -0.5 * ((np.asarray(gd, dtype=float) - 430.0) / 40.0) ** 2


@pytest.mark.parametrize(
    ("log_prior", "named"),
    [
        (lambda gd: np.asarray(gd) > 300.0, "bool"),
        (lambda gd: bool(np.asarray(gd).ravel()[0] > 300.0), "bool"),
        (lambda gd: _normal(gd) + 1j, "complex"),
        (lambda gd: _normal(gd) + 0j, "complex"),
        (lambda gd: None, "None"),
        (lambda gd: "0.0", "'0.0'"),
    ],
)
def test_calibrate_log_prior_returning_no_real_number_is_named(log_prior, named):
    x, y = road_obs()
    with warnings.catch_warnings():
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        with pytest.raises(GPMSAError, match=rf"log_prior must return .*got .*{named}"):
            gpmsa.calibrate(road_emulator(), x, y, log_prior=log_prior, **RUN)


def test_calibrator_mcmc_prior_returning_a_mask_is_refused_as_on_the_grid():
    x, y = road_obs()
    mask = lambda gd: np.asarray(gd) > 300.0  # noqa: E731
    with pytest.raises(GPMSAError, match="bool"):
        gpmsa.Calibrator(road_emulator()).update(x, y, prior=mask)
    cal = gpmsa.Calibrator(road_emulator(), method="mcmc", mcmc_options=dict(RUN))
    with pytest.raises(GPMSAError, match="log_prior must return .*bool"):
        cal.update(x, y, prior=mask)


@pytest.mark.parametrize(
    "shaped",
    [
        lambda v: v,
        lambda v: v.tolist(),
        lambda v: float(v[0]),
        lambda v: np.float32(v[0]),
        lambda v: np.array(v[0]),
        lambda v: v[:, None],
        lambda v: np.matrix(v),
    ],
)
def test_calibrate_log_prior_numbers_of_any_form_give_the_same_draws(shaped):
    x, y = road_obs()
    ref = gpmsa.calibrate(road_emulator(), x, y, log_prior=_normal, **RUN)
    got = gpmsa.calibrate(road_emulator(), x, y, log_prior=lambda gd: shaped(_normal(gd)), **RUN)
    np.testing.assert_allclose(got.samples["GD"], ref.samples["GD"], rtol=1e-6)


def test_calibrate_integer_log_prior_is_a_number():
    x, y = road_obs()
    flat = gpmsa.calibrate(road_emulator(), x, y, log_prior=lambda gd: np.zeros(1), **RUN)
    whole = gpmsa.calibrate(road_emulator(), x, y, log_prior=lambda gd: np.zeros(1, int), **RUN)
    np.testing.assert_array_equal(whole.samples["GD"], flat.samples["GD"])


def test_an_update_from_inside_an_update_of_the_same_calibrator_is_refused():
    """A prior that updated its own Calibrator: the inner and outer updates were counted as one
    and drew with one seed (the same draws of GD); now refused, another Calibrator there works,
    and the Calibrator counts on as if the refused update had not happened."""
    x, y = road_obs()
    cal, twin = gpmsa.Calibrator(road_emulator(), seed=5), gpmsa.Calibrator(road_emulator(), seed=5)
    inner = []

    def updating_itself(gd):
        inner.append(cal.update(x, y))
        return np.zeros(np.shape(gd)[0])

    with pytest.raises(GPMSAError, match="called from inside an update of the same Calibrator"):
        cal.update(x, y, prior=updating_itself)
    assert not inner

    def updating_another(gd):
        inner.append(gpmsa.Calibrator(road_emulator(), seed=6).update(x, y).samples["GD"])
        return np.zeros(np.shape(gd)[0])

    outer = cal.update(x, y, prior=updating_another).samples["GD"]
    assert len(inner) == 1
    assert not np.array_equal(inner[0], outer)
    np.testing.assert_array_equal(outer, twin.update(x, y).samples["GD"])
    np.testing.assert_array_equal(cal.update(x, y).samples["GD"], twin.update(x, y).samples["GD"])
