"""Calibration and prediction fixes of session 70.

1. The extrapolation warning (inputs outside the emulator's training domain, within its
   margin) was a plain UserWarning at four sites: it could not be filtered apart from others.
   It is now ``gpmsa.ExtrapolationWarning`` (a UserWarning) everywhere.
2. `closer_fit` searched to L-BFGS-B's default limits: on a 400-run, six-parameter emulator,
   250-460 predictions (3-16 s) for data that a theta read inside after 29-218 of them. Its
   searches now stop at the first theta that reads the observation inside and needs no
   excess observation error (the verdict and the lamOs start are then final), and run at most
   ``CLOSER_ITERATIONS`` iterations.
3. `prediction_bands` labelled a scalar output's horizontal axis "x[0]" though the emulator
   records the input's name and unit.
"""

import dataclasses
import warnings

import numpy as np
import pytest
import scipy.optimize
from _outside_cases import X_OBS, simulator, three_parameter_emulator

import gpmsa
from gpmsa.calibration import observations
from gpmsa.model.problem import check_x_obs


@pytest.fixture(scope="module")
def scalar_emulator():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    sim = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["v"], t_names=["GD"])
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e4]}
    return gpmsa.Emulator.from_params(sim, params)


def _extrapolation_warnings(call) -> list:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    return [w for w in caught if "extrapolat" in str(w.message)]


def test_extrapolation_warning_is_its_own_user_warning():
    assert issubclass(gpmsa.ExtrapolationWarning, UserWarning)
    assert "ExtrapolationWarning" in gpmsa.__all__
    assert not issubclass(gpmsa.ExtrapolationWarning, gpmsa.OutsideEmulatorWarning)


def test_every_extrapolation_site_warns_with_its_class(scalar_emulator):
    emu, outside = scalar_emulator, float(scalar_emulator.domain["v"][1]) + 0.02
    sites = {
        "Emulator.predict": lambda: emu.predict([[outside]], [[0.5]]),
        "emulator_prediction": lambda: gpmsa.emulator_prediction(
            emu, [[outside]], [[0.5]], draws=False
        ),
        "calibrate": lambda: gpmsa.calibrate(
            emu,
            [[outside]],
            [[1.2]],
            n_samples=20,
            n_burn=0,
            tune=False,
            seed=0,
            extrapolate=True,
        ),  # fmt: skip
        "check_x_obs": lambda: check_x_obs(np.array([[1.05]]), ("v",)),
    }
    for site, call in sites.items():
        caught = _extrapolation_warnings(call)
        assert caught, site
        assert {w.category for w in caught} == {gpmsa.ExtrapolationWarning}, site
    with warnings.catch_warnings():  # now filtered apart from the others
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", gpmsa.ExtrapolationWarning)
        emu.predict([[outside]], [[0.5]])


def _inside_data(emulator):
    y = simulator(X_OBS[:, 0], np.tile([0.37, 0.61, 0.23], (3, 1)))
    y = y + 0.002 * np.random.default_rng(0).standard_normal(y.shape)
    return observations.reduce(emulator, X_OBS, y)


def test_closer_fit_stops_at_the_first_theta_that_settles_it():
    """Data a theta reads inside (11-18 sds on the probe nodes): the search ran on to
    convergence (36 predictions here; 250-460 at 400 runs and six parameters)."""
    emu = three_parameter_emulator(corners=True)
    data = _inside_data(emu)
    gp = observations.fixed_gp(emu)
    theta = observations.theta_probe(3)
    probe = gp.predict(data.x, theta)
    assert observations.fit_of(*probe, data).outside_sds > observations.OUTSIDE_SDS
    settled = []  # per single-theta prediction: does it read inside with no excess?

    def predict(x, t):
        mean, cov = gp.predict(x, t)
        fit = observations.fit_of(mean, cov, data)
        settled.append(fit.outside_sds <= observations.OUTSIDE_SDS and fit.excess_var == 0)
        return mean, cov

    fit = observations.closer_fit(predict, data, theta, probe)
    assert fit.outside_sds < observations.OUTSIDE_SDS and fit.excess_var == 0.0
    assert settled[-1] and not any(settled[:-1])  # no prediction after the one that settled it


def test_closer_fit_caps_each_search(monkeypatch):
    from gpmsa.calibration.observations import CLOSER_ITERATIONS

    emu = three_parameter_emulator()
    data = observations.reduce(emu, X_OBS, 100.0 * simulator(X_OBS[:, 0], np.full((3, 3), 0.4)))
    options = []
    minimize = scipy.optimize.minimize

    def recorded(*args, **kwargs):
        options.append(kwargs.get("options", {}))
        return minimize(*args, **kwargs)

    monkeypatch.setattr(scipy.optimize, "minimize", recorded)
    theta = observations.theta_probe(3)
    fit = observations.closer_fit(observations.fixed_gp(emu).predict, data, theta)
    assert fit.outside_sds > 10 * observations.OUTSIDE_SDS  # a units error stays outside
    assert options and all(o.get("maxiter") == CLOSER_ITERATIONS for o in options)
    assert 10 <= CLOSER_ITERATIONS <= 100


@pytest.fixture(scope="module")
def joint():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])

    def fitted(**names):
        data = gpmsa.SimData(x=x, t=t, y=x + t, **names)
        return gpmsa.fit(data, obs, n_iter=50, tune=False, seed=0, discrepancy="constant")

    return obs, fitted


@pytest.mark.parametrize(
    ("names", "label"),
    [({"x_names": ["v"], "x_units": ["m/s"]}, "v (m/s)"), ({"x_names": ["v"]}, "v"),
     ({}, "x0")],
)  # fmt: skip
def test_prediction_bands_label_the_input_by_its_name_and_unit(joint, names, label):
    obs, fitted = joint
    pred = gpmsa.full_prediction(fitted(**names), obs, [[0.3], [0.6]], n_draws=5, n_rlz=4, seed=1)
    assert pred.x_names == tuple(names.get("x_names", ["x0"]))
    assert pred.x_units == tuple(names.get("x_units", [""]))
    assert gpmsa.plots.prediction_bands(pred).axes[1].get_xlabel() == label
    unnamed = dataclasses.replace(pred, x_names=(), x_units=())  # made by hand: generic
    assert gpmsa.plots.prediction_bands(unnamed).axes[1].get_xlabel() == "x[0]"
