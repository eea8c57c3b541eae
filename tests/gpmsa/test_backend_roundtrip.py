"""The emulator file does not depend on the backend: fit with one, calibrate with another."""

import numpy as np
import pytest

import gpmsa
from tests._extras import TORCH

pytestmark = TORCH  # every test fits or calibrates with the torch backend


@pytest.fixture(scope="module")
def road():
    from _backend_cases import road_data

    return road_data()


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # short chains on purpose
@pytest.mark.parametrize(("fit_with", "calibrate_with"), [("torch", "numpy"), ("numpy", "torch")])
def test_fit_save_load_calibrate_across_backends(road, tmp_path, fit_with, calibrate_with):
    sim, obs = road
    chains = {"torch": 4, "numpy": 1}[fit_with]
    emu = gpmsa.fit(sim, n_iter=120, tune=False, n_chains=chains, backend=fit_with, seed=1)
    path = tmp_path / f"{fit_with}.gpmsa"
    emu.save(path)
    loaded = gpmsa.load(path)
    assert loaded.settings["backend"] == fit_with
    for name, val in emu.params.items():
        np.testing.assert_array_equal(loaded.params[name], val)
    for name, val in emu.draws.items():
        np.testing.assert_array_equal(loaded.draws[name], val)
    x_obs, y_obs = obs.x, obs.y
    kw = {"n_samples": 300, "n_burn": 60, "seed": 4, "backend": calibrate_with}
    if calibrate_with == "torch":
        kw["n_chains"] = 4
    from_file = gpmsa.calibrate(loaded, x_obs, y_obs, **kw)
    in_memory = gpmsa.calibrate(emu, x_obs, y_obs, **kw)
    # the loaded emulator is the same emulator: identical draws for the same seed
    np.testing.assert_array_equal(from_file.samples["GD"], in_memory.samples["GD"])
    lo, hi = loaded.domain["GD"]
    assert lo < from_file.mean("GD") < hi and from_file.sd("GD") > 0


def test_files_from_both_backends_have_the_same_layout(road, tmp_path):
    from gpmsa.io.container import read_raw

    sim, _ = road
    paths = []
    for backend in ("numpy", "torch"):
        emu = gpmsa.fit(sim, n_iter=20, tune=False, backend=backend, seed=2)
        paths.append(tmp_path / f"{backend}.gpmsa")
        emu.save(paths[-1])
    raws = [read_raw(p) for p in paths]
    assert raws[0][0].keys() == raws[1][0].keys()
    assert sorted(raws[0][1]) == sorted(raws[1][1])
