"""The shipped emulators (paper Test Cases A and B), made by examples/train_emulator.py."""

from __future__ import annotations

from pathlib import Path

from control.errors import ControlError

EMULATOR_DIR = Path(__file__).parent / "emulators"

#: Test Case A: trained on noise-free accelerations; B: on accelerations with N(0, 1) noise.
CASES = {"A": "jackal_A.gpmsa", "B": "jackal_B.gpmsa"}


def shipped_emulator_path(case: str = "A") -> Path:
    """Path of the shipped emulator of Test Case "A" (noise-free) or "B" (noise std 1 m/s^2)."""
    if case not in CASES:
        raise ControlError(f"case must be one of {sorted(CASES)}, got {case!r}")
    path = EMULATOR_DIR / CASES[case]
    if not path.is_file():
        raise ControlError(
            f"shipped emulator {path} is missing; make it with `python examples/train_emulator.py`"
        )
    return path


def shipped_emulator(case: str = "A"):
    """The shipped Jackal emulator of Test Case "A" or "B" as a `gpmsa.Emulator`.

    Its ``metadata`` records the vehicle (``vehicle``), the noise level (``noise_std``), the window
    feature (``feature``) and the campaign's road settings (``road``); `control.run_closed_loop`
    checks them against the loop.
    """
    import gpmsa

    return gpmsa.load(shipped_emulator_path(case))
