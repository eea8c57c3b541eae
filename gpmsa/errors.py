"""Exceptions and warnings raised by gpmsa, and the text of the numbers in their messages."""

import functools
import math
import os
import sys


class GPMSAError(ValueError):
    """Invalid input to a gpmsa function (a ValueError subclass)."""


class EmulatorFileError(GPMSAError):
    """An emulator file is damaged, foreign, of a newer schema, or unsafe to read."""


class ResourceLimitError(GPMSAError):
    """A call would need more memory (or time) than ``gpmsa.limits`` allows; the message gives
    the estimate, the limit and how to change it."""


class BackendUnavailableError(ImportError):
    """A backend's optional packages are not installed; the message names the extra to install."""


class GPMSAWarning(Warning):
    """The base of every warning gpmsa issues: ``warnings.filterwarnings("error",
    category=gpmsa.GPMSAWarning)`` turns them all into errors (a strict pipeline's CI, say)
    and leaves numpy's and other libraries' alone. Each subclass is also a ``UserWarning``
    (`ChainRetryWarning` a ``RuntimeWarning``), so filters on those catch them as well."""


class OutsideEmulatorWarning(GPMSAWarning, UserWarning):
    """An observation lies outside what the emulator has seen (far from all its predictions)."""


class AtBoundWarning(OutsideEmulatorWarning):
    """An offline calibration's posterior of a theta element piles up against a bound of the
    emulator's domain (``gpmsa.mcmc.bounds``): the data may point outside the
    simulation design, or the model misses something that theta absorbs. An
    OutsideEmulatorWarning subclass: a filter on that one covers it."""


class OutlierRunWarning(GPMSAWarning, UserWarning):
    """A simulation run's output lies far beyond every other run's at an output point (a
    missing-value code such as -999, a failed run, a units error, or an output with heavy
    tails): ``gpmsa.fit`` and ``gpmsa.fit_study`` warn before sampling
    (``gpmsa.model.far_values.far_run``)."""


class ExtrapolationWarning(GPMSAWarning, UserWarning):
    """Inputs (x, theta or bounds given to a prediction or a calibration) lie outside the
    emulator's training domain: the emulator extrapolates there (predictions, a joint fit's and
    calibration's x_obs within ``EXTRAPOLATION_MARGIN`` of it, further refused; with
    ``extrapolate=True`` at any distance: calibration's x_obs, the x of ``calibrated_predict``
    and ``full_prediction``, the x and t of ``Emulator.predict`` and ``emulator_prediction``)."""


WRAPPER_MARK = "__gpmsa_wrapper__"
"""A module whose globals set this name to True (a library's thin layer over `gpmsa.fit`, say),
or every module of a package whose top-level ``__init__`` sets it (control's), is passed over
by `user_stacklevel` as gpmsa's own modules are: gpmsa's warnings point past it, at the line
of its caller."""


def user_stacklevel() -> int:
    """``warnings.warn``'s stacklevel, in the function that calls this, of the first frame
    outside gpmsa (the user's call, however deep the library's own calls run), outside any
    module or package marked with `WRAPPER_MARK` and outside ``dataclasses`` (whose
    ``replace`` makes a settings class anew: its ``__post_init__``'s warnings point at the
    line that called ``replace``). A frame of the standard library or of an installed package
    with a library frame further out (scipy's optimizer calling a marked wrapper's objective,
    which calls gpmsa) is passed over too; a user's own function there (a callback that calls
    gpmsa) is not: the warning points at its line."""
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
    if top in ("gpmsa", "dataclasses") or names.get(WRAPPER_MARK) is True:
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


def numbers_text(*values: float, digits: int = 6) -> tuple[str, ...]:
    """``values`` (a value and the range it is checked against, say) as text for a message:
    ``digits`` significant digits, more (up to 17) where two distinct values would read alike,
    so that 1e6 + 1.5 and the range [1e6 + 0.02, 1e6 + 0.99] do not all read "1e+06": then
    three significant digits of the difference of each two neighbouring values (relative to
    their size, not to the largest value's: 0.1 and 0.1000001 beside 1e12 read so)."""
    texts = tuple(f"{float(v):.{digits}g}" for v in values)
    finite = sorted({float(v) for v in values if math.isfinite(v)})
    if len({f"{v:.{digits}g}" for v in finite}) == len(finite):  # (the usual case)
        return texts
    pairs = zip(finite, finite[1:], strict=False)
    spread = max(max(abs(a), abs(b)) / (b - a) for a, b in pairs)  # (b - a > 0: distinct)
    need = math.ceil(math.log10(spread)) + 3 if math.isfinite(spread) else 17
    digits = min(17, max(digits, need))
    return tuple(f"{float(v):.{digits}g}" for v in values)


class DomainWarning(GPMSAWarning, UserWarning):
    """A unit domain given to ``SimData(x_range=, t_range=)`` is far wider than its design
    column spans (below ``gpmsa.model.data.RANGE_COVER_MIN`` of it: a unit mistake?): the
    runs then fill a sliver of [0, 1], and the fit can no longer resolve that input."""


class BasisWarning(GPMSAWarning, UserWarning):
    """A user-supplied emulator basis gives the runs weights on a scale that the priors do not
    expect (``gpmsa.fit(..., basis=)``)."""


class ReductionWarning(GPMSAWarning, UserWarning):
    """The observations as reduced may not say what the data say
    (``gpmsa.model.problem.reduce_obs``): their precisions declare an error larger than the
    simulation outputs' spread (a variance passed for a precision?)."""


class StartRejectedError(GPMSAError):
    """The theta constraint rejects the chains' start, or no random start inside it was found.

    ``remedy`` maps the keyword arguments that give an allowed start to the value they need
    (``...``: the user's own, e.g. ``{"theta_init": ...}`` or ``{"init": "gpmsa",
    "theta_init": ...}``), so a caller that passes them under other names (the Calibrator's
    ``mcmc_options``) can say so without reading the message.
    """

    def __init__(self, message: str, remedy: dict | None = None):
        super().__init__(message)
        self.remedy = dict(remedy or {})


class ChainError(GPMSAError):
    """A chain failed (its task raised, its worker died, or its draws are not finite).

    ``chains`` lists the indices (0-based) of the chains concerned; the message names them.
    """

    def __init__(self, message: str, chains: tuple[int, ...] = ()):
        super().__init__(message)
        self.chains = tuple(chains)


class ConvergenceWarning(GPMSAWarning, UserWarning):
    """Several chains disagree (R-hat above its limit) or give too few effective draws."""


class GridResolutionWarning(GPMSAWarning, UserWarning):
    """A grid `Calibrator`'s grid does not resolve the posterior (or a ``prior=`` given on it):
    its summaries and draws may be off; the message says by how much and what to change
    (a larger ``n_grid``, ``method="mcmc"``, a prior as a callable)."""


class FewDrawsWarning(GPMSAWarning, UserWarning):
    """Too few realizations for a prediction's central interval to resolve its tails
    (``interval``): it reads too narrow; the message names the option that draws more."""


class NuggetWarning(GPMSAWarning, UserWarning):
    """A fit's point estimate gives a covariance that does not factor in float64 (its nugget
    below rounding): the predictive functions refuse the emulator; the message names the
    component and the remedy."""


class UnusedSettingWarning(GPMSAWarning, UserWarning):
    """A setting given that the chosen option does not use (``HyperPriors(lam_a=)`` with
    ``sd_prior="uniform"``): the message names the option that would use it."""


class ChainRetryWarning(GPMSAWarning, RuntimeWarning):
    """A chain's task failed for a reason other than its input (a lost worker, say) and runs
    again with the same seed; a second failure is a `ChainError`."""
