"""Exceptions and warnings raised by vehicle."""

import sys

WRAPPER_MARK = "__vehicle_wrapper__"
"""A module whose globals set this name to True, or every module of a package whose top-level
``__init__`` sets it (control's, whose closed loop drives a `vehicle.Simulation`), is passed
over by `user_stacklevel` as vehicle's own modules are: vehicle's warnings point past it, at
the line of its caller."""


def user_stacklevel() -> int:
    """``warnings.warn``'s stacklevel, in the function that calls this, of the first frame
    outside vehicle (the user's call, however deep the library's own calls run) and outside any
    module or package marked with `WRAPPER_MARK`."""
    frame, level = sys._getframe(1), 1
    while frame is not None and _library_frame(frame.f_globals):
        frame, level = frame.f_back, level + 1
    return level


def _library_frame(names: dict) -> bool:
    top = names.get("__name__", "").split(".")[0]
    if top == "vehicle" or names.get(WRAPPER_MARK) is True:
        return True
    package = sys.modules.get(top)
    return package is not None and getattr(package, WRAPPER_MARK, False) is True


class VehicleError(ValueError):
    """Invalid input to a vehicle function (a ValueError subclass)."""


class SimulationDivergedError(RuntimeError):
    """A simulation left its numerically valid range (NaN/inf or runaway states)."""


class CampaignFileError(VehicleError):
    """A campaign file (or a cached run) is missing, damaged or of an unknown format."""


class SolverStepWarning(UserWarning):
    """The solver's fixed step is too coarse for the model's stiffest mode (results biased)."""
