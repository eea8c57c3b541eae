"""The layout of gpmsa/: sub-packages by job, imports one way, no import cycle, public names kept.

Every module under gpmsa/ is parsed with ``ast``; every import of gpmsa it makes counts, also one
inside a function (a lazy import is still a dependency). A "part" is a sub-package (``model``,
``mcmc``, ...) or a top-level module (``errors``, ``_version``); ``gpmsa/__init__.py`` is the
package's face, which imports every part and which no module may import.
"""

import ast
import functools
import importlib
import inspect
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import gpmsa

REPO = Path(__file__).resolve().parents[2]
PACKAGE = REPO / "gpmsa"

LAYERS = (
    ("errors", "_version", "_threads", "_progress", "_fp_state"),
    ("limits",),
    ("model", "io"),
    ("mcmc",),
    ("backends",),
    ("fitting", "calibration"),
    ("predictive", "studies"),
    ("cli", "plots"),
    ("__main__",),
)
"""The parts of gpmsa from the bottom up. A part may import itself and the parts of LOWER layers
only (never a part of its own layer, never one above): errors, _version, _threads, _progress,
_fp_state <-
model, io <-
mcmc <- backends <- fitting, calibration <- predictive, studies <- cli, plots <- __main__
(``python -m gpmsa``, the cli's command) (studies: several models
at once, built on fitting's Emulator and calibration's problem; cli describes study files); the
file container (io) knows
nothing of the Emulator, whose record lives in fitting and imports io. ``limits`` (resource
limits, read at call time) sits just above the leaves."""
LAYER = {part: i for i, parts in enumerate(LAYERS) for part in parts}

PUBLIC = [
    "BackendUnavailableError", "BasisWarning", "Calibrator", "ChainError", "Chains",
    "ConvergenceWarning", "Emulator", "EmulatorFileError", "GPMSAError", "GammaPrior",
    "LooResult", "ObsData", "ExtrapolationWarning", "DomainWarning",
    "ObsProblem", "OutlierRunWarning", "OutsideEmulatorWarning", "ReductionWarning",
    "Posterior", "Priors", "Problem", "ResourceLimitError", "SimData", "backends", "calibrate",
    "calibration_posterior", "cross_validate", "emulator_prediction", "fit", "full_prediction",
    "limits", "load", "plots", "predictive", "prepare", "sensitivity",
    "HyperPriors", "Study", "calibrate_study", "fit_study", "load_study", "StartRejectedError",
    "calibrated_predict", "AtBoundWarning", "GridResolutionWarning", "FewDrawsWarning",
    "NuggetWarning", "UnusedSettingWarning", "ChainRetryWarning", "GPMSAWarning",
]  # fmt: skip


def module_files(root: Path = PACKAGE) -> dict[str, Path]:
    """Dotted module name -> file for each .py under ``root`` (a package named by its folder)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def gpmsa_imports(source: str, name: str, is_package: bool, known) -> list[tuple[str, int]]:
    """(imported gpmsa module, line) for every import in ``source``, at any depth of the tree.

    ``from A import b`` counts as an import of A.b where that is a module, else of A; a name that
    is no known module is cut back to its longest known prefix.
    """
    package = name if is_package else name.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base
                       for a in node.names]  # fmt: skip
        else:
            continue
        for target in targets:
            if target != "gpmsa" and not target.startswith("gpmsa."):
                continue
            while target not in known and "." in target:
                target = target.rpartition(".")[0]
            found.append((target, node.lineno))
    return found


@functools.cache
def import_graph(root: Path = PACKAGE) -> dict[str, list[tuple[str, int]]]:
    """Each module under ``root`` -> its `gpmsa_imports`; parsed once a session per root (the
    checks only read it)."""
    files = module_files(root)
    return {
        name: gpmsa_imports(path.read_text(), name, path.name == "__init__.py", files)
        for name, path in files.items()
    }


def part_of(module: str) -> str | None:
    """The part a module belongs to; None for the package's face ``gpmsa``."""
    return module.split(".")[1] if "." in module else None


def layer_violations(graph) -> list[str]:
    bad = []
    for src, targets in graph.items():
        if src == "gpmsa":
            continue
        for tgt, line in targets:
            ps, pt = part_of(src), part_of(tgt)
            if pt is None:
                bad.append(f"{src}:{line} imports the package face gpmsa/__init__.py")
            elif ps != pt and not LAYER[ps] > LAYER[pt]:
                bad.append(f"{src}:{line} ({ps}, layer {LAYER[ps]}) imports {tgt} "
                           f"({pt}, layer {LAYER[pt]})")  # fmt: skip
    return bad


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node, or a node importing itself."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in edges.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def module_edges(graph) -> dict[str, set[str]]:
    return {src: {t for t, _ in targets} for src, targets in graph.items()}


def part_edges(graph) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for src, targets in graph.items():
        if part_of(src) is None:
            continue
        out.setdefault(part_of(src), set()).update(
            part_of(t) for t, _ in targets if part_of(t) not in (None, part_of(src))
        )
    return out


# --- the checks -------------------------------------------------------------------------------
def test_every_part_has_a_layer():
    parts = {part_of(m) for m in module_files()} - {None}
    assert parts == set(LAYER), f"place new parts in LAYERS: {sorted(parts - set(LAYER))}"


def test_parts_import_only_lower_layers():
    assert layer_violations(import_graph()) == []


def test_part_graph_is_acyclic():
    assert cycles(part_edges(import_graph())) == []


def test_no_module_import_cycle():
    assert cycles(module_edges(import_graph())) == []


def test_the_file_container_imports_only_the_leaves():
    graph = import_graph()
    leaves = {"gpmsa.errors", "gpmsa._version", "gpmsa.limits"}
    assert {t for t, _ in graph["gpmsa.io.atomic"]} <= leaves
    assert {t for t, _ in graph["gpmsa.io.container"]} <= leaves | {"gpmsa.io.atomic"}
    assert "gpmsa.io.container" in {t for t, _ in graph["gpmsa.fitting.emulator"]}


def test_a_reintroduced_emulator_file_cycle_is_caught(tmp_path):
    """The checker itself: a lazy import from the container back to the Emulator is found."""
    fake = tmp_path / "gpmsa"
    for rel, text in {
        "__init__.py": "",
        "errors.py": "",
        "io/__init__.py": "",
        "io/container.py": "def read(path):\n    from gpmsa.fitting.emulator import Emulator\n",
        "fitting/__init__.py": "",
        "fitting/emulator.py": "from gpmsa.io.container import read\n",
    }.items():
        (fake / rel).parent.mkdir(parents=True, exist_ok=True)
        (fake / rel).write_text(text)
    graph = import_graph(fake)
    assert graph["gpmsa.io.container"] == [("gpmsa.fitting.emulator", 2)]
    assert cycles(module_edges(graph)) == [["gpmsa.fitting.emulator", "gpmsa.io.container"]]
    assert cycles(part_edges(graph)) == [["fitting", "io"]]
    assert layer_violations(graph) == [
        "gpmsa.io.container:2 (io, layer 2) imports gpmsa.fitting.emulator (fitting, layer 5)"
    ]


def test_relative_and_from_imports_resolve():
    known = {"gpmsa", "gpmsa.model", "gpmsa.model.data", "gpmsa.mcmc", "gpmsa.mcmc.tuning"}
    source = "from . import data\nfrom ..mcmc import tuning\nimport gpmsa.model.data.x\nimport os\n"
    got = gpmsa_imports(source, "gpmsa.model.problem", False, known)
    assert got == [("gpmsa.model.data", 1), ("gpmsa.mcmc.tuning", 2), ("gpmsa.model.data", 3)]


def test_public_names_are_the_functions_after_every_module_is_imported():
    """No sub-package shadows a public function: gpmsa.fit is fit, gpmsa.calibrate is calibrate."""
    for info in pkgutil.walk_packages(gpmsa.__path__, "gpmsa."):
        if info.name in ("gpmsa.backends.torch_backend", "gpmsa.backends.pyro_backend"):
            continue  # they need torch; the registry imports them on demand
        if info.name not in ("gpmsa.cli.__main__", "gpmsa.__main__"):  # they run the command
            importlib.import_module(info.name)
    assert sorted(gpmsa.__all__) == sorted(PUBLIC)
    for name in PUBLIC:
        assert getattr(gpmsa, name) is not None
    assert gpmsa.fit is sys.modules["gpmsa.fitting.fit"].fit and inspect.isfunction(gpmsa.fit)
    calibrate = sys.modules["gpmsa.calibration.calibrate"].calibrate
    assert gpmsa.calibrate is calibrate and inspect.isfunction(gpmsa.calibrate)
    assert gpmsa.load is sys.modules["gpmsa.fitting.emulator"].load
    assert gpmsa.Calibrator is sys.modules["gpmsa.calibration.calibrator"].Calibrator
    assert gpmsa.Posterior is sys.modules["gpmsa.calibration.posterior"].Posterior
    predict = sys.modules["gpmsa.predictive.calibrated"].calibrated_predict
    assert gpmsa.predictive.calibrated_predict is predict
    assert inspect.ismodule(gpmsa.backends) and callable(gpmsa.backends.get)


def test_version_matches_the_project():
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert gpmsa.__version__ == project["version"]


def test_console_script_and_python_m_run_the_command():
    tomllib = pytest.importorskip("tomllib")
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    module, _, attr = scripts["gpmsa"].partition(":")
    assert callable(getattr(importlib.import_module(module), attr))
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-m", "gpmsa.cli", "--help"], env=env,
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "info" in done.stdout and "calibrate" in done.stdout
