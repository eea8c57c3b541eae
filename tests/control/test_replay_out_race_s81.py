"""Two ``terrain-replay`` runs given one ``--out`` that write at the same time: the run that
finishes keeps all its outputs. Before, each output was checked (``os.path.lexists``) and then
written over whatever had appeared meanwhile (the estimates' CSV is replaced where it is one),
so a run that found the other's CSV replaced by its own, then failed on the other's bag,
removed that CSV: the other run exited 0 with "wrote .../estimates.csv" and no such file."""

import pytest

pytest.importorskip("rosbags")

from control.errors import ControlError  # noqa: E402
from control.robot import cli  # noqa: E402


class _Result:
    """Stands for a ReplayResult whose outputs read ``mark``; ``meanwhile`` runs as its CSV is
    written (another run writing into the same --out then)."""

    def __init__(self, mark: str, meanwhile=None) -> None:
        self.mark, self.meanwhile = mark, meanwhile

    def to_csv(self, path):
        if self.meanwhile:
            self.meanwhile()
        path.write_text(self.mark)  # ReplayResult.to_csv replaces an empty file or a CSV

    def write_bag(self, path):
        path.mkdir()
        (path / "metadata.yaml").write_text(self.mark)


def test_a_run_writing_meanwhile_into_the_same_out_leaves_the_first_whole(tmp_path):
    out = tmp_path / "same"
    other = []

    def another_run():
        try:
            cli._write(out, _Result("theirs\n"), {"run": "theirs"})
            other.append("wrote")
        except ControlError as exc:
            other.append(str(exc))

    cli._write(out, _Result("mine\n", meanwhile=another_run), {"run": "mine"})  # exits 0
    assert "estimates.csv exists already" in other[0]  # the other run refused, not this one
    assert sorted(p.name for p in out.iterdir()) == sorted(cli.OUTPUTS)
    assert (out / "estimates.csv").read_text() == "mine\n"
    assert (out / "estimates" / "metadata.yaml").read_text() == "mine\n"
    assert '"mine"' in (out / "replay.json").read_text()


def test_a_symlink_planted_at_an_output_is_refused_and_kept(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    target = tmp_path / "elsewhere.txt"
    target.write_text("keep\n")
    (out / "replay.json").symlink_to(target)
    with pytest.raises(ControlError, match="replay.json exists already"):
        cli._write(out, _Result("mine\n"), {})
    assert target.read_text() == "keep\n" and (out / "replay.json").is_symlink()
    assert sorted(p.name for p in out.iterdir()) == ["replay.json"]  # its own outputs removed
