"""`control.training.fit_band_emulator` passes ``progress`` to `gpmsa.fit` (its fit_options):
the fit's bar on stderr with it, nothing without it, the same emulator either way."""

import warnings

import numpy as np
from scipy import signal

from control.training import fit_band_emulator


def _fit(progress: bool):
    """15 stand-in runs (5 speeds x 3 GDs, 2,000 samples: two batches of 8 blocks of 125)."""
    rng = np.random.default_rng(0)
    speed, gd = np.repeat([0.6, 0.9, 1.2, 1.5, 1.8], 3), np.tile([200.0, 400.0, 600.0], 5)
    b, a = signal.butter(2, [8.0, 14.0], btype="bandpass", fs=120.0)
    road = signal.lfilter(b, a, rng.standard_normal((15, 2000)), axis=1)
    accel = np.sqrt(gd * speed)[:, None] / 5.0 * road + 0.3 * rng.standard_normal(road.shape)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a 30-sweep chain does not converge
        return fit_band_emulator(speed, gd, accel, noise_std=0.3, n_pc=2, n_iter=30,
                                 tune=False, seed=0, progress=progress)  # fmt: skip


def test_fit_band_emulator_passes_progress_to_the_fit(capsys):
    quiet = _fit(False)
    assert capsys.readouterr().err == ""
    shown = _fit(True)
    assert "chain 1/1: sampling" in capsys.readouterr().err
    assert quiet.model_sha256 == shown.model_sha256
    for k in quiet.draws:
        assert np.array_equal(quiet.draws[k], shown.draws[k])
