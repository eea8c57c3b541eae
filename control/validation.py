"""Type checks of the settings' fields: a string or None where a number belongs is named in a
`ControlError`, before any numpy comparison fails on it with a message about ufuncs."""

from __future__ import annotations

import os
from dataclasses import fields, is_dataclass, replace
from numbers import Integral, Real
from pathlib import Path

import numpy as np

from control.errors import ControlError
from gpmsa import limits
from roadgen import checks


def is_real(value) -> bool:
    """Whether ``value`` is a real number that numpy holds as one (a bool, Python's or numpy's,
    is not; nor an int beyond 64 bits or a Fraction: numpy keeps those as objects, and its
    comparisons and ufuncs fail on them)."""
    if type(value) is float:  # (the usual case, first: the ABC check below costs ~0.3 us)
        return True
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real):
        return False
    if isinstance(value, float | np.floating | np.integer):
        return True
    if isinstance(value, int):
        return -(2**63) <= value < 2**64
    return np.asarray(value).dtype.kind in "iuf"


def is_integer(value) -> bool:
    """Whether ``value`` is an integer (a bool, Python's or numpy's, is not; 3.0 is not)."""
    return isinstance(value, Integral) and not isinstance(value, (bool, np.bool_))


def is_choice(value, allowed: tuple) -> bool:
    """Whether ``value`` is one of the strings ``allowed`` (an array or another non-string is
    not: ``array in allowed`` would raise numpy's "truth value ... is ambiguous")."""
    return isinstance(value, str) and value in allowed


def within(value: float, lo: float, hi: float) -> bool:
    """Whether ``value`` lies in [lo, hi], its ends widened by 1e-9 of the width (rounding of a
    speed at the emulator's domain edge is inside)."""
    tol = 1e-9 * (hi - lo)
    return lo - tol <= value <= hi + tol


def path_argument(value, name: str, of: str = "") -> Path:
    """``value`` (a str or os.PathLike, not empty) as a Path, a leading ``~`` (alone or before a
    separator) the home folder (``roadgen.checks.home_path``; a folder named "~" was made);
    ControlError naming the argument ``name`` for anything else (None, a number, ""); ``of``
    says what the path is of."""
    try:  # a path-like whose __fspath__ gives bytes, or neither str nor bytes: refused too
        text = os.fspath(value) if isinstance(value, str | os.PathLike) else None
    except TypeError:
        text = None
    if not isinstance(text, str) or not text:
        raise ControlError(
            f"{name} must be the path (a str or os.PathLike){of}, got {value!r:.60} "
            f"({type(value).__name__}"
            + ("; decode bytes with os.fsdecode" if isinstance(text or value, bytes) else "")
            + ")"
        )
    return checks.home_path(value)


def check_lookup(path: Path, name: str, error: type[ControlError] = ControlError) -> None:
    """``error`` naming the argument ``name`` where the OS cannot look ``path`` up: a name too
    long for the file system, a folder on the way that cannot be searched, a NUL byte or a
    character the file system's encoding cannot write (a lone surrogate). A missing path (or one
    below a file) passes, as does a link (not followed): the caller says what it needs there.
    Python 3.11's ``Path.exists``/``is_dir`` raise such errors as a bare OSError or ValueError."""
    try:
        os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return
    except UnicodeEncodeError as exc:
        bad = exc.object[exc.start : exc.end]
        raise error(
            f"{name}={str(path)!r}: the path holds {bad!r}, which the file system's encoding "
            f"({exc.encoding}) cannot write"
        ) from None
    except ValueError as exc:  # "embedded null byte"
        raise error(f"{name}={str(path)!r} is not a usable path ({exc})") from None
    except OSError as exc:  # e.g. ENAMETOOLONG, EACCES
        raise error(f"{name}={str(path)!r}: cannot look it up ({exc.strerror or exc})") from None


def check_not_masked(values, name: str) -> None:
    """ControlError naming ``name`` for a numpy masked array: converted, its mask would be read
    as data."""
    if isinstance(values, np.ma.MaskedArray):
        raise ControlError(
            f"{name} is a masked array: give NaN for missing samples ({name}.filled(np.nan))"
        )


def float_array(values, name: str) -> np.ndarray:
    """``values`` as a new float array; ControlError naming ``name`` unless they are real
    numbers (ints or floats: not bools, strings such as "1.5", complex numbers, objects or a
    masked array; ``roadgen.checks.real_array`` with control's error). NaN and inf pass."""
    check_not_masked(values, name)
    return checks.real_array(name, values, ControlError)


def check_n_draws(n_draws) -> None:
    """ControlError unless ``n_draws`` (posterior draws made for histograms) is an integer >= 1;
    gpmsa.ResourceLimitError, as ``gpmsa.Calibrator(n_draws=)``, when they would need more than
    ``gpmsa.limits.MAX_MEMORY_BYTES`` (they are drawn lazily, when first read)."""
    if not (is_integer(n_draws) and n_draws >= 1):
        raise ControlError(f"n_draws must be an integer >= 1, got {n_draws!r}")
    limits.check_memory(24.0 * n_draws, f"posterior(n_draws={n_draws}): the draws of GD")


def check_posterior_name(name) -> None:
    """ControlError unless ``name`` (the posterior's name of GD) is a non-empty str."""
    if not isinstance(name, str) or not name:
        raise ControlError(f"name must be the parameter's name (a non-empty str), got {name!r:.60}")


def require_reals(obj, names: tuple[str, ...], optional: tuple[str, ...] = ()) -> None:
    """ControlError naming the first of ``names`` whose value in ``obj`` is not a real number
    (bools are not); the fields in ``optional`` may also be None. A numpy scalar among them is
    stored as the Python number of its value (`python_number`)."""
    for name in names:
        value = getattr(obj, name)
        if not (is_real(value) or (value is None and name in optional)):
            allowed = "a real number or None" if name in optional else "a real number"
            if isinstance(value, Real) and not isinstance(value, (bool, np.bool_)):
                allowed += " numpy holds (a float, or an int of at most 64 bits)"
            raise ControlError(
                f"{type(obj).__name__}.{name} must be {allowed}, got {value!r:.60} "
                f"({type(value).__name__})"
            )
        python_number(obj, name)


def python_number(obj, name: str) -> None:
    """Store the field ``name`` of ``obj`` (a settings dataclass, frozen or not), where it is a
    numpy scalar, as the Python float or int of its value: under NumPy's
    promotion rules (NEP 50) a Python float meeting an np.float32 is computed in float32, so a
    setting given as np.float32(25.0) would give other estimates and commands than 25.0 (and
    an np.int64 is no count for Python's own APIs, e.g. a deque's maxlen)."""
    value = getattr(obj, name)
    if isinstance(value, np.floating | np.integer):
        object.__setattr__(obj, name, python_value(value))


def python_value(value):
    """``value`` as the Python float or int of its value where it is a numpy float or integer
    scalar (a longdouble's ``item()`` stays a longdouble); anything else as it is."""
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def require_integers(obj, names: tuple[str, ...], optional: tuple[str, ...] = ()) -> None:
    """ControlError naming the first of ``names`` whose value in ``obj`` is not an integer
    (bools are not; 3.0 is not); the fields in ``optional`` may also be None. A numpy integer
    among them is stored as the Python int (`python_number`)."""
    for name in names:
        value = getattr(obj, name)
        if not (is_integer(value) or (value is None and name in optional)):
            allowed = "an integer or None" if name in optional else "an integer"
            raise ControlError(
                f"{type(obj).__name__}.{name} must be {allowed}, got {value!r:.60} "
                f"({type(value).__name__})"
            )
        python_number(obj, name)


def require_instance(obj, name: str, cls: type) -> None:
    """ControlError naming ``name`` when its value in ``obj`` is not a ``cls``."""
    check_instance(getattr(obj, name), f"{type(obj).__name__}.{name}", cls)


def check_instance(value, name: str, cls: type, hint: str = "") -> None:
    """ControlError naming the argument ``name`` when ``value`` is not a ``cls`` (named with
    its package: ``control.Simplex``), and ``hint`` (how to make one) where given."""
    if not isinstance(value, cls):
        package = cls.__module__.split(".")[0]
        raise ControlError(
            f"{name} must be a {package}.{cls.__name__}, got {value!r:.60} "
            f"({type(value).__name__})" + (f": {hint}" if hint else "")
        )


def check_flags(**flags) -> None:
    """ControlError naming the first of ``flags`` (name: value) that is not True or False (a
    numpy bool too)."""
    for name, flag in flags.items():
        if not isinstance(flag, bool | np.bool_):
            raise ControlError(f"{name} must be True or False, got {flag!r:.60}")


def replace_fields(settings, overrides: dict):
    """``settings`` (a settings dataclass) with ``overrides`` replacing its fields; `ControlError`
    naming the overrides that are no field of it, and for one that is a field of a nested
    settings field, how to set it (e.g. ``changepoint=ChangePointSettings(mean_segment_m=...)``)."""
    names = [f.name for f in fields(settings)]
    unknown = [key for key in overrides if key not in names]
    if unknown:
        nested = [(name, type(getattr(settings, name))) for name in names]
        hint = "".join(
            f"; {key!r} is a field of {cls.__name__}: pass {name}={cls.__name__}({key}=...)"
            for key in unknown
            for name, cls in nested
            if is_dataclass(cls) and key in {f.name for f in fields(cls)}
        )
        raise ControlError(
            f"{', '.join(map(repr, unknown))}: no {type(settings).__name__} field{hint} (its "
            f"fields: {', '.join(names)})"
        )
    if not overrides and type(settings).__dataclass_params__.frozen:
        return settings  # the same settings (made anew, they would warn again)
    return replace(settings, **overrides)
