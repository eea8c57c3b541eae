"""gpmsa with ArviZ 0.x and 1.x (session 82): ``gpmsa.mcmc.diagnostics`` is the one module that
calls ArviZ, and hides what 1.x (Python >= 3.12) changed. These tests run on the installed
release (CI: 0.23.4; checked by hand on Python 3.13 with 1.2.0 and 1.3.0).

Before: with ArviZ 1.x every ``to_arviz`` raised TypeError (``from_dict`` takes the groups as
one dict), ``Posterior.hdi`` of draws raised TypeError (``hdi_prob`` is now ``prob``), and
``diagnostics.autocorrelation`` (the trace figures) raised AttributeError (``arviz.autocorr`` is
gone; it is ``arviz_stats.base.array_stats.autocorr``); pyproject asked for arviz < 1."""

from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc import diagnostics
from gpmsa.mcmc.diagnostics import arviz_major

az = pytest.importorskip("arviz")

REPO = Path(__file__).resolve().parents[2]


def _chains(seed=0, n_draws=100):
    """Two chains, the second drifting a little (an R-hat above 1)."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(2, n_draws))
    x[1] += 0.3 * np.cumsum(rng.normal(size=n_draws)) / 10
    return x


def test_arviz_major_is_the_installed_release():
    assert arviz_major() == int(az.__version__.split(".")[0])
    assert arviz_major() in (0, 1)


def test_to_arviz_gives_the_groups_and_draws_with_either_release(tmp_path):
    chains = {"GD": _chains(1, 30), "E": _chains(2, 30)}
    post = gpmsa.Posterior({k: v.reshape(-1) for k, v in chains.items()}, chains=chains,
                           info={"units": {"GD": "mm", "E": ""}})  # fmt: skip
    idata = post.to_arviz()
    assert type(idata).__name__ == ("DataTree" if arviz_major() >= 1 else "InferenceData")
    assert tuple(idata.posterior.data_vars) == ("GD", "E")
    np.testing.assert_array_equal(idata.posterior["GD"].values, chains["GD"])
    assert (
        idata.posterior["GD"].attrs["units"] == "mm" and "units" not in idata.posterior["E"].attrs
    )
    lp = np.arange(20.0).reshape(2, 10)
    with_lp = diagnostics.to_inference_data({"a": np.ones((2, 10, 3))}, log_post=lp)
    np.testing.assert_array_equal(with_lp.sample_stats["lp"].values, lp)
    assert with_lp.posterior["a"].dims == ("chain", "draw", "a_dim_0")
    idata.to_netcdf(str(tmp_path / "post.nc"))
    back = az.from_netcdf(str(tmp_path / "post.nc"))
    np.testing.assert_array_equal(back.posterior["E"].values, chains["E"])


def test_autocorrelation_is_the_normalised_sample_autocovariance():
    x = _chains(3, 64)
    x[0] = 5.0  # a constant chain: NaN
    got = diagnostics.autocorrelation(x)
    assert np.all(np.isnan(got[0]))
    d = x[1] - x[1].mean()
    n = d.size
    want = np.array([np.dot(d[: n - k], d[k:]) for k in range(n)]) / np.dot(d, d)
    np.testing.assert_allclose(got[1], want, rtol=1e-10, atol=1e-13)


@pytest.mark.parametrize("level", [0.5, 0.9, 0.94])
def test_hdi_of_draws_is_the_shortest_interval_of_floor_level_n_steps(level):
    draws = np.random.default_rng(4).exponential(size=501)
    s = np.sort(draws)
    k = int(np.floor(level * s.size))
    i = int(np.argmin(s[k:] - s[: s.size - k]))
    assert diagnostics.hdi(draws, level) == (s[i], s[i + k])
    assert gpmsa.Posterior(samples={"x": draws}).hdi("x", level) == (s[i], s[i + k])


def test_ess_and_rhat_are_arvizs_to_the_digit_with_either_release():
    """Rank-normalised bulk ESS and split R-hat (FFT and ranks: no BLAS), the same digits from
    ArviZ 0.23.4, 1.2.0 and 1.3.0."""
    x = _chains()
    assert diagnostics.ess(x) == pytest.approx(119.67361938927301, rel=1e-10)
    assert diagnostics.rhat(x) == pytest.approx(1.0123791524554542, rel=1e-10)
    summary = diagnostics.summarize({"a": x[..., None]})["a"]
    assert summary["ess"] == pytest.approx([119.67361938927301], rel=1e-10)
    assert summary["rhat"] == pytest.approx([1.0123791524554542], rel=1e-10)


def test_the_pin_allows_arviz_1_from_python_3_12_only():
    tomllib = pytest.importorskip("tomllib")
    requirements = pytest.importorskip("packaging.requirements")
    deps = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    arviz = [requirements.Requirement(d) for d in deps if d.startswith("arviz")]

    def allowed(python: str) -> set[str]:
        versions = ("0.19.0", "0.23.0", "0.23.1", "0.23.4", "1.0.0", "1.1.0", "1.2.0", "1.3.0",
                    "2.0.0")  # fmt: skip
        env = {"python_version": python, "python_full_version": python + ".0"}
        live = [r for r in arviz if r.marker is None or r.marker.evaluate(env)]
        assert len(live) == 1, (python, live)
        return {v for v in versions if live[0].specifier.contains(v)}

    assert allowed("3.10") == allowed("3.11") == {"0.23.1", "0.23.4"}
    assert allowed("3.12") == allowed("3.13") == {"0.23.1", "0.23.4", "1.2.0", "1.3.0"}


def test_where_arviz_1_may_install_the_netcdf_writer_is_required():
    """ArviZ 1.x leaves h5netcdf and h5py to an extra: a fresh Python 3.13 install wrote no
    netCDF (`to_arviz().to_netcdf` raised ValueError, "none of the suitable backend libraries"),
    while 0.x requires them itself."""
    tomllib = pytest.importorskip("tomllib")
    requirements = pytest.importorskip("packaging.requirements")
    deps = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    for python in ("3.12", "3.13", "3.14"):
        env = {"python_version": python, "python_full_version": python + ".0"}
        live = [requirements.Requirement(d) for d in deps]
        live = [r for r in live if r.marker is None or r.marker.evaluate(env)]
        writer = [r for r in live if r.name == "h5netcdf"]
        assert len(writer) == 1 and "h5py" in writer[0].extras, python
        assert writer[0].specifier.contains("1.8.0") and not writer[0].specifier.contains("1.7.0")
