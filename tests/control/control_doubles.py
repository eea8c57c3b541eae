"""Test doubles for control: a calibrator and a block model with known likelihoods, and a
synthetic sensor stream."""

import functools
from types import SimpleNamespace

import numpy as np

from gpmsa.model.transforms import Standardizer

C = 0.05  # f = C * GD * v**1.3 (m/s^2)^2, a made-up but realistic-looking law
SIGMA = 0.06  # spread of log f for one 1,000-sample window of white noise (sqrt(2/1000) ~ 0.045)


def log_f(v, gd):
    return np.log(C) + np.log(gd) + 1.3 * np.log(v)


class FakeCalibrator:
    """Gaussian likelihood of y = log f on a grid: the part of gpmsa.Calibrator the BCR uses."""

    def __init__(self, metadata=None, v_range=(0.5, 2.0)):
        self.emulator = SimpleNamespace(
            domain={"v": tuple(v_range), "GD": (200.0, 600.0)},
            standardizer=Standardizer(
                x_min=np.array([v_range[0]]),
                x_max=np.array([v_range[1]]),
                t_min=np.array([200.0]),
                t_max=np.array([600.0]),
                y_mean=np.zeros(1),
                y_sd=1.0,
                grid=np.zeros(1),
            ),
            x_names=["v"],
            t_names=["GD"],
            metadata=metadata or {},
        )
        self.grid = np.linspace(200.0, 600.0, 401)
        self.calls = 0

    def log_likelihood_grid(self, x_obs, y_obs):
        self.calls += 1
        v = float(np.asarray(x_obs).ravel()[0])
        y = float(np.asarray(y_obs).ravel()[0])
        return self.grid, -0.5 * ((y - log_f(v, self.grid)) / SIGMA) ** 2


def stream(gd_of_position, speed, duration_s, rate_hz=120.0, seed=0, t0=0.0, s0=0.0):
    """White-noise accelerations whose variance follows f = C GD v^1.3 at constant speed."""
    rng = np.random.default_rng(seed)
    n = int(round(duration_s * rate_hz))
    t = t0 + np.arange(1, n + 1) / rate_hz
    pos = s0 + speed * (t - t0)
    f = np.exp(log_f(speed, gd_of_position(pos)))
    acc = rng.standard_normal(n) * np.sqrt(f)
    return t, pos, acc, np.full(n, float(speed))


@functools.cache
def _unit_statistics(spec):
    """(mean, Cholesky factor of the covariance) of the block features of unit-variance white
    noise (8,000 blocks, seed 123) for a FeatureSpec: computed once a spec (~0.1 s) and shared,
    read-only, by every FakeBlockModel of that spec."""
    from control.feature import block_features

    unit = np.random.default_rng(123).standard_normal((8000, spec.block_samples))
    feats = block_features(unit, spec)
    offset, chol = feats.mean(axis=0), np.linalg.cholesky(np.cov(feats.T))
    offset.setflags(write=False)
    chol.setflags(write=False)
    return offset, chol


class FakeBlockModel:
    """The part of control.ObservationModel the BCR uses, for white-noise blocks of `stream`.

    A white-noise block of variance f has log band powers log f + m and quantiles (less the
    mean) sqrt(f) u, where m and u have a distribution that does not depend on f; their mean
    and covariance are estimated once from unit-variance noise, so the likelihood of GD for a
    `stream` block is Gaussian in (bands - log f, quantiles / sqrt(f)), with the Jacobian
    f^(-1/2) of each quantile.
    """

    def __init__(self, spec=None, v_range=(0.5, 2.0)):
        from control.feature import FeatureSpec

        self.spec = spec or FeatureSpec()
        self.offset, self.chol = _unit_statistics(self.spec)
        self.dim = self.offset.size
        self.n_quantiles = len(self.spec.quantiles)
        self.gd = np.geomspace(200.0, 600.0, 121)
        self.speed_range = tuple(v_range)
        self.emulator = SimpleNamespace(t_names=["GD"], x_names=["v"])
        self.calls = 0

    def _whitened(self, y, v):
        lf = log_f(v, self.gd)[:, None]  # (G, 1)
        y = np.asarray(y)[None, :]
        nb = self.dim - self.n_quantiles
        unit = np.concatenate([y[:, :nb] - lf, y[:, nb:] / np.exp(0.5 * lf)], axis=1)
        return np.linalg.solve(self.chol, (unit - self.offset[None, :]).T), lf[:, 0]  # (K, G)

    def _d2(self, y, v):
        return np.sum(self._whitened(y, v)[0] ** 2, axis=0)

    def level_score(self, y, v, direction):
        r, lf = self._whitened(y, v)
        best = int(np.argmin(np.sum(r**2, axis=0)))
        nb = self.dim - self.n_quantiles
        unit = np.concatenate([direction[:nb], direction[nb:] / np.exp(0.5 * lf[best])])
        w = np.linalg.solve(self.chol, unit)
        return float(w @ r[:, best] / np.sqrt(w @ w))

    def loglik(self, y, v):
        self.calls += 1
        jacobian = -0.5 * self.n_quantiles * log_f(v, self.gd)
        return -0.5 * self._d2(y, v) + jacobian

    def plausibility(self, y, v):
        from scipy.stats import chi2

        d2 = float(np.min(self._d2(y, v)))
        return d2, float(chi2.sf(d2, self.dim))


def plotted_run_and_track():
    """(a closed-loop result's traces, a two-segment track): the parts of ClosedLoopResult and
    roadgen.Track that the figures read, 50 estimates over GD 300 / 500."""
    track = SimpleNamespace(
        segments=((50.0, 300.0), (50.0, 500.0)), boundaries_m=(0.0, 50.0), length_m=100.0
    )
    pos = np.linspace(10, 100, 50)
    run = SimpleNamespace(
        position=pos,
        gd_mean=np.full(50, 350.0),
        gd_lo=np.full(50, 300.0),
        gd_hi=np.full(50, 400.0),
        sample_position=pos,
        sample_speed=np.full(50, 1.5),
    )
    return run, track


def bcr_of(kind: str):
    """A BCR on the doubles: "changepoint" (on `FakeBlockModel`), "static span" (the same with
    the static-level check's ring of 300 samples at standard gravity), or a window method's name
    (on `FakeCalibrator`, the paper's window)."""
    import control
    from control.feature import STANDARD_GRAVITY

    if kind == "changepoint":
        return control.BCR(FakeBlockModel())
    if kind == "static span":  # the static-level check's ring too
        limits = control.SensorLimits(static_mps2=STANDARD_GRAVITY, static_span=300)
        return control.BCR(FakeBlockModel(), sensor=limits)
    return control.BCR(FakeCalibrator(), method=kind, feature=control.PAPER_WINDOW)
