"""Fixtures of the control tests (the doubles live in control_doubles.py)."""

import pytest
from control_doubles import FakeBlockModel, FakeCalibrator


@pytest.fixture
def fake_calibrator():
    return FakeCalibrator()


@pytest.fixture
def block_model():
    return FakeBlockModel()
