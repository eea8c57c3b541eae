"""From a probe of the fit path: observations in other units, dates as outputs, names given as
one string, seeds that could not be rerun, options not recorded, more draws than n_keep, and a
single point given as a vector."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + t))


def _fit(data, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: convergence warnings
        return gpmsa.fit(data, **({"n_iter": 40, "progress": False} | kw))


def test_observations_far_outside_the_simulations_are_refused(data):
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    yo = np.sin(3 * xo + 0.4)
    for y in (yo * 1e150, yo * 1e170, yo + 1e6):  # fitted silently or a ChainError before
        with pytest.raises(GPMSAError, match=r"y_obs lies .* standard deviations .*wrong units"):
            _fit(data, obs=gpmsa.ObsData(x=xo, y=y), seed=0)


def test_dates_and_one_string_of_names_are_refused(data):
    x, t = data.x, data.t
    for y in (np.arange(30).astype("timedelta64[s]"), np.arange(30).astype("datetime64[D]")):
        with pytest.raises(GPMSAError, match=r"numeric array, got (timedelta|datetime)"):
            gpmsa.SimData(x=x, t=t, y=y)
    with pytest.raises(GPMSAError, match=r"x_names must be a list of names, got the string 'ab'"):
        gpmsa.SimData(x=np.hstack([x, t]), t=t, y=data.y, x_names="ab")
    with pytest.raises(GPMSAError, match=r"x_units must be a list of units, got the string 'm'"):
        gpmsa.SimData(x=x, t=t, y=data.y, x_units="m")


def test_a_fit_without_a_seed_records_one_that_repeats_it(data):
    first = _fit(data)
    seed = first.settings["seed"]
    assert isinstance(seed, int)
    again = _fit(data, seed=seed)
    np.testing.assert_array_equal(first.draws["betaU"], again.draws["betaU"])


def test_a_torch_dtype_is_recorded_by_name(data):
    torch = pytest.importorskip("torch")
    emu = _fit(data, seed=0, backend="torch", dtype=torch.float32, tune=False)  # tuning: 3,300
    # sweeps of one chain, 9 s, for a record that does not depend on it
    assert emu.settings["backend_options"] == {"dtype": "float32"}


def test_n_keep_bounds_the_draws_of_all_chains(data):
    for n_iter, n_burn, chains, n_keep in ((20, 10, 3, 4), (100, 20, 4, 5), (50, 10, 2, 7)):
        emu = _fit(data, n_iter=n_iter, n_burn=n_burn, n_chains=chains, n_jobs=1, n_keep=n_keep,
                   seed=1)  # fmt: skip
        assert emu.n_draws <= n_keep
    with pytest.raises(GPMSAError, match=r"n_keep=1 is fewer than n_chains=4"):
        _fit(data, n_chains=4, n_keep=1, seed=1)


def test_one_point_may_be_given_as_a_vector_of_its_inputs():
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 2))
    emu = _fit(gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + t[:, :1] - t[:, 1:])), seed=0)
    row = emu.predict([[0.5]], [[0.5, 0.2]])
    np.testing.assert_array_equal(emu.predict([[0.5]], [0.5, 0.2])[0], row[0])
    with pytest.raises(GPMSAError, match=r"t must have 2 columns, got shape \(3,\)"):
        emu.predict([[0.5]], [0.5, 0.2, 0.1])


def test_one_kept_draw_gives_nan_spreads_without_numpy_or_arviz_noise(data, monkeypatch):
    stats_utils = pytest.importorskip("arviz.stats.stats_utils")
    logged = []  # ArviZ's own logger (it does not propagate): "Shape validation failed"
    monkeypatch.setattr(stats_utils._log, "warning", lambda msg, *a, **k: logged.append(msg))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # numpy's "Degrees of freedom <= 0"
        emu = gpmsa.fit(data, n_iter=20, n_burn=19, seed=1, progress=False)
    assert emu.n_draws == 1
    assert all(np.isnan(v) for entry in emu.diagnostics.values() for v in entry["sd"])
    with pytest.warns(gpmsa.ConvergenceWarning) as record:
        gpmsa.fit(data, n_iter=20, n_burn=19, n_chains=2, n_jobs=1, seed=1, progress=False)
    assert logged == []
    message = str(record[0].message)
    assert "too few draws to judge (1 a chain)" in message and "constant draws" not in message
