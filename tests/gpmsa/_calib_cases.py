"""Shared cases for the calibration tests: the road case and small synthetic emulators."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import numpy as np

import gpmsa
from gpmsa.fitting.emulator import Emulator

DATA = Path(__file__).parent.parent / "data"


@cache
def road_case() -> dict:
    """case.npz as a dict of arrays, plus the SEPIA calibration-only reference."""
    case = dict(np.load(DATA / "case.npz", allow_pickle=False))
    ref = json.loads((DATA / "reference_posteriors.json").read_text())
    case["sepia_calibration_only"] = ref["sepia_calibration_only"]
    return case


@cache
def road_emulator() -> Emulator:
    """The road case's emulator at SEPIA's fixed (calibration-only) parameter values."""
    case = road_case()
    sim = gpmsa.SimData(
        x=case["v"][:, None], t=case["GD"][:, None], y=case["f"][:, None],
        x_names=["v"], t_names=["GD"], y_names=["f"],
    )  # fmt: skip
    params = case["sepia_calibration_only"]["fixed_emulator_params_unit_scale"]
    return Emulator.from_params(sim, params)


def road_obs() -> tuple[list[list[float]], list[list[float]]]:
    """The road case's single observation (x_obs, y_obs), native units."""
    case = road_case()
    return [[float(case["v_obs"][0])]], [[float(case["f_obs"][0])]]


@cache
def two_param_emulator() -> Emulator:
    """A scalar-output emulator with one x and two calibration parameters (q = 2)."""
    rng = np.random.default_rng(7)
    m = 60
    x = rng.uniform(0, 1, m)
    t = rng.uniform(0, 1, (m, 2))
    y = np.sin(2.0 * x + 1.5 * t[:, 0]) + 0.8 * t[:, 1] * x
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y[:, None], x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[1.0], [1.5], [0.8]], "lamUz": [1.0], "lamWs": [5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    return Emulator.from_params(sim, params)


@cache
def vector_emulator() -> Emulator:
    """A vector-output emulator (l_sim = 8 on a grid, p_u = 2) with one x and one parameter."""
    rng = np.random.default_rng(11)
    m = 40
    x = rng.uniform(0, 1, m)
    t = rng.uniform(0, 1, m)
    grid = np.linspace(0, 1, 8)
    y = (1.0 + t[:, None]) * np.sin(np.pi * grid[None, :] * (0.5 + x[:, None])) + 0.3 * t[:, None]
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=y, index=grid, x_names=["x"], t_names=["t"])
    params = {"betaU": [[1.0, 1.0], [1.0, 1.0]], "lamUz": [1.0, 1.0], "lamWs": [5000.0, 5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    return Emulator.from_params(sim, params, n_pc=2)


def with_draws(emu: Emulator, n: int = 5, seed: int = 3) -> Emulator:
    """A copy of ``emu`` with ``n`` retained draws: its parameters perturbed by 10 % (lognormal)."""
    rng = np.random.default_rng(seed)
    draws = {
        k: np.stack([v * np.exp(0.1 * rng.standard_normal(v.shape)) for _ in range(n)])
        for k, v in emu.params.items()
    }
    out = Emulator(
        standardizer=emu.standardizer, x_unit=emu.x_unit, t_unit=emu.t_unit, y=emu.y, K=emu.K,
        w=emu.w, index=emu.index, params=emu.params, priors=emu.priors,
        names={"x": emu.x_names, "t": emu.t_names, "y": emu.y_names},
        units={"x": emu.x_units, "t": emu.t_units, "y": emu.y_units},
        draws=draws, log_post=np.zeros(n), levels=emu.levels, mean_basis=emu.mean_basis,
    )  # fmt: skip
    return out


@cache
def categorical_emulator() -> Emulator:
    """30 runs of y = x + (0, 1, -0.7)[t] with a categorical calibration parameter t0 of three
    levels, at fixed parameters."""
    rng = np.random.default_rng(0)
    x, t = rng.random(30), np.arange(30) % 3
    sim = gpmsa.SimData(x, t, x + np.array([0.0, 1.0, -0.7])[t], t_categorical=[0])
    return Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3],
                                      "lamWOs": [1e3]})  # fmt: skip


def one_t_emulator() -> tuple[Emulator, list, list]:
    """A 1-parameter emulator (y = x + t, t in [0, 1], centre 0.5) at fixed parameters, and one
    observation near t = 0.8: (emulator, x_obs, y_obs)."""
    rng = np.random.default_rng(0)
    x, t = rng.random(16), rng.random(16)
    sim = gpmsa.SimData(x[:, None], t[:, None], (x + t)[:, None], x_names=["x"], t_names=["t"])
    emu = Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3],
                                     "lamWOs": [1e3]})  # fmt: skip
    return emu, [[0.5]], [[1.3]]


def recorded_edge_prior(edge: float, shapes: list):
    """A callable log prior on one parameter, zero (-inf) below ``edge`` and flat above, that
    appends the shape of every array it is called with to ``shapes``."""

    def prior(t):
        shapes.append(np.shape(t))
        return np.where(np.asarray(t) < edge, -np.inf, 0.0)

    return prior


@cache
def sine_sum_emulator(q: int, runs: int, n_iter: int, prefix: str = "t") -> Emulator:
    """``runs`` runs of y = sin(3 x) + sum(t) (one scalar output, q calibration parameters named
    prefix0, prefix1, ...), an untuned fit of ``n_iter`` sweeps (its retained draws)."""
    import warnings

    rng = np.random.default_rng(81)
    x, t = rng.uniform(size=(runs, 1)), rng.uniform(size=(runs, q))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x[:, 0]) + t.sum(axis=1), x_names=["x"],
                         t_names=[f"{prefix}{k}" for k in range(q)])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, n_iter=n_iter, tune=False, seed=0)


def one_component_functional() -> tuple[Emulator, np.ndarray]:
    """(emulator, output grid): 10 runs of a 4-value output linear in x and t, one principal
    component, at fixed parameters (the observation-reduction tests' functional case)."""
    x = np.linspace(0.0, 1.0, 10)
    t = np.random.default_rng(1).permutation(np.linspace(0.0, 1.0, 10))
    grid = np.linspace(0.0, 1.0, 4)
    y = (1.0 + x[:, None] + t[:, None]) * (1.0 + grid[None, :])
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=y, index=grid, x_names=["x"], t_names=["t"])
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}
    return Emulator.from_params(sim, params, n_pc=1), grid
