"""Calibration of the uncertainty: 90% intervals cover the truth 85-95% of the time."""

import numpy as np
import pytest
from _calib_cases import road_emulator

from gpmsa import Calibrator
from gpmsa.calibration.observations import fixed_gp

N_OBS = 300


@pytest.mark.filterwarnings("ignore::gpmsa.errors.OutsideEmulatorWarning")  # 1 in 300 draws
def test_intervals_cover_truth_drawn_from_the_model():
    """Truth (GD, lamOs) from the priors, the observation from the emulator's own predictive."""
    emu = road_emulator()
    cal, gp, std = Calibrator(emu), fixed_gp(emu), emu.standardizer
    lo, hi = emu.domain["v"]
    rng = np.random.default_rng(123)
    hits = 0
    for _ in range(N_OBS):
        theta, lam, v = rng.uniform(0, 1), rng.gamma(1.0, 1000.0), rng.uniform(lo, hi)
        mean, cov = gp.predict(std.x_to_unit([[v]]), np.array([[theta]]))
        u = mean[0, 0, 0] + np.sqrt(cov[0, 0, 0, 0] + 1 / lam) * rng.standard_normal()
        a, b = cal.update([[v]], [[u * std.y_sd + std.y_mean[0]]]).interval("GD", 0.9)
        hits += a <= std.t_from_unit([[theta]])[0, 0] <= b
    assert 0.85 <= hits / N_OBS <= 0.95


def test_intervals_cover_truth_from_the_generating_formula():
    """Truth GD uniform on the domain; f = 0.02 GD v^1.6 (1 + 0.05 z), as the road case."""
    emu = road_emulator()
    cal = Calibrator(emu)
    (v_lo, v_hi), (gd_lo, gd_hi) = emu.domain["v"], emu.domain["GD"]
    rng = np.random.default_rng(321)
    hits = 0
    for _ in range(N_OBS):
        gd, v = rng.uniform(gd_lo, gd_hi), rng.uniform(v_lo, v_hi)
        f = 0.02 * gd * v**1.6 * (1 + 0.05 * rng.standard_normal())
        a, b = cal.update([[v]], [[f]]).interval("GD", 0.9)
        hits += a <= gd <= b
    assert 0.85 <= hits / N_OBS <= 0.95
