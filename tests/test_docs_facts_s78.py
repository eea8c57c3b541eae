"""Facts the user documentation states about the code, checked against it: every module of
gpmsa/ is named in docs/internals.md and every module of control/ in docs/closed-loop.md's
"Pieces" (and no module that does not exist), and every resource limit or other constant the
docs give with its value (`gpmsa.limits.MAX_OBS_VALUES` (128)) has that value."""

import importlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
INTERNALS = (ROOT / "docs" / "internals.md").read_text()
CLOSED_LOOP = (ROOT / "docs" / "closed-loop.md").read_text()
PACKAGES = ("gpmsa", "control", "roadgen", "vehicle")


def _folder_rows() -> dict[str, str]:
    """internals.md's "Where things are" table: folder ("model/") -> its row's text."""
    rows = re.findall(r"^\| `(\w+/)` \|(.*)$", INTERNALS, re.M)
    return dict(rows)


def _listed_in_internals(rel: str, folders: dict[str, str]) -> bool:
    """A module (path relative to gpmsa/) is named by its path in backticks (a module row), or
    by its name in backticks in its folder's row of the "Where things are" table."""
    if f"`{rel}`" in INTERNALS:
        return True
    folder, _, name = rel.rpartition("/")
    return bool(folder) and f"`{name[:-3]}`" in folders.get(folder + "/", "")


def test_every_gpmsa_module_is_listed_in_internals():
    folders = _folder_rows()
    assert {"model/", "mcmc/", "calibration/", "studies/", "cli/", "io/"} <= set(folders)
    modules = [p.relative_to(ROOT / "gpmsa").as_posix() for p in (ROOT / "gpmsa").rglob("*.py")]
    missing = [
        rel
        for rel in sorted(modules)
        if not rel.endswith(("__init__.py", "__main__.py"))
        and not _listed_in_internals(rel, folders)
    ]
    assert not missing, f"modules not named in docs/internals.md: {missing}"


def test_internals_names_no_module_that_does_not_exist():
    named = re.findall(r"`((?:\w+/)+\w+\.py)`", INTERNALS)
    assert len(named) > 60
    gone = sorted(  # gpmsa's modules relative to gpmsa/, other files to the repository
        {rel for rel in named if not ((ROOT / "gpmsa" / rel).is_file() or (ROOT / rel).is_file())}
    )
    assert not gone, f"docs/internals.md names modules that do not exist: {gone}"


def test_every_control_module_is_a_piece_in_closed_loop():
    rows = re.findall(r"^\| `(control/[\w/]+\.py)` \|", CLOSED_LOOP, re.M)
    assert len(rows) > 10
    gone = [rel for rel in rows if not (ROOT / rel).is_file()]
    assert not gone, f"docs/closed-loop.md lists modules that do not exist: {gone}"
    missing = [
        p.relative_to(ROOT).as_posix()
        for p in sorted((ROOT / "control").glob("*.py"))
        if p.name != "__init__.py" and p.relative_to(ROOT).as_posix() not in rows
    ]
    assert not missing, f"control modules missing from docs/closed-loop.md's Pieces: {missing}"
    robot = re.search(r"^\| `control/robot/` \|(.*)$", CLOSED_LOOP, re.M).group(1)
    unnamed = [
        p.stem
        for p in sorted((ROOT / "control" / "robot").glob("*.py"))
        if p.name != "__init__.py" and f"`{p.stem}`" not in robot
    ]
    assert not unnamed, f"control/robot modules missing from the control/robot/ row: {unnamed}"


NUMBER = r"\d{1,3}(?:,\d{3})+|\d+(?:\.\d+)?(?:e[-+]?\d+)?"
UNITS = {"": 1, "%": 0.01, "KiB": 2**10, "MiB": 2**20, "GiB": 2**30}
CONSTANT = re.compile(
    rf"`(?P<name>(?:\w+\.)*[A-Z][A-Z0-9_]+)`\s*(?:\(|=\s*)(?P<value>{NUMBER})\s*"
    r"(?P<unit>%|KiB|MiB|GiB)?(?=[),;:]|\s*$)",
    re.M,
)


def _constant(name: str):
    """The value of a dotted constant (package.module.NAME), or of gpmsa.limits' NAME; None
    for a name the docs use otherwise (an experiment's setting, another library's)."""
    parts = name.split(".")
    if len(parts) == 1:
        limits = importlib.import_module("gpmsa.limits")
        return getattr(limits, name, None)
    if parts[0] not in PACKAGES:
        return None
    module = importlib.import_module(".".join(parts[:-1]))
    return getattr(module, parts[-1])


def test_every_constant_the_docs_give_with_its_value_has_it():
    checked, wrong = 0, []
    for doc in DOCS:
        text = doc.read_text()
        for m in CONSTANT.finditer(text):
            real = _constant(m["name"])
            if real is None:
                continue
            stated = float(m["value"].replace(",", "")) * UNITS[m["unit"] or ""]
            checked += 1
            if abs(stated - float(real)) > 1e-9 * max(1.0, abs(float(real))):
                line = text[: m.start()].count("\n") + 1
                wrong.append(f"{doc.name}:{line}: {m['name']} reads {m.group(0)!r}, is {real!r}")
    assert checked >= 10, checked
    assert not wrong, "\n".join(wrong)
