"""A lamUz too small for float64 (it made predictive variances negative) is refused where an
emulator is built or read, and hierarchical sd bounds whose square leaves float64 are refused
by name (from the s61 file fuzz)."""

import numpy as np
import pytest

import gpmsa
from gpmsa.studies.layout import HyperPriors


def _sim():
    rng = np.random.default_rng(0)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    return gpmsa.SimData(x=x, t=t, y=x + t)


def _params(**change):
    prm = dict(betaU=np.full((2, 1), 0.5), lamUz=np.array([1.0]), lamWs=np.array([1e3]),
               lamWOs=np.array([1e3]))  # fmt: skip
    return {**prm, **{k: np.array([v]) for k, v in change.items()}}


@pytest.mark.parametrize("lam_uz", [1e-9, 1e-30, 1e-300])
def test_from_params_refuses_a_lamUz_whose_variance_float64_cannot_resolve(lam_uz):
    with pytest.raises(gpmsa.GPMSAError, match=r"params\['lamUz'\] .* too large for float64"):
        gpmsa.Emulator.from_params(_sim(), _params(lamUz=lam_uz))


def test_out_of_prior_values_that_compute_well_are_still_taken():
    """lamWs of 1e6 (a nugget below GPM/SA's bound) or lamUz of 0.01: valid Gaussian
    processes, positive variances."""
    emu = gpmsa.Emulator.from_params(_sim(), _params(lamWs=1e6, lamUz=0.01))
    _, var = emu.predict([[0.5]], [[0.5]])
    assert np.all(var > 0)


def test_a_file_with_such_a_lamUz_is_refused(tmp_path):
    """A file rewritten by hand (hash recomputed): EmulatorFileError, not negative variances."""
    from test_file_fuzz_s61 import _write
    from test_file_hostile import read_members

    emu = gpmsa.Emulator.from_params(_sim(), _params())
    manifest, arrays = read_members(emu.save(tmp_path / "e.gpmsa"))
    arrays["param_lamUz"] = np.array([1e-30])
    with pytest.raises(gpmsa.EmulatorFileError, match=r"params\['lamUz'\]"):
        gpmsa.load(_write(tmp_path / "bad.gpmsa", manifest, arrays))


@pytest.mark.parametrize("sd_max", [1e200, 1e155, 1e-155, 1e-200])
def test_hyperpriors_sd_max_whose_square_leaves_float64_is_refused(sd_max):
    with pytest.raises(
        gpmsa.GPMSAError,
        match=r"sd_max=.* its square and 4/sd_max\^2 \(the default start precision\) must be",
    ):
        HyperPriors(sd_max=sd_max)
    assert HyperPriors(sd_max=1e140).lam_start == 5.0
