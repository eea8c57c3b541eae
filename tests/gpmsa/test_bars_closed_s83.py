"""A chain's progress bar is closed when the chain stops on an error or a Ctrl-C, as when it
ends: a bar left open (held by the traceback, as IPython and Jupyter keep the last one) stayed
in tqdm's list of bars, and every later bar was drawn a line lower, below the dead one."""

import warnings

import numpy as np
import pytest
from _study_cases import emulator, observations

import gpmsa
from gpmsa import _progress


@pytest.fixture
def bars(monkeypatch):
    """The bars made while the test runs; each raises KeyboardInterrupt (a Ctrl-C) at its
    first update, as a chain interrupted mid-run."""
    made = []
    real = _progress._bar_class()

    class Interrupted(real):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

        def update(self, n=1):
            super().update(n)
            raise KeyboardInterrupt

    monkeypatch.setattr(_progress, "_bar_class", lambda: Interrupted)
    return made


def _data() -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(15, 1)), rng.uniform(size=(15, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(2 * x + t), x_names=["x"], t_names=["t"])


@pytest.mark.parametrize("options", [{}, {"temperatures": (1.0, 2.0)}], ids=["plain", "tempered"])
def test_an_interrupted_fit_closes_its_chain_bar(bars, options):
    with pytest.raises(KeyboardInterrupt), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gpmsa.fit(_data(), n_iter=300, n_chains=1, tune=False, seed=0, progress=True, **options)
    assert len(bars) == 1 and bars[0].disable  # tqdm's close sets it


@pytest.mark.parametrize("options", [{}, {"temperatures": (1.0, 2.0)}], ids=["plain", "tempered"])
def test_an_interrupted_study_closes_its_chain_bar(bars, options):
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    with pytest.raises(KeyboardInterrupt), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gpmsa.calibrate_study(
            [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data],
            hierarchical=["t"], n_samples=300, n_burn=0, tune=False, seed=5, progress=True,
            **options,
        )  # fmt: skip
    assert len(bars) == 1 and bars[0].disable
