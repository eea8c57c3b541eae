"""gpmsa's warnings under a third-party frame: a layer marked with ``__gpmsa_wrapper__`` whose
objective scipy's optimizer (or numpy's apply_along_axis) runs, and which calls gpmsa, had its
DomainWarning shown at scipy's _optimize.py (numpy's _shape_base_impl.py): the walk of
`gpmsa.errors.user_stacklevel` stopped at the first frame outside gpmsa. Installed code between
library frames is now passed over; a user's callback there is not (its line is shown)."""

import functools
import inspect
import types
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import gpmsa

RNG = np.random.default_rng(3)
X, T = RNG.uniform(size=(20, 1)), RNG.uniform(200.0, 600.0, size=(20, 1))
Y = np.sin(3 * X[:, 0]) + T[:, 0] / 300.0
WIDE = {"x": X, "t": T, "y": Y, "x_names": ["v"], "t_names": ["GD"], "x_range": {"v": (0, 1e12)}}
"""SimData's arguments for a DomainWarning (an x_range far wider than the design)."""

WRAPPER = """
import numpy as np
from scipy.optimize import minimize_scalar

__gpmsa_wrapper__ = True


def by_scipy(make):
    minimize_scalar(lambda v: (make(), (v - 1.0) ** 2)[1], bounds=(0.0, 2.0),
                    method="bounded", options={"maxiter": 1})


def by_numpy(make):
    np.apply_along_axis(lambda row: (make(), row)[1], 1, np.zeros((1, 1)))
"""


def _wrapper(tmp_path) -> types.ModuleType:
    """A user's library over gpmsa, marked as its wrapper (a file of its own, not installed)."""
    module = types.ModuleType("user_wrapper_s86")
    exec(compile(WRAPPER, str(tmp_path / "user_wrapper_s86.py"), "exec"), module.__dict__)
    return module


def _shown_at(call) -> set[tuple[str, int]]:
    """Where ``call()``'s DomainWarnings point (file, line)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    found = {(w.filename, w.lineno) for w in caught if issubclass(w.category, gpmsa.DomainWarning)}
    assert found
    return found


def _here() -> tuple[str, int]:
    """The caller's file and line."""
    frame = inspect.currentframe().f_back
    return frame.f_code.co_filename, frame.f_lineno


def test_a_marked_wrappers_objective_run_by_scipy_warns_at_the_wrappers_caller(tmp_path):
    wrapper, make = _wrapper(tmp_path), functools.partial(gpmsa.SimData, **WIDE)
    assert _shown_at(lambda: wrapper.by_scipy(make)) == {_here()}


def test_a_marked_wrappers_function_run_by_numpy_warns_at_the_wrappers_caller(tmp_path):
    wrapper, make = _wrapper(tmp_path), functools.partial(gpmsa.SimData, **WIDE)
    assert _shown_at(lambda: wrapper.by_numpy(make)) == {_here()}


def test_a_users_callback_run_by_the_wrapper_through_scipy_keeps_its_own_line(tmp_path):
    """Re-entrant: the user's function, run beneath gpmsa's wrapper and scipy, calls gpmsa:
    the warning is about that call, so it points there, not at the wrapper's caller."""
    lines = []

    def user_make() -> gpmsa.SimData:
        lines.append(_here())
        return gpmsa.SimData(**WIDE)  # (the line after the one recorded)

    wrapper = _wrapper(tmp_path)
    shown = _shown_at(lambda: wrapper.by_scipy(user_make))
    assert shown == {(lines[0][0], lines[0][1] + 1)}


def test_with_no_library_frame_further_out_the_first_frame_outside_is_kept():
    """A call of gpmsa in a worker thread: no user frame on that stack, the warning points at
    concurrent.futures' frame that made the call, as before (not past the stack's end)."""
    with ThreadPoolExecutor(1) as pool:
        shown = _shown_at(lambda: pool.submit(functools.partial(gpmsa.SimData, **WIDE)).result())
    ((filename, _),) = shown
    assert filename.endswith("thread.py") and "concurrent" in filename
