"""Warnings of gpmsa and vehicle under control's calls point at the user's line: a stiff
robot's SolverStepWarning from the closed loop's simulation pointed at control/closed_loop.py
(vehicle's fixed stacklevel), and gpmsa's warnings stopped at control's frames. control marks
itself as a wrapper of both (``__gpmsa_wrapper__``, ``__vehicle_wrapper__``)."""

import sys
import types
import warnings

import pytest

import control
import gpmsa
import roadgen
import vehicle


def test_a_stiff_robots_solver_warning_in_the_closed_loop_points_at_the_users_call():
    stiff = vehicle.Jackal(tyre_stiffness_n_per_m=1e6, lift_off=False)
    track = roadgen.track([(3.0, 300.0)], seed=1)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        control.run_closed_loop(track, control.shipped_emulator("A"), model=stiff, seed=1,
                                check=False)  # fmt: skip
    solver = [w for w in got if issubclass(w.category, vehicle.SolverStepWarning)]
    assert [w.filename for w in solver] == [__file__], [(w.filename, w.lineno) for w in got]


def test_vehicles_direct_calls_still_point_at_the_users_call():
    stiff = vehicle.Jackal(tyre_stiffness_n_per_m=1e6, lift_off=False)
    track = roadgen.track([(3.0, 300.0)], seed=1)
    with pytest.warns(vehicle.SolverStepWarning) as got:
        vehicle.Simulation(stiff, track)
    assert [w.filename for w in got] == [__file__]


@pytest.fixture
def marked_package(monkeypatch):
    """A package whose ``__init__`` marks it as gpmsa's and vehicle's wrapper, and a module of
    it (unmarked itself) whose function makes a gpmsa and a vehicle warning."""
    package = types.ModuleType("wrapper_pkg_s82")
    package.__gpmsa_wrapper__ = package.__vehicle_wrapper__ = True
    module = types.ModuleType("wrapper_pkg_s82.inner")
    code = (
        "import gpmsa, vehicle\n"
        "from vehicle.linear import warn_if_step_too_coarse\n"
        "def call():\n"
        "    gpmsa.HyperPriors(lam_a=2.0)\n"
        "    warn_if_step_too_coarse(vehicle.Jackal(tyre_stiffness_n_per_m=1e6, lift_off=False),"
        " 120.0, 5)\n"
    )
    exec(compile(code, "/wrapper_pkg_s82/inner.py", "exec"), module.__dict__)
    monkeypatch.setitem(sys.modules, "wrapper_pkg_s82", package)
    monkeypatch.setitem(sys.modules, "wrapper_pkg_s82.inner", module)
    return module


def test_a_package_marked_in_its_init_is_passed_over(marked_package):
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        marked_package.call()
    assert {(w.category, w.filename) for w in got} == {
        (gpmsa.UnusedSettingWarning, __file__),
        (vehicle.SolverStepWarning, __file__),
    }, [(w.filename, w.lineno) for w in got]
