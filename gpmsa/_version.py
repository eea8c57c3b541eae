"""The library version (a leaf, so that the file container can stamp it), and the versions of
what computed a result (recorded with a fitted emulator, shown by ``gpmsa info``)."""

from __future__ import annotations

import functools

__version__ = "0.1.0"

_BACKEND_PACKAGES = {"torch": ("torch", "gpytorch"), "pyro": ("torch", "pyro-ppl")}

MAX_VERSION_CHARS = 200
"""A plug-in's record is cut to this many characters (its ``__version__`` is anything it says)."""


def library_versions(backend: str | None = None, plugin: object = None) -> dict[str, str]:
    """Versions of Python, gpmsa, numpy, scipy and the BLAS in use (name, version, CPU kernel,
    threads), plus the backend's packages, or for a plug-in backend (``plugin``: its module,
    ``gpmsa.backends.get(backend)``) its module's name and version (`plugin_version`): the
    numbers that can change a seeded result between machines (docs/vehicle-models.md,
    "Reproducibility")."""
    import platform
    from importlib import metadata

    import numpy
    import scipy

    out = {
        "python": platform.python_version(),
        "gpmsa": __version__,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "machine": f"{platform.system()} {platform.machine()}",
    }
    try:
        from threadpoolctl import threadpool_info

        blas = [i for i in threadpool_info() if i.get("user_api") == "blas"]
        out["blas"] = "; ".join(  # sorted: the order threadpoolctl finds them varies by run
            sorted(
                f"{i.get('internal_api')} {i.get('version')} ({i.get('architecture')}, "
                f"{i.get('num_threads')} threads)"
                for i in blas
            )
        )
    except Exception:  # threadpoolctl is optional here; versions are informative only
        out["blas"] = "unknown"
    for pkg in _BACKEND_PACKAGES.get(backend or "", ()):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out if plugin is None else out | plugin_version(str(backend), plugin)


def plugin_version(backend: str, module) -> dict[str, str]:
    """The record of plug-in backend ``backend`` (``gpmsa.backends.register``) whose module is
    ``module``: ``{"backend <backend>": "<its module's name> <version>"}``, the version its
    ``__version__``, else that of the distribution providing its top-level package, else
    "unknown". Never raises ({} at worst): versions are informative, a broken plug-in's
    metadata must not fail a fit."""
    try:
        name = getattr(module, "__name__", None)
        name = name if isinstance(name, str) and name else None
        version = _module_version(module, name)
        record = version if name is None else f"{name} {version}"
        return {f"backend {backend}": record[:MAX_VERSION_CHARS]}
    except Exception:  # anything a broken plug-in raises
        return {}


def _module_version(module, name: str | None) -> str:
    """``module.__version__`` as a string, else `_distribution_version`; "unknown" where
    either raises."""
    try:
        version = getattr(module, "__version__", None)
        return _distribution_version(name) if version is None else str(version)
    except Exception:  # a broken plug-in's metadata
        return "unknown"


def _distribution_version(module_name: str | None) -> str:
    """The version of the installed distribution providing ``module_name``'s top-level
    package ("<version> (<distribution>)" where their names differ), else "unknown"."""
    from importlib import metadata

    top = (module_name or "").split(".")[0]
    if not top:
        return "unknown"
    dists = _distributions().get(top)
    if not dists and top not in _NO_DISTRIBUTION:  # installed since the map was built?
        _distributions.cache_clear()
        dists = _distributions().get(top)
    if not dists:  # a module of no installed package (a local file): looked up once
        _NO_DISTRIBUTION.add(top)
        return "unknown"
    version = metadata.version(dists[0])
    return version if dists[0] == top else f"{version} ({dists[0]})"


_NO_DISTRIBUTION: set[str] = set()
"""Top-level module names no installed distribution provided when the map was last built."""


@functools.cache
def _distributions() -> dict:
    """importlib.metadata's top-level package -> distributions map (~0.1-0.3 s to build: kept;
    `_distribution_version` builds it again once for a package it does not hold)."""
    from importlib import metadata

    return metadata.packages_distributions()
