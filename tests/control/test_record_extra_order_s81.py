"""run_closed_loop names a wrong ``record`` path with or without the robot extra (before, an
installation without it answered a path of the wrong type, or a folder, with the extra to
install)."""

from __future__ import annotations

import pytest

import control
import control.robot.record
import roadgen
from control.errors import ControlError, MissingExtraError


def _no_extra():
    raise MissingExtraError("recording a run as MCAP needs the optional package 'mcap'")


@pytest.mark.parametrize(
    ("record", "match"),
    [(5, r"record must be the path \(a str or os.PathLike\)"), ("", "record")],
)
def test_a_wrong_record_path_is_named_without_the_extra(monkeypatch, emulator_a, record, match):
    monkeypatch.setattr(control.robot.record, "check_can_record", _no_extra)
    track = roadgen.track([(10.0, 300.0)], seed=0)
    with pytest.raises(ControlError, match=match) as info:
        control.run_closed_loop(track, emulator_a, record=record)
    assert not isinstance(info.value, MissingExtraError)


def test_a_good_path_without_the_extra_names_the_extra(monkeypatch, emulator_a, tmp_path):
    monkeypatch.setattr(control.robot.record, "check_can_record", _no_extra)
    track = roadgen.track([(10.0, 300.0)], seed=0)
    with pytest.raises(MissingExtraError, match="optional package 'mcap'"):
        control.run_closed_loop(track, emulator_a, record=tmp_path / "run.mcap")
