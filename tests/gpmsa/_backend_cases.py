"""Problems shared by the backend tests: the road case and a small multivariate case."""

import sys
import textwrap
from pathlib import Path
from types import ModuleType

import numpy as np

import gpmsa
from gpmsa import backends
from gpmsa.model.problem import Prepared, prepare

DATA = Path(__file__).parents[1] / "data" / "case.npz"


def road_data() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """The road case: 198 runs over (v, GD), scalar output f, one observation at v = 1.25."""
    d = np.load(DATA)
    sim = gpmsa.SimData(x=d["v"][:, None], t=d["GD"][:, None], y=d["f"][:, None],
                        x_names=["v"], t_names=["GD"])  # fmt: skip
    obs = gpmsa.ObsData(x=d["v_obs"][:, None], y=d["f_obs"][:, None])
    return sim, obs


def multi_data(seed: int = 0) -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """A small multivariate case: 24 runs, output on a 15-point grid, two experiments."""
    rng = np.random.default_rng(seed)
    m, grid = 24, np.linspace(0.0, 1.0, 15)
    x = (rng.permutation(m) + rng.random(m)) / m
    t = (rng.permutation(m) + rng.random(m)) / m

    def model(x, t):
        return np.sin(2.0 * grid[None, :] * (1.0 + t[:, None])) * (1.0 + x[:, None])

    y = model(x, t)
    x_obs = np.array([0.3, 0.7])
    y_obs = model(x_obs, np.array([0.4, 0.4])) + 0.02 * rng.normal(size=(2, grid.size))
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=y, index=grid)
    return sim, gpmsa.ObsData(x=x_obs[:, None], y=y_obs)


def road_problem(with_obs: bool = True) -> Prepared:
    """Prepared road-case problem (joint sim + obs, or simulation-only)."""
    sim, obs = road_data()
    return prepare(sim, obs if with_obs else None)


def multi_problem(discrepancy=None) -> Prepared:
    """Prepared multivariate problem (joint sim + obs)."""
    sim, obs = multi_data()
    return prepare(sim, obs, discrepancy=discrepancy)


def installed_plugin(monkeypatch, folder: Path, module: str, source: str) -> ModuleType:
    """A plug-in backend in the user's project: ``source`` written as ``folder/module.py``,
    importable from there and registered by its import path as "mine" (the caller restores the
    registry, and drops the module from ``sys.modules`` afterwards)."""
    (folder / f"{module}.py").write_text(textwrap.dedent(source), encoding="utf-8")
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.delitem(sys.modules, module, raising=False)
    backends.register("mine", module)
    return backends.get("mine")
