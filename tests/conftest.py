"""Shared pytest configuration."""

from pathlib import Path

import pytest

DATA_DIR = Path(__file__).parent / "data"


@pytest.fixture
def data_dir() -> Path:
    """Folder of test data files copied into the project (never ../shared)."""
    return DATA_DIR
