"""Inputs that would exhaust the machine, and invalid seeds (issue 15, section 4)."""

import tracemalloc

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import roadgen
from roadgen import checks


@pytest.mark.parametrize(
    "make",
    [
        lambda: roadgen.track([(1e7, 300)]),
        lambda: roadgen.iso8608_profile(21.0, 300.0, dx_m=1e-7),
        lambda: roadgen.track([(50, 300), (50, 500)], dx_m=1e-7),
        lambda: roadgen.iso8608_profile(21.0, 300.0, dx_m=1e-9),  # the finest grid allowed
    ],
)
def test_oversized_roads_are_refused_before_allocating(make):
    tracemalloc.start()
    try:
        with pytest.raises(roadgen.RoadgenError, match=r"GiB of memory, above the limit "
                           r"roadgen.checks.MAX_MEMORY_BYTES = 4 GiB"):  # fmt: skip
            make()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1_000_000


@settings(max_examples=80, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])  # fmt: skip
@given(log_length=st.floats(0.0, 12.0), log_dx=st.floats(-12.0, 0.0), kind=st.booleans())
def test_a_road_is_made_exactly_when_its_estimate_fits(monkeypatch, log_length, log_dx, kind):
    """Under a 2 MB limit: refused (RoadgenError) iff the estimate exceeds it, else made."""
    monkeypatch.setattr(checks, "MAX_MEMORY_BYTES", 2_000_000)
    length, dx = 10.0**log_length, 10.0**log_dx
    fits = checks.BYTES_PER_POINT * (length / dx + 1) <= checks.MAX_MEMORY_BYTES
    try:
        road = (
            roadgen.track([(length / 2, 300.0), (length / 2, 500.0)], dx_m=dx, blend_m=2.5 * dx,
                          lead_in_m=0.0, seed=1)
            if kind
            else roadgen.iso8608_profile(length, 300.0, dx_m=dx, seed=1)
        )  # fmt: skip
    except roadgen.RoadgenError as exc:
        assert not fits or "out of range" in str(exc) or "too short" in str(exc)
        return
    assert fits and road.z.size * checks.BYTES_PER_POINT <= 2 * checks.MAX_MEMORY_BYTES


BAD_SEEDS = st.one_of(
    st.integers(max_value=-1),
    st.integers(min_value=2**128, max_value=2**300),
    st.floats(allow_nan=True),
    st.text(max_size=3),
    st.booleans(),
    st.lists(st.integers(0, 9), max_size=2),
)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=BAD_SEEDS)
def test_invalid_seeds_give_a_clear_error(seed):
    for make in (
        lambda: roadgen.iso8608_profile(5.0, 300.0, seed=seed),
        lambda: roadgen.track([(5.0, 300.0), (5.0, 500.0)], seed=seed),
    ):
        with pytest.raises(roadgen.RoadgenError, match=r"^seed="):
            make()


def test_valid_seeds_still_work():
    a = roadgen.iso8608_profile(5.0, 300.0, seed=np.int64(3))
    b = roadgen.iso8608_profile(5.0, 300.0, seed=3)
    c = roadgen.iso8608_profile(5.0, 300.0, seed=np.random.default_rng(3))
    assert np.array_equal(a.z, b.z) and a.settings.seed == 3 and c.settings.seed is None
    assert roadgen.iso8608_profile(5.0, 300.0, seed=2**127).z.size > 0
