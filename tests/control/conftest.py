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
