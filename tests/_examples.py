"""Load a script of examples/ or benchmarks/ as a module (its functions tested without running
main)."""

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
BENCHMARKS = EXAMPLES.parent / "benchmarks"


def load_example(name: str) -> ModuleType:
    """examples/<name>.py imported as module ``name``, with examples/ on sys.path as when the
    script runs (its helpers: ``from _cli import ...``)."""
    if str(EXAMPLES) not in sys.path:
        sys.path.append(str(EXAMPLES))
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def load_benchmark(name: str) -> ModuleType:
    """benchmarks/<name>.py imported as module ``name``, registered in sys.modules (a dataclass
    of the script looks its module up there), with benchmarks/ on sys.path while it is
    imported, as when the script runs (its helpers: ``from _host import ...``); not after, where
    a bare ``import backends`` would find a benchmark."""
    added = str(BENCHMARKS) not in sys.path
    if added:
        sys.path.append(str(BENCHMARKS))
    try:
        spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    finally:
        if added:
            sys.path.remove(str(BENCHMARKS))
    return module
