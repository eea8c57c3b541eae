"""``terrain-replay`` used in odd but valid ways: its summary piped into ``head`` (or into a
reader that has gone), stderr closed with ``--progress``, and two runs given one ``--out``.

Before: a reader that had gone ended the command with a BrokenPipeError traceback and exit
status 1 after it had written its outputs; ``--progress`` with no stderr (``2>&-``) crashed in
the progress bar (status 1, nothing written); and a run whose write into ``--out`` failed
removed the outputs of another run written there meanwhile, by name, or the whole folder it
had found missing, the other run's outputs in it (seen: two runs given one ``--out``, the
second exiting 0 with "wrote same/estimates.csv, ..." and the folder empty)."""

import os
import sys

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import ControlError  # noqa: E402
from control.robot import cli, write_sensor_bag  # noqa: E402


@pytest.fixture
def bag(tmp_path):
    """A short, healthy ROS 2 bag (MCAP storage): 400 samples at 120 Hz, 1 m/s."""
    t = 1.0 + np.arange(400) / 120.0
    accel = np.random.default_rng(1).normal(size=t.size)
    return write_sensor_bag(tmp_path / "drive", t, accel, t, t - 1.0, np.ones(t.size))


def test_a_reader_that_has_gone_ends_no_run_in_a_traceback(bag, tmp_path, monkeypatch, capsys):
    read, write = os.pipe()
    os.close(read)  # `terrain-replay BAG ... | head -1`, head gone
    with open(write, "w") as gone:
        monkeypatch.setattr(sys, "stdout", gone)
        code = cli.main([str(bag), "--emulator", "A", "--out", str(tmp_path / "out")])
        monkeypatch.undo()
    assert code == 0
    assert "Traceback" not in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(cli.OUTPUTS)


def test_progress_with_stderr_closed_runs(bag, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "stderr", None)  # `terrain-replay ... --progress 2>&-`
    code = cli.main([str(bag), "--emulator", "A", "--out", str(tmp_path / "out"), "--progress"])
    monkeypatch.undo()
    assert code == 0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(cli.OUTPUTS)


class _Result:
    """Stands for a ReplayResult; ``meanwhile`` runs before its CSV is written (another run
    writing into the same --out), ``fail`` makes its bag write fail."""

    def __init__(self, meanwhile=None, fail=False) -> None:
        self.meanwhile, self.fail = meanwhile, fail

    def to_csv(self, path):
        if self.meanwhile:
            self.meanwhile()
        path.write_text("mine\n")

    def write_bag(self, path):
        if self.fail:
            raise ControlError(f"{path}: cannot write (No space left on device)")
        path.mkdir()


def _others_outputs(out):
    out.mkdir(parents=True, exist_ok=True)
    (out / "estimates.csv").write_text("theirs\n")
    (out / "estimates").mkdir()
    (out / "estimates" / "metadata.yaml").write_text("theirs\n")
    (out / "replay.json").write_text("{}")


def test_outputs_another_run_wrote_meanwhile_are_neither_replaced_nor_removed(tmp_path):
    out = tmp_path / "same"
    _others_outputs(out)  # after this run's check of --out (`_check_out`), before its write
    with pytest.raises(ControlError, match=r"estimates.csv exists already"):
        cli._write(out, _Result(), {})
    assert (out / "estimates.csv").read_text() == "theirs\n"
    assert (out / "estimates" / "metadata.yaml").read_text() == "theirs\n"
    assert (out / "replay.json").read_text() == "{}"


def test_a_failed_write_removes_only_what_it_wrote(tmp_path):
    out = tmp_path / "made" / "here"  # missing: this run makes both folders

    def another_run_writes_a_file():
        (out / "theirs.txt").write_text("theirs\n")

    with pytest.raises(ControlError, match="No space left"):
        cli._write(out, _Result(meanwhile=another_run_writes_a_file, fail=True), {})
    assert os.listdir(out) == ["theirs.txt"]  # its estimates.csv removed, their file kept


def test_a_failed_write_into_missing_folders_still_leaves_none(tmp_path):
    out = tmp_path / "made" / "here"
    with pytest.raises(ControlError, match="No space left"):
        cli._write(out, _Result(fail=True), {})
    assert os.listdir(tmp_path) == []
