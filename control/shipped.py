"""The shipped emulators (paper Test Cases A and B), made by examples/train_emulator.py."""

from __future__ import annotations

import os
from pathlib import Path

from control.errors import ControlError, EmulatorMismatchError
from control.validation import is_choice
from gpmsa import Emulator
from roadgen.checks import home_path

EMULATOR_DIR = Path(__file__).parent / "emulators"

#: Test Case A: trained on noise-free accelerations; B: on accelerations with N(0, 1) noise.
CASES = ("A", "B")
#: "band": the block feature of the change-point BCR; "window": the paper's log f of a window.
KINDS = ("band", "window")


def emulator_file_name(case: str, kind: str = "band") -> str:
    """File name of the emulator of a case and feature kind."""
    if not is_choice(case, CASES):
        raise ControlError(f"case must be one of {CASES}, got {case!r}")
    if not is_choice(kind, KINDS):
        raise ControlError(f"kind must be one of {KINDS}, got {kind!r}")
    return f"jackal_{case}.gpmsa" if kind == "band" else f"jackal_{case}_window.gpmsa"


def shipped_emulator_path(case: str = "A", kind: str = "band", folder=None) -> Path:
    """Path of the shipped emulator of Test Case "A" (noise-free) or "B" (noise std 1 m/s^2),
    for the block feature ("band", the default BCR) or the paper's window feature ("window");
    with ``folder``, the file of that name there (`examples/train_emulator.py --emulator-dir`).
    ControlError naming a missing file and the command that makes it, an empty ``folder`` or
    one that is a file."""
    name = emulator_file_name(case, kind)
    if folder is not None and not isinstance(folder, str | os.PathLike):
        raise ControlError(
            f"folder must be None or a path, got {folder!r} ({type(folder).__name__})"
        )
    if folder is None:
        path, make = EMULATOR_DIR / name, "`python examples/train_emulator.py --ship`"
    else:
        if not str(folder).strip():
            raise ControlError("folder is an empty path: give the folder of the emulators")
        given = home_path(folder)  # ~: the home folder
        if given.exists() and not given.is_dir():
            raise ControlError(f"folder {str(folder)!r} is not a folder")
        path = given / name
        make = (
            f"`python examples/train_emulator.py --emulator-dir {folder} --cases {case} "
            f"--features {kind}`"
        )
    if not path.is_file():
        raise ControlError(f"emulator {path} is missing; make it with {make}")
    return path


def shipped_emulator(case: str = "A", kind: str = "band", folder=None) -> Emulator:
    """The shipped Jackal emulator of Test Case "A" or "B" as a `gpmsa.Emulator` (with
    ``folder``: the one of that name there, e.g. trained for your robot).

    ``kind="band"``: the block-feature emulator of the change-point BCR (metadata:
    ``block_scatter``); ``kind="window"``: the paper's feature (log f of a 1,000-sample
    window). Its ``metadata`` records the vehicle (``vehicle``), the noise level
    (``noise_std``), the feature (``feature``), the road settings (``road``) and the versions
    that made it; `control.run_closed_loop` checks them against the loop.

    Raises ControlError for a missing file, `gpmsa.EmulatorFileError` for a damaged one and
    `EmulatorMismatchError` for a file whose recorded feature is not of ``kind``.
    """
    import gpmsa
    from control.compat import emulator_feature

    path = shipped_emulator_path(case, kind, folder)
    emulator = gpmsa.load(path)
    feature = emulator_feature(emulator).name
    if (feature == "log_band_power") != (kind == "band"):
        raise EmulatorMismatchError(
            f"{path} holds an emulator of the feature {feature!r}, not of kind {kind!r}"
        )
    return emulator
