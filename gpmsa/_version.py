"""The library version (a leaf, so that the file container can stamp it), and the versions of
what computed a result (recorded with a fitted emulator, shown by ``gpmsa info``)."""

from __future__ import annotations

__version__ = "0.1.0"

_BACKEND_PACKAGES = {"torch": ("torch", "gpytorch"), "pyro": ("torch", "pyro-ppl")}


def library_versions(backend: str | None = None) -> dict[str, str]:
    """Versions of Python, gpmsa, numpy, scipy and the BLAS in use (name, version, CPU kernel,
    threads), plus the backend's packages: the numbers that can change a seeded result between
    machines (docs/vehicle-models.md, "Reproducibility")."""
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
    return out
