"""The symmetric two-mode case of the parallel-tempering tests: t on 11 runs of 10 (t - 0.5)^2,
eight observations at 0.9 (modes at t = 0.2 and 0.8, exact P(t > 0.5) = 1/2)."""

import numpy as np

import gpmsa


def two_mode_case() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    t = np.linspace(0.0, 1.0, 11)[:, None]
    sim = gpmsa.SimData(t=t, y=10 * (t - 0.5) ** 2)
    obs = gpmsa.ObsData(y=0.9 + 0.002 * np.array([[1], [-1], [0.5], [-0.5]] * 2))
    return sim, obs
