"""Roads for the vehicle tests (made with roadgen, short)."""

import pytest

import roadgen


@pytest.fixture(scope="session")
def rough_road() -> roadgen.Profile:
    """A 12 m GD-400 road with a 1 m lead-in."""
    return roadgen.iso8608_profile(12.0, gd=400, seed=3, lead_in_m=1.0)


@pytest.fixture(scope="session")
def flat_road() -> roadgen.Profile:
    """A 5 m road with GD so small that it is flat to ~1e-9 m."""
    return roadgen.iso8608_profile(5.0, gd=1e-12, seed=0)
