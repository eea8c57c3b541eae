"""What ``to_arviz`` hands to other tools (session 80): every draw under its own name, each
parameter's unit as its variable's "units" attribute, and a netCDF file (``to_netcdf``) that
arviz and xarray read back without gpmsa.

Before: a parameter named "chain" or "draw" (or "NAME_dim_0" beside a draw with more axes)
came out as ArviZ's coordinate of that dimension, its draws lost without a word; and the units
that calibrate records (``Posterior.info["units"]``) were not kept."""

import warnings

import numpy as np
import pytest
from _study_cases import observations, simulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.mcmc.sampler import Chains

az = pytest.importorskip("arviz")

ODD_NAMES = ("GD", "E ü", 'a,"b"', "x[1]", "t.mu")


def _posterior(names, units=None, n_chains=3, n_draws=40):
    rng = np.random.default_rng(2)
    chains = {n: rng.normal(10.0 * i, 1.0, (n_chains, n_draws)) for i, n in enumerate(names)}
    info = {"units": units} if units is not None else {}
    return gpmsa.Posterior({k: v.reshape(-1) for k, v in chains.items()}, chains=chains,
                           info=info)  # fmt: skip


@pytest.mark.parametrize("name", ["chain", "draw"])
def test_a_parameter_named_as_a_dimension_is_refused_not_lost(name):
    post = _posterior(["t", name])
    with pytest.raises(GPMSAError, match=rf"to_arviz: parameter '{name}' is named as one of "
                                         r"ArviZ's dimensions.*rename the parameter"):  # fmt: skip
        post.to_arviz()


def test_a_name_of_another_draws_axis_is_refused():
    rng = np.random.default_rng(0)
    draws = {"b": rng.normal(size=(2, 10, 3)), "b_dim_0": rng.normal(size=(2, 10))}
    chains = Chains(draws, rng.normal(size=(2, 10)), {k: np.ones(2) for k in draws},
                    {"b": np.ones((2, 3)), "b_dim_0": np.ones((2, 1))})  # fmt: skip
    with pytest.raises(GPMSAError, match="parameter 'b_dim_0' is named as one of ArviZ's"):
        chains.to_arviz()
    del draws["b_dim_0"]  # without it: as before, b's axis "b_dim_0"
    idata = Chains(draws, np.zeros((2, 10)), {"b": np.ones(2)}, {"b": np.ones((2, 3))}).to_arviz()
    assert idata.posterior["b"].dims == ("chain", "draw", "b_dim_0")


def test_odd_names_units_and_chains_survive_a_netcdf_file(tmp_path):
    pytest.importorskip("h5netcdf")
    xr = pytest.importorskip("xarray")
    units = {"GD": "1e-6 m^3", "E ü": "GPa", 'a,"b"': "", "x[1]": None}  # "" and None: no unit
    post = _posterior(ODD_NAMES, units)
    path = tmp_path / "post.nc"
    post.to_arviz().to_netcdf(str(path))
    back = az.from_netcdf(str(path))
    assert list(back.posterior.data_vars) == list(ODD_NAMES)
    for name in ODD_NAMES:
        values = back.posterior[name].values
        assert values.shape == (3, 40) and values.dtype == np.float64
        np.testing.assert_array_equal(values, post.chains[name])  # bit for bit, per chain
        assert back.posterior[name].attrs.get("units") == (units.get(name) or None)
    with xr.open_dataset(path, group="posterior", engine="h5netcdf") as plain:  # no arviz
        assert plain["GD"].attrs["units"] == "1e-6 m^3"
        np.testing.assert_array_equal(plain["E ü"].values, post.chains["E ü"])


def test_a_units_record_plot_refuses_still_gives_the_draws():
    post = _posterior(["GD"], units=["1e-6 m^3"])  # a list, not name -> unit
    idata = post.to_arviz()
    assert "units" not in idata.posterior["GD"].attrs
    np.testing.assert_array_equal(idata.posterior["GD"].values, post.chains["GD"])


def test_a_single_draw_set_has_one_chain_and_its_unit():
    post = gpmsa.Posterior({"GD": np.arange(5.0)}, info={"units": {"GD": "1e-6 m^3"}})
    idata = post.to_arviz()
    assert idata.posterior["GD"].shape == (1, 5)
    assert idata.posterior["GD"].attrs["units"] == "1e-6 m^3"


def test_a_study_keeps_its_parameters_units():
    x = np.linspace(0.0, 1.0, 5)
    xg, tg = np.meshgrid(x, np.linspace(0.0, 1.0, 7), indexing="ij")
    xs, ts = xg.reshape(-1, 1), tg.reshape(-1, 1)
    sim = gpmsa.SimData(x=xs, t=ts, y=simulator(xs, ts), x_names=["x"], t_names=["t"],
                        t_units=["mm"])  # fmt: skip
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1000.0], "lamWOs": [1000.0]}
    emu = gpmsa.Emulator.from_params(sim, params)
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        study = gpmsa.calibrate_study([emu, emu], [d[0] for d in data], [d[1] for d in data],
                                      labels=["a", "b"], shared=["t"], n_samples=30, n_burn=10,
                                      tune=False, seed=0)  # fmt: skip
    idata = study.to_arviz()
    assert idata.posterior["t"].attrs["units"] == "mm"
    assert "units" not in idata.posterior["lamOs[a]"].attrs
    np.testing.assert_array_equal(idata.sample_stats["lp"].values, study.draws["log_post"])
