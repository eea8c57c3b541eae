"""Cases shared by the far-value tests: a design of 25 runs, a functional output
y = sin(3x + 2s) + t^2 s on 12 index points s and a scalar one, the MCMC of a joint fit stopped
before it samples, and the OutsideEmulatorWarnings a call gives."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import OutsideEmulatorWarning
from gpmsa.backends import numpy_backend
from gpmsa.studies import run as study_run

GRID = np.linspace(0.0, 1.0, 12)


class Sampling(Exception):
    """Raised by a stub in place of the MCMC: the sampling was reached."""


def design(m: int = 25) -> tuple[np.ndarray, np.ndarray]:
    """x and t of ``m`` runs on [0, 1], the corners (0, 1) and (1, 0) among them."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, m), rng.uniform(0, 1, m)
    x[:2], t[:2] = (0.0, 1.0), (1.0, 0.0)
    return x, t


def functional(x, t) -> np.ndarray:
    """The functional output on ``GRID``, one row per (x, t)."""
    return np.sin(3 * np.asarray(x)[:, None] + 2 * GRID) + np.asarray(t)[:, None] ** 2 * GRID


def functional_sim() -> gpmsa.SimData:
    """The functional output's runs, its index named time (s)."""
    x, t = design()
    return gpmsa.SimData(x=x, t=t, y=functional(x, t), index=GRID, x_names=["v"],
                         t_names=["k"], index_names="time", index_units="s")  # fmt: skip


def scalar_sim() -> gpmsa.SimData:
    """A scalar output's runs, y = sin(3x) + t^2."""
    x, t = design()
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2, x_names=["v"], t_names=["k"])


def stop_sampling(monkeypatch) -> None:
    """The MCMC of gpmsa.fit and gpmsa.fit_study replaced by a stop (`Sampling`)."""

    def stop(*args, **kwargs):
        raise Sampling

    monkeypatch.setattr(numpy_backend, "sample", stop)
    monkeypatch.setattr(study_run, "sample_study", stop)


def outside_texts(call) -> tuple[list[str], object]:
    """The texts of the OutsideEmulatorWarnings ``call`` gives, and its result."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    texts = [str(w.message) for w in caught if issubclass(w.category, OutsideEmulatorWarning)]
    return texts, result


def texts_before_sampling(call) -> list[str]:
    """`outside_texts` of ``call``, which must reach the (stopped) sampling."""

    def stopped():
        with pytest.raises(Sampling):
            call()

    return outside_texts(stopped)[0]
