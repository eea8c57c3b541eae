"""roadgen messages that set a value beside what it is checked against, at six (or three)
digits, read two distinct numbers apart (`roadgen.errors.distinct_texts`)."""

import dataclasses

import pytest

import roadgen
from roadgen import checks, envelope
from roadgen.errors import RoadgenError


def test_boundaries_off_by_less_than_six_digits_are_named_apart_from_the_expected_ones():
    # Before: "boundaries_m=(0.0, 33.3333) do not match ...: at (0, 33.3333) m".
    track = roadgen.track([(100 / 3, 300), (20, 500)], dx_m=0.05, seed=0)
    with pytest.raises(RoadgenError, match=r"at \(0\.0, 33\.333333333333336\) m"):
        dataclasses.replace(track, boundaries_m=(0.0, 33.3333))


def test_work_just_past_the_envelope_limit_does_not_read_as_the_limit(monkeypatch):
    # Before: "2e+04 comparisons, above MAX_ENVELOPE_WORK = 2e+04".
    road = roadgen.iso8608_profile(20.0, 300.0, dx_m=0.01, seed=1)  # 2001 points
    monkeypatch.setattr(envelope, "MAX_ENVELOPE_WORK", 2001 * 10 - 1)
    with pytest.raises(
        RoadgenError, match=r"20010\.0 comparisons, above MAX_ENVELOPE_WORK = 20009\.0;"
    ):
        roadgen.wheel_envelope(road, 0.1)  # 10 steps on each side


def test_memory_just_past_the_limit_does_not_read_as_the_limit():
    # Before: "needs about 4 GiB of memory, above the limit ... = 4 GiB".
    with pytest.raises(RoadgenError) as info:
        checks.memory_limit(4 * 1024**3 + 1024, "x", 4 * 1024**3, "LIMIT", "adv", RoadgenError)
    assert "needs about 4.000000953674316 GiB" in str(info.value), str(info.value)
    assert "LIMIT = 4.0 GiB" in str(info.value), str(info.value)
