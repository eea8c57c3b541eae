"""The project as a user installs it (a wheel in site-packages, not this checkout): every data
file the packages hold and open ships (``package-data``), no package reads a file of the
repository beside it at run time, the dependency floors are releases that work together, and
the source distribution holds what the README's commands run."""

from __future__ import annotations

import ast
import fnmatch
import re
from pathlib import Path

import pytest

import control
from control.shipped import CASES, EMULATOR_DIR, KINDS, emulator_file_name

tomllib = pytest.importorskip("tomllib")

REPO = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())
PACKAGES = ("gpmsa", "roadgen", "vehicle", "control")
SKIP_DIRS = {"__pycache__", ".pytest_cache", ".hypothesis", ".ruff_cache"}


def _package_files(package: str):
    for path in sorted((REPO / package).rglob("*")):
        if path.is_file() and not SKIP_DIRS & set(path.parts) and path.suffix != ".pyc":
            yield path


def _shipped(package: str, relative: str) -> bool:
    """Whether the wheel holds ``relative`` (a path inside ``package``) by package-data."""
    globs = PYPROJECT["tool"]["setuptools"]["package-data"].get(package, [])
    return any(fnmatch.fnmatchcase(relative, glob) for glob in globs)


def test_the_packages_found_are_the_four_and_each_folder_of_modules_is_a_package():
    """setuptools' find ships a folder of modules only with its ``__init__.py``."""
    assert PYPROJECT["tool"]["setuptools"]["packages"]["find"]["include"] == [
        f"{p}*" for p in ("gpmsa", "vehicle", "roadgen", "control")
    ]
    for package in PACKAGES:
        for folder in {p.parent for p in _package_files(package) if p.suffix == ".py"}:
            assert (folder / "__init__.py").is_file(), folder


def test_every_data_file_in_the_packages_is_shipped():
    """A file beside the modules that is not Python (an emulator, py.typed) is one the
    library reads or a type checker needs: package-data must name it, or a wheel lacks it."""
    data = [(p, path) for p in PACKAGES for path in _package_files(p) if path.suffix != ".py"]
    assert len(data) >= 8  # four py.typed, four emulators
    for package, path in data:
        relative = path.relative_to(REPO / package).as_posix()
        assert _shipped(package, relative), f"{package}/{relative} is not in package-data"


def test_the_shipped_emulators_are_shipped_files():
    assert EMULATOR_DIR == Path(control.__file__).parent / "emulators"
    for case in CASES:
        for kind in KINDS:
            name = emulator_file_name(case, kind)
            assert (EMULATOR_DIR / name).is_file()
            assert _shipped("control", f"emulators/{name}")


def test_no_package_reads_the_repository_beside_it():
    """Every ``__file__`` in the packages' code: the shipped emulators' folder and the
    campaign cache key's own sources (both inside the installed packages); a path built from
    it up to the repository (examples/, tests/, docs/) would not exist in site-packages."""
    uses = []
    for package in PACKAGES:
        for path in _package_files(package):
            if path.suffix != ".py":
                continue
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Name) and node.id == "__file__":
                    uses.append(path.relative_to(REPO).as_posix())
    assert sorted(uses) == ["control/shipped.py", "vehicle/campaign.py"]
    shipped = (REPO / "control" / "shipped.py").read_text()
    assert 'EMULATOR_DIR = Path(__file__).parent / "emulators"' in shipped


def _floor(requirement: str) -> tuple[int, ...]:
    match = re.search(r">=\s*([\d.]+)", requirement)
    assert match, requirement
    return tuple(int(part) for part in match.group(1).split("."))


def test_dependency_floors_are_releases_that_work_with_numpy_2():
    """Floors found by installing them: exudyn 1.9-1.11 have no ``SimulationSettings.solution``
    (vehicle's models), matplotlib 3.7 and arviz 0.18 were built for numpy 1 (and arviz
    0.16-0.17 import scipy.signal.gaussian, gone in scipy 1.13), arviz < 0.23.1 does not
    require the h5py its ``to_netcdf`` needs since h5netcdf 1.8; the extras': rosbags < 0.11.6
    reads one schema per MCAP topic and no IDL schema in block form, mcap < 1.2 has no
    ``record_size_limit``, hypothesis < 6.85 no ``characters(exclude_categories=)``. pip keeps
    an older installed release that meets a floor, so a floor too low breaks in use."""
    needs = {"exudyn": (1, 13), "matplotlib": (3, 8, 4), "arviz": (0, 23, 1), "numpy": (2, 0),
             "rosbags": (0, 11, 6), "mcap": (1, 2, 1), "hypothesis": (6, 85)}  # fmt: skip
    project = PYPROJECT["project"]
    floors: dict[str, list[tuple[int, ...]]] = {}
    extras = [r for group in ("robot", "test") for r in project["optional-dependencies"][group]]
    for requirement in project["dependencies"] + extras:
        name = re.match(r"[A-Za-z0-9_.-]+", requirement).group(0).lower()
        if name in needs:
            floors.setdefault(name, []).append(_floor(requirement))
    for name, floor in needs.items():
        assert floors[name] and min(floors[name]) >= floor, (name, floors[name])


def test_the_source_distribution_holds_what_the_readme_runs():
    """The README's commands run examples/ and the tests (with tests/data, docs/ and .ci/run)
    from the repository root: an unpacked sdist is such a root (setuptools alone would add
    the top-level tests/test*.py files only)."""
    lines = (REPO / "MANIFEST.in").read_text().splitlines()
    for folder in ("docs", "examples", "benchmarks", "tests"):
        assert f"graft {folder}" in lines
    assert "include .ci/run" in lines
    assert "global-exclude *.py[cod] __pycache__ .DS_Store" in lines


def test_the_source_distribution_leaves_out_what_git_ignores(tmp_path, monkeypatch):
    """MANIFEST.in as setuptools reads it, over a checkout where the examples, benchmarks and
    tests have run from their own folders: their out/ folders (figures, campaign caches) and
    the tools' caches stay out of the sdist, as .gitignore keeps them out of the repository."""
    file_list = pytest.importorskip("setuptools.command.egg_info").FileList
    kept = ["docs/a.md", "examples/a.py", "benchmarks/b.py", "tests/data/d.csv",
            "tests/control/test_a.py", ".ci/run"]  # fmt: skip
    ignored = ["examples/out/fig.png", "benchmarks/out/bench_campaigns/run.npz",
               "tests/control/out/o.json", "tests/.hypothesis/examples/h",
               "tests/.pytest_cache/v", "tests/.ruff_cache/r", "docs/.ruff_cache/r",
               "tests/__pycache__/t.cpython-311.pyc", "benchmarks/a.campaign-cache/c.npz",
               "out/metrics.json", "build/lib/x.py"]  # fmt: skip
    for name in kept + ignored:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("x\n")
    monkeypatch.chdir(tmp_path)
    files = file_list()
    files.findall()
    for line in (REPO / "MANIFEST.in").read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            files.process_template_line(line)
    assert sorted(files.files) == sorted(kept)
