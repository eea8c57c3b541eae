"""examples/_cli.py: the scripts' outputs are written in one step."""

import json

import matplotlib
import pytest

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

from tests._examples import load_example  # noqa: E402

cli = load_example("_cli")


class Boom(RuntimeError):
    pass


def test_write_text_replaces_and_leaves_no_part(tmp_path):
    path = tmp_path / "metrics.json"
    cli.write_text(path, json.dumps({"a": 1}))
    cli.write_text(path, json.dumps({"a": 2}))
    assert json.loads(path.read_text()) == {"a": 2}
    assert [p.name for p in tmp_path.iterdir()] == ["metrics.json"]


def test_failed_figure_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "trace.png"
    fig = Figure()
    fig.subplots().plot([0, 1], [1, 0])
    cli.save_figure(fig, path)
    before = path.read_bytes()
    assert before.startswith(b"\x89PNG")

    def fail(fh, **kwargs):
        fh.write(b"\x89PNG half")
        raise Boom("disk full half way")

    monkeypatch.setattr(fig, "savefig", fail)
    with pytest.raises(Boom):
        cli.save_figure(fig, path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["trace.png"]
