"""Skips for the tests that need an optional extra (pyproject's ``torch``, ``dask``, ``robot``):
``pip install ".[test]"`` alone runs every other test, and skips these with a reason that names
the extra to install.

    from tests._extras import PYRO, TORCH, backend_param

    @TORCH                                   # a test of the torch backend
    def test_torch_...(): ...

    @pytest.mark.parametrize("backend", [backend_param("numpy"), backend_param("torch")])
    def test_...(backend): ...               # only the torch case skips without torch

A test that imports an extra's module itself may use ``pytest.importorskip`` instead
(test_optional_imports_s82.py checks that no test module imports one at module level)."""

from __future__ import annotations

import importlib.util

import pytest

EXTRA = {"torch": "torch", "gpytorch": "torch", "pyro": "torch", "dask": "dask",
         "distributed": "dask", "rosbags": "robot", "mcap": "robot"}  # fmt: skip
"""Each optional package (its import name) -> the extra of pyproject.toml that installs it."""

BACKEND_PACKAGES = {"numpy": (), "torch": ("torch",), "pyro": ("torch", "pyro")}
"""Each gpmsa backend -> the optional packages it imports."""


def installed(module: str) -> bool:
    """Whether ``module`` is found (not imported: importing torch takes seconds)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):  # a parent package missing, or a broken one
        return False


def needs(*modules: str) -> pytest.MarkDecorator:
    """A mark that skips the test where one of ``modules`` (optional packages) is missing, the
    reason naming it and its extra."""
    missing = [m for m in modules if not installed(m)]
    if not missing:
        return pytest.mark.skipif(False, reason="")
    extra = EXTRA[missing[0].split(".")[0]]
    return pytest.mark.skipif(
        True, reason=f'needs {missing[0]}: pip install "terrain-gpmsa[{extra}]" (the {extra} extra)'
    )


TORCH = needs("torch")
"""Skips a test of the torch backend (or of torch itself) without torch."""
PYRO = needs(*BACKEND_PACKAGES["pyro"])
"""Skips a test of the pyro backend without torch or pyro-ppl."""
DISTRIBUTED = needs("distributed")
"""Skips a test of dask.distributed (a Client) without it."""


def backend_needs(name: str | None) -> pytest.MarkDecorator:
    """`needs` of gpmsa backend ``name``'s packages (None, numpy or an unknown name: none)."""
    return needs(*BACKEND_PACKAGES.get(name or "numpy", ()))


def backend_param(*values, backend: str | None = None, id: str | None = None):
    """``pytest.param(*values)`` that skips where backend ``backend``'s packages are missing
    (``backend`` defaults to ``values[0]``, a backend's name)."""
    name = values[0] if backend is None else backend
    return pytest.param(*values, marks=backend_needs(name), id=id)
