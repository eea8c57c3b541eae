"""A unit that xarray's CF decoding reads as a time is not written as a "units" attribute by
``to_arviz`` (session 80 review): its draws would come back from ``to_netcdf`` as dates or
durations, or the file would not open at all.

Before: ``Posterior.to_arviz`` wrote every recorded unit; a parameter in "s since start" made
``arviz.from_netcdf(path)`` raise ("unable to decode time units"), one in "days since
2000-01-01" read back as datetime64 (so `gpmsa.Posterior` refused the draws), and one in
"seconds" as timedelta64 wherever xarray decodes durations by their units (the default of
older xarray releases)."""

import numpy as np
import pytest

import gpmsa

az = pytest.importorskip("arviz")
xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

UNITS = {"t0": "s since start", "onset": "days since 2000-01-01", "tau": "seconds", "GD": "mm"}


def _posterior() -> gpmsa.Posterior:
    rng = np.random.default_rng(3)
    chains = {name: rng.normal(5.0, 1.0, (2, 20)) for name in UNITS}
    return gpmsa.Posterior({k: v.reshape(-1) for k, v in chains.items()}, chains=chains,
                           info={"units": UNITS})  # fmt: skip


def test_time_units_are_not_written_and_the_draws_read_back_as_numbers(tmp_path):
    post = _posterior()
    idata = post.to_arviz()
    assert idata.posterior["GD"].attrs["units"] == "mm"  # any other unit: kept
    for name in ("t0", "onset", "tau"):
        assert "units" not in idata.posterior[name].attrs
    path = tmp_path / "post.nc"
    idata.to_netcdf(str(path))
    back = az.from_netcdf(str(path))
    again = gpmsa.Posterior({k: v.values.ravel() for k, v in back.posterior.items()})
    for name in UNITS:
        np.testing.assert_array_equal(again.samples[name], post.samples[name])
    with xr.open_dataset(path, group="posterior", engine="h5netcdf",
                         decode_timedelta=True) as old:  # fmt: skip
        assert old["tau"].dtype == np.float64  # (as older xarray opens it by default)
