"""The tests run without the optional extras (torch, dask, robot): a test file imports an
extra's package (or gpmsa's backend modules that need torch and pyro) inside a test or with
``pytest.importorskip``, never by a plain import at module level, which stops the collection of
every test ("ModuleNotFoundError: No module named 'torch'", an error, not a skip).

Before (session 82, Python 3.13 where torch has no wheel here): test_ridge.py,
test_theta_priors_s75.py and test_torch_chains.py imported torch at module level, and
``pytest tests/gpmsa`` stopped with 3 collection errors, running none of its tests."""

import ast
import re
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
OPTIONAL = {"torch", "gpytorch", "pyro", "dask", "distributed", "rosbags", "mcap"}
"""The packages of pyproject's optional extras (torch, dask, robot) a test may use."""
NEEDS_TORCH = {"gpmsa.backends.torch_backend", "gpmsa.backends.pyro_backend"}


def _skip_target(node: ast.stmt) -> str | None:
    """The module of a module-level ``pytest.importorskip("m")`` (bare or assigned), else None."""
    value = node.value if isinstance(node, ast.Expr | ast.Assign) else None
    if (
        isinstance(value, ast.Call)
        and isinstance(value.func, ast.Attribute)
        and value.func.attr == "importorskip"
        and value.args
        and isinstance(value.args[0], ast.Constant)
    ):
        return str(value.args[0].value)
    return None


def _module_level_imports(body: list[ast.stmt]):
    """(line, modules, skipped) of each import statement run when the module is imported, in
    order: its body's, and those in a module-level ``if``, ``with`` or ``try`` body (not an
    ``except ImportError`` handler's); ``from a import b`` names both a and a.b (b may be a
    module); ``skipped``: the modules that a ``pytest.importorskip`` before it has checked."""
    skipped: set[str] = set()
    for node in body:
        target = _skip_target(node)
        if target is not None:
            skipped.add(target)
        elif isinstance(node, ast.Import):
            yield node.lineno, [alias.name for alias in node.names], set(skipped)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            yield node.lineno, names, set(skipped)
        elif isinstance(node, ast.If | ast.With):
            yield from _module_level_imports(node.body + getattr(node, "orelse", []))
        elif isinstance(node, ast.Try):
            yield from _module_level_imports(node.body + node.orelse + node.finalbody)


def _unguarded(module: str, skipped: set[str]) -> bool:
    """Whether importing ``module`` needs an optional extra that no importorskip checked."""
    root = module.split(".")[0]
    if root in OPTIONAL:
        return root not in skipped and module not in skipped
    if module in NEEDS_TORCH:
        return not ({"torch", module} & skipped)
    return False


def _plain_optional_imports(path: Path, root: Path = TESTS) -> list[str]:
    found = []
    tree = ast.parse(path.read_text(), str(path))
    for line, modules, skipped in _module_level_imports(tree.body):
        if any(_unguarded(m, skipped) for m in modules):
            found.append(f"{path.relative_to(root)}:{line} imports {modules[0]}")
    return sorted(found)


def test_no_test_module_imports_an_optional_extra_at_module_level():
    files = sorted(TESTS.rglob("*.py"))
    assert len(files) > 300
    found = [hit for path in files for hit in _plain_optional_imports(path)]
    assert not found, "use pytest.importorskip or import inside the test:\n" + "\n".join(found)


def test_the_check_finds_a_plain_import_and_passes_importorskip(tmp_path):
    bad = tmp_path / "test_bad.py"
    bad.write_text("import numpy\nimport torch\nfrom gpmsa.backends import pyro_backend as pb\n"
                   "if True:\n    from rosbags.typesys import Stores\n")  # fmt: skip
    assert len(_plain_optional_imports(bad, tmp_path)) == 3
    good = tmp_path / "test_good.py"
    good.write_text("import pytest\ntorch = pytest.importorskip('torch')\n"
                    "from gpmsa.backends import torch_backend\npytest.importorskip('mcap')\n"
                    "from mcap.reader import make_reader\n\n"
                    "def test_a():\n    import rosbags\n")  # fmt: skip
    assert _plain_optional_imports(good, tmp_path) == []


def test_the_skip_marks_name_the_extra_that_installs_the_package(monkeypatch):
    """tests/_extras.py's marks (``@TORCH``, ``backend_param("torch")``, ``needs(...)``) skip
    with a reason that names the missing package and the extra of pyproject.toml that installs
    it, and only where it is missing."""
    tomllib = pytest.importorskip("tomllib")
    from tests import _extras

    extras = tomllib.loads((TESTS.parent / "pyproject.toml").read_text())["project"]
    imports = {"pyro-ppl": ["pyro"], "dask[distributed]": ["dask", "distributed"]}
    declared = {
        module: extra
        for extra, requirements in extras["optional-dependencies"].items()
        if extra != "test"
        for req in requirements
        for module in imports.get(re.split(r"[<>=!~; ]", req)[0], [re.split(r"[<>=!~; ]", req)[0]])
    }
    assert declared == _extras.EXTRA and set(declared) == OPTIONAL
    monkeypatch.setattr(_extras, "installed", lambda module: module != "pyro")
    assert _extras.needs("torch", "mcap").args == (False,)
    mark = _extras.backend_param("pyro").marks[0]
    assert mark.args == (True,)
    assert (
        mark.kwargs["reason"] == 'needs pyro: pip install "terrain-gpmsa[torch]" (the torch extra)'
    )
    assert _extras.backend_param("numpy", 1).marks[0].args == (False,)
    monkeypatch.setattr(_extras, "installed", lambda module: False)
    for module, extra in declared.items():
        reason = _extras.needs(module).kwargs["reason"]
        assert reason == f'needs {module}: pip install "terrain-gpmsa[{extra}]" (the {extra} extra)'
