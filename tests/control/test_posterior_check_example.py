"""examples/posterior_check.py (the paper's Table 2 with its window emulator) runs end to end."""

import json

from tests._examples import load_example


def test_table_two_runs_on_the_shipped_window_emulator(tmp_path, capsys):
    summary = load_example("posterior_check").main(["--roads", "1", "--out", str(tmp_path)])
    printed = capsys.readouterr().out
    assert "Table 2, case A" in printed and "max / mean percent error" in printed
    saved = json.loads((tmp_path / "table2_A.json").read_text())
    assert saved["summary"] == summary
    errors = saved["percent_error"]
    assert len(errors) == 7 and all(len(row) == 3 for row in errors)  # GD x speed, one road each
    gds = (250, 300, 350, 400, 450, 500, 550)
    prior_only = sum(abs(400 - gd) / gd for gd in gds) / len(gds) * 100  # the prior's mean, 23.6
    assert 0 < summary["one_road"]["mean"] < prior_only  # the windows inform GD (seeded: fixed)
    assert (tmp_path / "posterior_grid_A.png").stat().st_size > 0
