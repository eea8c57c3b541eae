"""Computational backends for gpmsa: a registry of modules implementing ``sample``.

A backend module exposes ``sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None,
seed=None, progress=False, **options) -> gpmsa.mcmc.sampler.Chains``. Modules are imported
lazily, so importing gpmsa never imports torch.
"""

from __future__ import annotations

import importlib
import inspect
from types import ModuleType

import numpy as np

from gpmsa.errors import BackendUnavailableError, GPMSAError
from gpmsa.mcmc.sampler import check_sample_args

__all__ = [
    "available",
    "check_options",
    "check_sample_args",
    "get",
    "names",
    "placement",
    "recorded_options",
]

_REGISTRY: dict[str, tuple[str, str]] = {
    # name: (module path, pip extra that provides its packages)
    "numpy": ("gpmsa.backends.numpy_backend", ""),
    "torch": ("gpmsa.backends.torch_backend", "torch"),
    "pyro": ("gpmsa.backends.pyro_backend", "torch"),
}


def names() -> tuple[str, ...]:
    """Every registered backend name (installed or not)."""
    return tuple(_REGISTRY)


def available() -> tuple[str, ...]:
    """Registered backends whose module imports (its packages are installed)."""
    out = []
    for name in _REGISTRY:
        try:
            get(name)
        except (BackendUnavailableError, GPMSAError):
            continue
        out.append(name)
    return tuple(out)


def get(name: str) -> ModuleType:
    """The backend module called ``name``.

    Raises GPMSAError for an unknown name and BackendUnavailableError when its packages are missing
    or fail to import (e.g. a pyro-ppl release that does not work with the installed torch).
    """
    if not isinstance(name, str) or name not in _REGISTRY:
        raise GPMSAError(f"unknown backend {name!r}; registered: {names()}")
    path, extra = _REGISTRY[name]
    try:
        return importlib.import_module(path)
    except ModuleNotFoundError as exc:
        if exc.name == path:
            raise GPMSAError(f"backend {name!r} is registered but {path} does not exist") from exc
        if _own(exc):
            raise
        raise BackendUnavailableError(
            f'backend {name!r} needs {exc.name}: pip install "terrain-gpmsa[{extra}]"'
        ) from exc
    except (ImportError, OSError) as exc:  # installed but broken: incompatible versions, libraries
        if isinstance(exc, ImportError) and _own(exc):
            raise
        raise BackendUnavailableError(
            f"backend {name!r}: its packages are installed but fail to import "
            f"({type(exc).__name__}: {exc}); install compatible versions: "
            f'pip install --upgrade "terrain-gpmsa[{extra}]"'
        ) from exc


def _own(exc: ImportError) -> bool:
    """Whether an import error is gpmsa's own (a bug to show as it is, not a missing package)."""
    return (exc.name or "").split(".")[0] == "gpmsa"


def check_options(
    backend: str, options: dict, reserved: tuple[str, ...], caller: str, renamed=None
) -> None:
    """GPMSAError naming every key of ``options`` that backend ``backend``'s ``sample`` does not
    take, or that ``caller`` sets itself (``reserved``: its own arguments; ``renamed``: a
    reserved name -> the caller's argument that sets it, where their names differ)."""
    accepted = inspect.signature(get(backend).sample).parameters
    open_ended = any(a.kind is inspect.Parameter.VAR_KEYWORD for a in accepted.values())
    taken = sorted(set(options) & set(reserved))
    if taken:
        hints = "".join(
            f"; {caller} sets {k} from its argument {renamed[k]}"
            for k in taken
            if renamed and k in renamed
        )
        raise GPMSAError(
            f"{caller}: {taken} are {caller}'s own arguments, not backend options{hints}"
        )
    unknown = [] if open_ended else sorted(set(options) - set(accepted))
    if unknown:
        offered = sorted(set(accepted) - set(reserved) - {"problem"})
        hint = ("; x_obs outside the design: a joint fit warns within 10% of a column's width "
                "and refuses beyond, gpmsa.calibrate of the fitted emulator takes extrapolate=True"
                if "extrapolate" in unknown else "")  # fmt: skip
        raise GPMSAError(
            f"{caller}: unknown option(s) {unknown} for the {backend!r} backend; it takes "
            f"{offered}{hint}"
        )


_UNRECORDED = object()


def _recorded_option(value):
    """A backend option as a record holds it: plain values as they are (a numpy scalar as its
    Python value), a torch dtype or device by its name ("float32", "cuda"); anything else is
    not recorded (_UNRECORDED)."""
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if type(value).__module__.split(".")[0] == "torch":
        return str(value).removeprefix("torch.")
    return _UNRECORDED


def recorded_options(options: dict) -> dict:
    """``options`` as ``fit``'s settings and ``calibrate``'s info record them, sorted by name:
    plain values as they are (numpy scalars as Python ones), a torch dtype or device by its
    name; other values left out."""
    recorded = {k: _recorded_option(v) for k, v in sorted(options.items())}
    return {k: v for k, v in recorded.items() if v is not _UNRECORDED}


def placement(backend: str, n_jobs=None, executor=None) -> dict:
    """The ``n_jobs``/``executor`` options to pass to backend ``backend``'s ``sample`` (those
    given). GPMSAError when given to a backend that runs its chains in one process (torch)."""
    sample = get(backend).sample
    out = {}
    for key, val in (("n_jobs", n_jobs), ("executor", executor)):
        if val is not None:
            if key not in inspect.signature(sample).parameters:
                raise GPMSAError(
                    f"backend {backend!r} runs its chains in one process: it takes no {key}="
                )
            out[key] = val
    return out
