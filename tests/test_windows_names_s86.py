"""The names of the files the library makes are valid on Windows and distinct on a
case-insensitive file system (macOS's and Windows' defaults), checked here on Linux by
Windows' rules: no ``<>:"/\\|?*`` or control character, no trailing dot or space, no reserved
device name (CON, NUL, COM1, ...: also with an extension) and at most 255 characters."""

import re
from pathlib import Path, PureWindowsPath

import pytest

_RESERVED = {"CON", "PRN", "AUX", "NUL", *(f"{d}{k}" for d in ("COM", "LPT") for k in range(10))}


def windows_problem(name: str) -> str | None:
    """Why ``name`` (one path component) cannot be a file name on Windows, else None."""
    if re.search(r'[<>:"/\\|?*\x00-\x1f]', name):
        return "a character Windows refuses"
    if name.endswith((".", " ")):
        return "a trailing dot or space (Windows drops it)"
    if name.split(".", 1)[0].rstrip(" ").upper() in _RESERVED:
        return "a reserved device name"
    if len(name) > 255:
        return "longer than 255 characters"
    if PureWindowsPath(name).name != name:
        return "not one component"
    return None


def test_the_check_sees_each_problem():
    bad = ["run-2026-12-07T03:50:41.csv", "a?.png", "notes.", "out ", "CON", "nul.txt",
           "com1.gpmsa", "x" * 256, "a\tb"]  # fmt: skip
    assert [name for name in bad if windows_problem(name) is None] == []
    assert windows_problem("jackal_A.gpmsa") is None


def test_terrain_replay_outputs():
    from control.robot import cli

    assert [n for n in cli.OUTPUTS if windows_problem(n)] == []
    assert len({n.lower() for n in cli.OUTPUTS}) == len(cli.OUTPUTS)


def test_shipped_emulator_names_are_distinct_in_any_case():
    from control.shipped import CASES, KINDS, emulator_file_name

    names = [emulator_file_name(c, k) for c in CASES for k in KINDS]
    assert [n for n in names if windows_problem(n)] == []
    assert len({n.lower() for n in names}) == len(names)


@pytest.mark.parametrize(
    "name",
    ["jackal_A.gpmsa", "Łódź run.gpmsa", "x" * 250 + ".gpmsa"],
    ids=["plain", "unicode", "long"],
)
def test_a_save_s_temporary_file_name(name):
    from gpmsa.io.atomic import _temporary_name

    tmp = _temporary_name(Path(name))
    assert windows_problem(tmp) is None, tmp


def test_a_campaign_cache_file_name():
    import vehicle
    from vehicle.campaign import RunSpec

    spec = RunSpec(vehicle.Jackal(), v=1.0, gd=450.0, seed=0, road_length_m=21.0, dx_m=0.006,
                   lead_in_m=1.0, band=None, rate_hz=120.0, noise_std=1.0, window=1000,
                   substeps=4)  # fmt: skip
    name = f"run-{spec.key()}.npz"  # as `run_campaign` names it in cache_dir
    assert windows_problem(name) is None and name == name.lower(), name
