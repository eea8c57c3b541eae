"""Computational backends for gpmsa: a registry of modules implementing ``sample``.

A backend module exposes ``sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None,
seed=None, progress=False, **options) -> gpmsa.mcmc.sampler.Chains``. Modules are imported
lazily, so importing gpmsa never imports torch. ``register`` adds a backend of one's own
(docs/internals.md, "A backend of your own"), ``unregister`` removes it.
"""

from __future__ import annotations

import importlib
import inspect
from types import ModuleType

import numpy as np

from gpmsa._fp_state import underflow_as_zero
from gpmsa._version import library_versions
from gpmsa.errors import BackendUnavailableError, GPMSAError
from gpmsa.mcmc.sampler import Chains, check_sample_args

__all__ = [
    "available",
    "check_extensions",
    "check_options",
    "check_sample_args",
    "check_tempering",
    "get",
    "names",
    "open_ended",
    "placement",
    "recorded_options",
    "register",
    "sample",
    "takes",
    "unregister",
]

_REGISTRY: dict[str, tuple[str | ModuleType, str]] = {
    # name: (module path, or a registered module, and the pip argument that installs its packages)
    "numpy": ("gpmsa.backends.numpy_backend", ""),
    "torch": ("gpmsa.backends.torch_backend", "terrain-gpmsa[torch]"),
    "pyro": ("gpmsa.backends.pyro_backend", "terrain-gpmsa[torch]"),
}
BUILTIN = ("numpy", "torch", "pyro")
"""The backends gpmsa ships; any other registered name is a plug-in (`register`)."""

INTERFACE = ("n_iter", "n_chains", "tune", "step_widths", "seed", "progress")
"""The keywords every backend's ``sample`` takes (after the problem)."""


def register(name: str, module: str | ModuleType, *, extra: str = "") -> None:
    """Register a backend of one's own as ``name`` (a plug-in; re-registering it replaces it,
    `unregister` removes it).

    ``module``: an import path (imported at first use, as the built-in backends are) or a
    module (any object) with ``sample(problem, *, n_iter, n_chains=1, tune=True,
    step_widths=None, seed=None, progress=False, ...) -> gpmsa.mcmc.sampler.Chains``; its other
    keyword options are passed through from ``fit``/``calibrate`` as given (every one where it
    takes ``**options``), ``n_jobs``/``executor`` only where its signature names them. It may
    declare ``SUPPORTS``: the ``Problem.extensions`` its ``sample`` handles; a problem using
    another is refused before sampling, as is parallel tempering (numpy and torch only).
    ``extra``: the pip argument that installs its packages, named when its import fails.
    GPMSAError for a name that is not a non-empty string or is a built-in backend's."""
    if not isinstance(name, str) or not name.strip():
        raise GPMSAError(f"register: name must be a non-empty string, got {name!r}")
    if name in BUILTIN:
        raise GPMSAError(f"register: {name!r} is a built-in backend's name; choose another")
    if not isinstance(extra, str):
        raise GPMSAError(f"register: extra must be a string (a pip argument), got {extra!r}")
    if isinstance(module, str):
        if not module.strip():
            raise GPMSAError("register: module must be an import path or a module, got ''")
    else:
        _check_module(name, module)  # refused now, not at the fit
    _REGISTRY[name] = (module, extra)


def unregister(name: str) -> None:
    """Remove the plug-in registered as ``name`` (`register`); GPMSAError for a built-in
    backend's name or a name not registered."""
    if isinstance(name, str) and name in BUILTIN:
        raise GPMSAError(f"unregister: {name!r} is a built-in backend, which cannot be removed")
    if not isinstance(name, str) or name not in _REGISTRY:
        plugins = tuple(n for n in _REGISTRY if n not in BUILTIN)
        raise GPMSAError(f"unregister: no plug-in {name!r} is registered; registered: {plugins}")
    del _REGISTRY[name]


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
    if not isinstance(path, str):
        return path
    try:
        module = importlib.import_module(path)
    except ModuleNotFoundError as exc:
        if exc.name == path:
            raise GPMSAError(f"backend {name!r} is registered but {path} does not exist") from exc
        if _own(exc):
            raise
        how = f': pip install "{extra}"' if extra else ""
        raise BackendUnavailableError(f"backend {name!r} needs {exc.name}{how}") from exc
    except (ImportError, OSError) as exc:  # installed but broken: incompatible versions, libraries
        if isinstance(exc, ImportError) and _own(exc):
            raise
        how = f': pip install --upgrade "{extra}"' if extra else ""
        raise BackendUnavailableError(
            f"backend {name!r}: its packages are installed but fail to import "
            f"({type(exc).__name__}: {exc}); install compatible versions{how}"
        ) from exc
    if name not in BUILTIN:
        _check_module(name, module)
    return module


def _check_module(name: str, module) -> None:
    """GPMSAError where plug-in ``module`` has no callable ``sample`` taking `INTERFACE`."""
    sample = getattr(module, "sample", None)
    if not callable(sample):
        raise GPMSAError(f"backend {name!r}: {module!r} has no callable sample(problem, *, ...)")
    if not _any_keyword(sample):
        params = inspect.signature(sample).parameters
        missing = [k for k in INTERFACE if k not in params]
        if missing:
            raise GPMSAError(
                f"backend {name!r}: its sample takes no {missing}; a backend's sample takes "
                f"(problem, *, {', '.join(INTERFACE)}, ...)"
            )


def takes(backend: str, key: str) -> bool:
    """Whether backend ``backend``'s ``sample`` takes keyword ``key`` (by name, or a plug-in's
    through ``**options``)."""
    sample = get(backend).sample
    return key in inspect.signature(sample).parameters or _any_keyword(sample)


def open_ended(backend: str) -> bool:
    """Whether backend ``backend``'s ``sample`` takes any keyword (``**options``: a plug-in's
    options pass through unchecked)."""
    return _any_keyword(get(backend).sample)


def _any_keyword(sample) -> bool:
    return any(p.kind is inspect.Parameter.VAR_KEYWORD
               for p in inspect.signature(sample).parameters.values())  # fmt: skip


@underflow_as_zero
def sample(backend: str, problem, *, n_iter: int, n_chains: int, **kwargs) -> Chains:
    """The chains of backend ``backend``'s ``sample(problem, n_iter=, n_chains=, **kwargs)``,
    checked: a plug-in's ``problem`` without an extension it does not declare (its
    ``SUPPORTS``), its result a `Chains` of ``n_chains`` x ``n_iter`` draws of every parameter
    of ``problem`` (GPMSAError naming what is wrong)."""
    check_extensions(backend, problem.extensions)
    chains = get(backend).sample(problem, n_iter=n_iter, n_chains=n_chains, **kwargs)
    if not isinstance(chains, Chains):
        raise GPMSAError(f"backend {backend!r}: its sample returned a {type(chains).__name__}, "
                         "not a gpmsa.mcmc.sampler.Chains")  # fmt: skip
    lead = (n_chains, n_iter)
    if chains.log_post.shape != lead:  # (Chains' own check: each draw's first axes log_post's)
        wrong = [f"log_post has shape {chains.log_post.shape}"]
    else:
        missing = [k for k in problem.names if k not in chains.draws]
        wrong = [f"no draws of {missing}"] if missing else []
        shapes = {k: (np.shape(chains.draws[k]), (*lead, *v.shape))
                  for k, v in problem.init.items() if k in chains.draws}  # fmt: skip
        wrong += [f"draws[{k!r}] has shape {got}, not {want}"
                  for k, (got, want) in shapes.items() if got != want]  # fmt: skip
    if wrong:
        raise GPMSAError(f"backend {backend!r}: its sample returned Chains of other draws than "
                         f"n_chains x n_iter = {n_chains} x {n_iter} sweeps of the problem's "
                         f"parameters: {'; '.join(wrong)}")  # fmt: skip
    return chains


def check_extensions(backend: str, extensions: tuple[str, ...]) -> None:
    """GPMSAError naming the ``extensions`` (names of ``Problem.extensions``) that plug-in
    ``backend``'s module does not declare in its ``SUPPORTS``; a built-in backend's pass (they
    check their own)."""
    if backend in BUILTIN:
        return
    declared = getattr(get(backend), "SUPPORTS", ())
    missing = [e for e in extensions if e not in declared]
    if missing:
        raise GPMSAError(
            f"backend {backend!r} does not declare support for {missing} (its module's "
            f"SUPPORTS: {tuple(declared)}); use backend='numpy', or declare them where "
            "its sample handles them"
        )


def check_tempering(backend: str, options: dict) -> None:
    """GPMSAError naming ``temperatures``/``swap_every``/``adapt_ladder`` in ``options`` for
    another backend than numpy or torch, which alone run tempered chains."""
    if backend in ("numpy", "torch"):
        return
    given = [k for k in ("temperatures", "swap_every") if options.get(k) is not None]
    if given:
        raise GPMSAError(
            f"{' and '.join(given)}: parallel tempering runs on the numpy and torch backends "
            f"only, not backend={backend!r}"
        )
    if "adapt_ladder" in options:
        raise GPMSAError(
            f"adapt_ladder: the adaptive ladder runs on the numpy and torch backends only, not "
            f"backend={backend!r}"
        )


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
    unknown = [] if open_ended(backend) else sorted(set(options) - set(accepted))
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


def recorded_versions(backend: str) -> dict[str, str]:
    """The versions of what runs on ``backend`` as ``fit``'s settings and ``calibrate``'s info
    record them (`gpmsa._version.library_versions`: a plug-in's module too)."""
    return library_versions(backend, None if backend in BUILTIN else get(backend))


def placement(backend: str, n_jobs=None, executor=None) -> dict:
    """The ``n_jobs``/``executor`` options to pass to backend ``backend``'s ``sample`` (those
    given). GPMSAError when given to a backend that runs its chains in one process (torch)."""
    sample = get(backend).sample
    out = {}
    for key, val in (("n_jobs", n_jobs), ("executor", executor)):
        if val is not None:
            if key not in inspect.signature(sample).parameters:  # named: **options is not enough
                raise GPMSAError(
                    f"backend {backend!r} runs its chains in one process: it takes no {key}="
                )
            out[key] = val
    return out
