"""The warning of an update interval longer than ``max_age_s`` (`BCRSettings`): it points at the
user's line also where the settings are made by ``dataclasses.replace`` or
``bcr_settings_for(..., update_every=)`` (before: at dataclasses.py), it is not given again
where control re-makes settings (each copy names the user's line: the default filter shows it
once), and its remedy is a number that works (before: "at most
491 samples" where 492 is quiet, "at most 0 samples", or a count below the change-point
method's least update_every)."""

import dataclasses
import warnings

import pytest

import control
from control import BCR, PAPER_WINDOW, BCRSettings, ControlWarning, FeatureSpec
from control.closed_loop import simulated_sensor_settings


def holds(caught) -> list:
    return [w for w in caught if issubclass(w.category, ControlWarning)
            and "max_age_s" in str(w.message)]  # fmt: skip


def test_settings_made_by_replace_warn_at_the_users_line():
    quiet = BCRSettings(method="window", feature=PAPER_WINDOW, update_every=600)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dataclasses.replace(quiet, update_every=1000)
        control.bcr_settings_for(control.shipped_emulator("A", "window"), update_every=1000)
    assert [w.filename for w in holds(caught)] == [__file__] * 2


def test_controls_own_copies_warn_at_the_users_line_so_the_default_filter_shows_one():
    """control re-makes the settings (the simulated sensor's, a BCR's): each copy's warning
    names the user's line, so Python's default filter shows it once per line."""
    emulator = control.shipped_emulator("A", "window")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        settings = control.bcr_settings_for(emulator, update_every=1000)
        loop = simulated_sensor_settings(settings, 0.0)  # as run_closed_loop re-makes them
        BCR.from_emulator(emulator, loop)
    assert holds(caught) and {w.filename for w in holds(caught)} == {__file__}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        for _ in range(3):
            simulated_sensor_settings(settings, 0.0)  # one line, three copies
    assert len(holds(caught)) == 1
    assert (loop.update_every, loop.max_age_s) == (1000, 5.0)


def test_the_remedys_count_is_the_largest_that_is_quiet():
    with pytest.warns(ControlWarning, match=r"at most 492 samples") as record:
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=1000, max_age_s=4.1)
    assert "at least 8.33333 s" in str(record[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ControlWarning)
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=492, max_age_s=4.1)


@pytest.mark.parametrize(
    ("kwargs", "least"),
    [
        ({"method": "window", "feature": PAPER_WINDOW, "update_every": 1, "max_age_s": 0.005},
         "update_every is at least 1"),
        ({"feature": FeatureSpec(block_samples=4096), "max_age_s": 1.0},
         "update_every is at least 512"),
    ],
)  # fmt: skip
def test_where_no_update_every_is_short_enough_it_says_raise_max_age(kwargs, least):
    with pytest.warns(ControlWarning, match="longer than max_age_s") as record:
        settings = BCRSettings(**kwargs)
    message = str(record[0].message)
    assert "lower update_every" not in message and least in message
    held = settings.samples_per_update / settings.rate_hz
    assert f"raise max_age_s to at least {held:.6g} s" in message
