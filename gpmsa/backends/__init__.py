"""Computational backends for gpmsa: a registry of modules implementing ``sample``.

A backend module exposes ``sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None,
seed=None, progress=False, **options) -> gpmsa.mcmc.sampler.Chains``. Modules are imported
lazily, so importing gpmsa never imports torch.
"""

from __future__ import annotations

import importlib
from types import ModuleType

import numpy as np

from gpmsa.errors import BackendUnavailableError, GPMSAError

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

    Raises GPMSAError for an unknown name and BackendUnavailableError when its packages are missing.
    """
    if name not in _REGISTRY:
        raise GPMSAError(f"unknown backend {name!r}; registered: {names()}")
    path, extra = _REGISTRY[name]
    try:
        return importlib.import_module(path)
    except ModuleNotFoundError as exc:
        if exc.name == path:
            raise GPMSAError(f"backend {name!r} is registered but {path} does not exist") from exc
        raise BackendUnavailableError(
            f'backend {name!r} needs {exc.name}: pip install "terrain-gpmsa[{extra}]"'
        ) from exc


def check_sample_args(n_iter, n_chains, seed) -> None:
    """The checks every backend's ``sample`` makes on its run arguments (GPMSAError naming it)."""
    if not isinstance(n_iter, (int, np.integer)) or n_iter < 1:
        raise GPMSAError(f"n_iter must be an integer >= 1, got {n_iter!r}")
    if not isinstance(n_chains, (int, np.integer)) or n_chains < 1:
        raise GPMSAError(f"n_chains must be an integer >= 1, got {n_chains!r}")
    if seed is not None and not isinstance(seed, (int, np.integer)):
        raise GPMSAError(f"seed must be an int or None, got {seed!r}")
