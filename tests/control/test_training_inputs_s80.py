"""What `control.training.fit_band_emulator` / `fit_window_emulator` refuse before a fit
(session 80 review): a robot's runs given as they come, and records that would contradict
the file.

Before: GD in m^3 (ISO's Gd(n0) as printed, 3e-4) was fitted without a word (the training
script refuses it, GD_MIN_HI); runs of different lengths read "setting an array element with a
sequence"; one run, or runs all at one speed, read "give nodes", then SimData's "leave x out";
and ``metadata={"noise_std": ...}`` replaced the noise sd the fit was given."""

import numpy as np
import pytest

import control
from control.training import fit_band_emulator, fit_window_emulator

FITS = [fit_band_emulator, fit_window_emulator]
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # (before: fits)
SPEEDS = np.repeat([0.6, 1.2, 1.8], 2)
GDS = np.tile([200.0, 600.0], 3)


def _accel(n: int = 2_000) -> np.ndarray:
    return np.random.default_rng(0).standard_normal((SPEEDS.size, n))


@pytest.mark.parametrize("fit", FITS)
def test_gd_in_cubic_metres_is_refused_naming_the_remedy(fit):
    with pytest.raises(control.ControlError, match=r"gd .*1e-6 m\^3.*in m\^3\?.*\[200, 600\]"):
        fit(SPEEDS, GDS * 1e-6, _accel(), noise_std=0.3, n_iter=2)


@pytest.mark.parametrize("fit", FITS)
def test_runs_of_different_lengths_say_cut_them_to_one(fit):
    runs = [row[: 2_000 - 10 * i] for i, row in enumerate(_accel())]
    with pytest.raises(control.ControlError, match=r"different lengths \(1950 to 2000 samples\)"):
        fit(SPEEDS, GDS, runs, noise_std=0.3, n_iter=2)


@pytest.mark.parametrize("fit", FITS)
def test_too_few_runs_or_one_speed_or_one_gd_is_named(fit):
    with pytest.raises(control.ControlError, match=r"1 run\b.*>= 4 runs"):
        fit(SPEEDS[:1], GDS[:1], _accel()[:1], noise_std=0.3, n_iter=2)
    with pytest.raises(control.ControlError, match=r"every run has speed 1.2 m/s.*>= 2 speeds"):
        fit(np.full(6, 1.2), GDS, _accel(), noise_std=0.3, n_iter=2)
    with pytest.raises(control.ControlError, match=r"every run has gd 300.*>= 2 GDs"):
        fit(SPEEDS, np.full(6, 300.0), _accel(), noise_std=0.3, n_iter=2)


@pytest.mark.parametrize("fit", FITS)
def test_metadata_that_contradicts_the_fit_is_refused(fit):
    with pytest.raises(control.ControlError, match=r"metadata\['noise_std'\] = 1.0 differs.*0.3"):
        fit(SPEEDS, GDS, _accel(), noise_std=0.3, metadata={"noise_std": 1.0}, n_iter=2)
    with pytest.raises(control.ControlError, match=r"metadata must be a dict"):
        fit(SPEEDS, GDS, _accel(), noise_std=0.3, metadata=[("road", "mine")], n_iter=2)
