"""Exceptions and warnings raised by vehicle."""

import functools
import os
import sys

WRAPPER_MARK = "__vehicle_wrapper__"
"""A module whose globals set this name to True, or every module of a package whose top-level
``__init__`` sets it (control's, whose closed loop drives a `vehicle.Simulation`), is passed
over by `user_stacklevel` as vehicle's own modules are: vehicle's warnings point past it, at
the line of its caller."""


def user_stacklevel() -> int:
    """``warnings.warn``'s stacklevel, in the function that calls this, of the first frame
    outside vehicle (the user's call, however deep the library's own calls run) and outside any
    module or package marked with `WRAPPER_MARK`. A frame of the standard library or of an
    installed package with a library frame further out (a marked wrapper's callback run by
    scipy or numpy) is passed over too; a user's own function there is not (as
    ``gpmsa.errors.user_stacklevel``)."""
    frames = []  # (a library frame?, its code's file), the caller's first
    frame = sys._getframe(1)
    while frame is not None:
        frames.append((_library_frame(frame.f_globals), frame.f_code.co_filename))
        frame = frame.f_back
    outermost = max((i for i, (own, _) in enumerate(frames) if own), default=-1)
    for i, (own, filename) in enumerate(frames):
        if not (own or (i < outermost and _installed_frame(filename))):
            return i + 1
    return len(frames) + 1


def _library_frame(names: dict) -> bool:
    top = names.get("__name__", "").split(".")[0]
    if top == "vehicle" or names.get(WRAPPER_MARK) is True:
        return True
    package = sys.modules.get(top)
    return package is not None and getattr(package, WRAPPER_MARK, False) is True


def _installed_frame(filename: str) -> bool:
    """Whether ``filename`` (a frame's code's) is the standard library's or an installed
    package's (frozen modules' ``<frozen ...>`` included): never the user's script."""
    if filename.startswith("<"):  # <frozen runpy>; <string>, <stdin>, a notebook's <ipython-...>
        return filename.startswith("<frozen ")
    return os.path.normcase(os.path.abspath(filename)).startswith(_installed_roots())


@functools.cache
def _installed_roots() -> tuple[str, ...]:
    import site
    import sysconfig

    paths = sysconfig.get_paths()
    roots = {paths[k] for k in ("stdlib", "platstdlib", "purelib", "platlib")}
    roots.update(site.getsitepackages() if hasattr(site, "getsitepackages") else ())
    roots.add(site.getusersitepackages())
    both = roots | {os.path.realpath(r) for r in roots}
    return tuple(os.path.join(os.path.normcase(os.path.abspath(r)), "") for r in both)


class VehicleError(ValueError):
    """Invalid input to a vehicle function (a ValueError subclass)."""


class SimulationDivergedError(RuntimeError):
    """A simulation left its numerically valid range (NaN/inf or runaway states)."""


class CampaignFileError(VehicleError):
    """A campaign file (or a cached run) is missing, damaged or of an unknown format."""


class SolverStepWarning(UserWarning):
    """The solver's fixed step is too coarse for the model's stiffest mode (results biased)."""
