"""examples/closed_loop.py (the README's main job): other tracks and seeds, and its input errors."""

import json
import math

import pytest

from tests._examples import load_example


def load_script():
    return load_example("closed_loop")


def test_segments_parse_and_bad_ones_are_named():
    parse = load_script().parse_segments
    assert parse("50:300, 50:500,50:300") == ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
    assert parse("12.5:250") == ((12.5, 250.0),)
    bad = {"50:300,30": "'30'", "50:300:1": "'50:300:1'", "a:b": "'a:b'", "50:-300": "'50:-300'",
           "nan:300": "'nan:300'", "": "''"}  # fmt: skip
    for text, named in bad.items():
        with pytest.raises(ValueError, match=named):
            parse(text)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--track", "40:250,30:700"], "outside the emulator's GD domain [200, 600] (--beyond"),
        (["--track", "40:250,30"], "not LENGTH_M:GD"),
        (["--first-seed", "-2"], "--first-seed must be >= 0"),
        (  # its last run's seed, 2**128 + 1, beyond the seeds' range
            ["--first-seed", str(2**128 - 2)],
            "--first-seed must be <= 2**128 - 3 (the seeds' range)",
        ),
        (["--runs", "0"], "--runs must be >= 1"),
        (["--speed-step", "-0.1"], "speed_step_mps must lie in"),
        (
            ["--emulator-dir", "no/such/dir", "--cases", "B"],
            "no/such/dir/jackal_B.gpmsa is missing",
        ),
    ],
)
def test_bad_arguments_are_a_usage_error_naming_the_option(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as exit_info:
        load_script().main(["--out", str(tmp_path), *argv])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_another_track_and_seed_give_one_rmse_per_prescribed_gd(tmp_path, capsys):
    argv = ["--out", str(tmp_path), "--runs", "1", "--first-seed", "7", "--track", "15:250,15:450"]
    metrics = load_script().main(argv)
    assert "paper" not in metrics  # the paper's figures belong to the paper's track only
    assert metrics["settings"]["seeds"] == [7]
    for key in ("ours", "paper_method"):
        for case in ("A", "B"):
            rmse = metrics[key][case]["rmse"]
            assert set(rmse) == {"250", "450"}
            assert all(0 < value < 400 for value in rmse.values())
            (run,) = metrics[key][case]["runs"]
            assert len(run["detection_delay_m"]) == 1  # one change on this track
    assert (
        json.loads((tmp_path / "metrics.json").read_text())["settings"]["track"] == "15:250,15:450"
    )
    assert {p.name for p in tmp_path.glob("*.png")} == {
        f"{kind}_{case}_{key}.png"
        for kind in ("gd_trace", "speed")
        for case in ("A", "B")
        for key in ("ours", "paper_method")
    }
    printed = capsys.readouterr().out
    assert "seed 7 (no paper figures for this track)" in printed
    assert "GD 250" in printed and "GD 450" in printed
    assert "edge of the emulator's GD domain" not in printed  # inside the domain: none named


def test_the_speed_figures_mark_the_simplex_settings_given(tmp_path, monkeypatch):
    """--v-safe 0.8 drew a line labelled "safe speed 1 m/s": the figures took plot_speed's
    defaults, not the Simplex's settings."""
    script = load_script()
    seen = []
    real = script.plot_speed

    def spy(*args, **kwargs):
        seen.append(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(script, "plot_speed", spy)
    argv = ["--out", str(tmp_path), "--runs", "1", "--track", "3:250,3:450", "--v-safe", "0.8"]
    script.main(argv)
    assert len(seen) == 4  # two cases x (ours, the paper's method)
    assert all(kw.get("v_safe") == 0.8 and kw.get("gd_max") == 350.0 for kw in seen)


def test_a_part_too_short_for_an_estimate_prints_a_dash_and_writes_null(tmp_path, capsys):
    # 2 m at <= 2 m/s ends before the paper's method fills its 1,000-sample window.
    metrics = load_script().main(["--out", str(tmp_path), "--runs", "1", "--track", "2:300"])
    assert all(math.isnan(metrics["paper_method"][case]["rmse"]["300"]) for case in ("A", "B"))
    written = json.loads((tmp_path / "metrics.json").read_text())  # strict JSON: no NaN token
    assert written["paper_method"]["A"]["rmse"]["300"] is None
    assert "NaN" not in (tmp_path / "metrics.json").read_text()
    out = capsys.readouterr().out
    # GD's unit in brackets in the table's title, as `gpmsa info` prints it (session 81)
    assert out.startswith("RMSE of the GD estimate [1e-6 m^3], seed 1 (no paper figures"), out
    rows = [line.split() for line in out.splitlines() if "GD 300" in line]
    assert len(rows) == 2 and all(row[3:5] == ["-", "-"] for row in rows)  # paper, paper method


def test_beyond_domain_drives_a_track_outside_the_emulators_domain_and_counts_named_edges(
    tmp_path, capsys
):
    argv = ["--out", str(tmp_path), "--runs", "1", "--first-seed", "1", "--cases", "B",
            "--track", "20:300,40:900", "--beyond-domain"]  # fmt: skip
    metrics = load_script().main(argv)
    (run,) = metrics["ours"]["B"]["runs"]
    assert run["domain_edge"]["upper"] > 0 and run["domain_edge"]["lower"] == 0
    printed = capsys.readouterr().out
    assert f"B seed 1: {run['domain_edge']['upper']} upper" in printed
