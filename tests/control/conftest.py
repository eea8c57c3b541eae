"""Fixtures of the control tests (the doubles live in control_doubles.py)."""

import pytest
from control_doubles import FakeBlockModel, FakeCalibrator

import control


@pytest.fixture
def fake_calibrator():
    return FakeCalibrator()


@pytest.fixture
def block_model():
    return FakeBlockModel()


@pytest.fixture(scope="session")
def emulator_a():
    """The shipped band emulator of case A (noise-free)."""
    return control.shipped_emulator("A")


@pytest.fixture(scope="session")
def likelihood_a(emulator_a):
    """Its block likelihood, prepared once for the session."""
    return control.ObservationModel(emulator_a)


@pytest.fixture(scope="session")
def emulator_b():
    """The shipped band emulator of case B (noise sd 1 m/s^2)."""
    return control.shipped_emulator("B")


@pytest.fixture(scope="session")
def likelihood_b(emulator_b):
    """Its block likelihood, prepared once for the session."""
    return control.ObservationModel(emulator_b)


@pytest.fixture(scope="session")
def new_bcr(likelihood_a, likelihood_b):
    """``new_bcr(case, **overrides)``: a new BCR, as ``control.BCR.from_emulator(
    control.shipped_emulator(case), **overrides)`` makes it, on case "A"'s or "B"'s block
    likelihood prepared once for the session (an ObservationModel takes ~0.2 s to prepare and
    BCRs may share one): the same estimates, bit for bit."""
    models = {"A": likelihood_a, "B": likelihood_b}

    def make(case: str, **overrides) -> control.BCR:
        model = models[case]
        return control.BCR(model, control.bcr_settings_for(model.emulator, **overrides))

    return make
