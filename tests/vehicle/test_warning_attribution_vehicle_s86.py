"""vehicle's SolverStepWarning under a third-party frame. A campaign warned at the user's call,
then again in each run: from a process pool's workers on stderr at concurrent/futures/
process.py:261, once a worker; with a thread executor one more warning a run, recorded at
concurrent/futures/thread.py:58. And a layer marked ``__vehicle_wrapper__`` that makes a
Simulation in an objective scipy runs had it shown at scipy's _optimize.py."""

import functools
import inspect
import types
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import vehicle

STIFF = vehicle.Jackal(tyre_stiffness_n_per_m=1e6, lift_off=False)
"""A 75 Hz mode: too fast for the default 5 substeps (a SolverStepWarning)."""

WRAPPER = """
from scipy.optimize import minimize_scalar

__vehicle_wrapper__ = True


def by_scipy(make):
    minimize_scalar(lambda v: (make(), (v - 1.0) ** 2)[1], bounds=(0.0, 2.0),
                    method="bounded", options={"maxiter": 1})
"""


def _shown_at(call) -> list[tuple[str, int]]:
    """Where ``call()``'s SolverStepWarnings point (file, line), one entry per warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    return [(w.filename, w.lineno) for w in caught if w.category is vehicle.SolverStepWarning]


def _here() -> tuple[str, int]:
    """The caller's file and line."""
    frame = inspect.currentframe().f_back
    return frame.f_code.co_filename, frame.f_lineno


def test_a_campaign_warns_of_a_coarse_step_once_at_the_users_call():
    design = np.array([[0.7, 250.0], [1.6, 550.0]])
    short = {"road_length_m": 6.0, "window": 300, "lead_in_m": 0.5, "progress": False}
    with ThreadPoolExecutor(1) as ex:
        run = functools.partial(vehicle.run_campaign, design, model=STIFF, executor=ex, **short)
        assert _shown_at(lambda: run(seed=1)) == [_here()]


def test_a_marked_wrappers_objective_run_by_scipy_warns_at_the_wrappers_caller(
    tmp_path, rough_road
):
    module = types.ModuleType("user_vehicle_wrapper_s86")
    exec(compile(WRAPPER, str(tmp_path / "user_vehicle_wrapper_s86.py"), "exec"), module.__dict__)
    make = functools.partial(vehicle.Simulation, STIFF, rough_road)
    assert set(_shown_at(lambda: module.by_scipy(make))) == {_here()}
