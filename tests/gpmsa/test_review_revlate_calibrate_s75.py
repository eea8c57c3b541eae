"""Review of session 75's calibration message: an option that needs the fast sampler names
everything in its way as given (another backend and fast=False both; it named the backend
alone, and the user who switched it met the refusal again)."""

import warnings

import numpy as np
import pytest

import gpmsa


@pytest.fixture(scope="module")
def emu():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + 2 * t)), n_iter=20, seed=1)


def test_every_option_in_the_fast_samplers_way_is_named(emu):
    pytest.importorskip("torch")
    with pytest.raises(gpmsa.GPMSAError, match=r"got backend='torch', fast=False$"):
        gpmsa.calibrate(emu, [[0.3]], [[0.9]], backend="torch", fast=False,
                        emulator_params="draws")  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match=r"got backend='torch'$"):  # fast left unset
        gpmsa.calibrate(emu, [[0.3]], [[0.9]], backend="torch", emulator_params="draws")
