"""A user trains emulators for another robot (heavier, stiffer tyres, a bigger wheel, 0.3-3 m/s,
GD 100-800) with examples/train_emulator.py and drives the closed loop on them (session 64)."""

import pytest

import control
import gpmsa
import roadgen
from tests._examples import load_example

ROBOT = ["mass_kg=30", "pitch_inertia_kgm2=0.8", "tyre_stiffness_n_per_m=35000",
         "wheel_radius_m=0.13", "max_speed_mps=3"]  # fmt: skip


class CampaignRan(Exception):
    pass


def _stop_before_the_campaign(monkeypatch, script, seen: dict) -> None:
    def campaign(design, model, *args, **kwargs):
        seen["model"], seen["design"] = model, design
        raise CampaignRan

    monkeypatch.setattr(script.vehicle, "run_campaign", campaign)


def test_a_repeated_vehicle_option_keeps_every_item(tmp_path, monkeypatch):
    """``--vehicle mass_kg=30 --vehicle max_speed_mps=3`` kept the last item alone (argparse
    replaced the list): the campaign drove the default 18.4 kg Jackal and the emulator recorded
    it, while the user had asked for 30 kg."""
    script = load_example("train_emulator")
    seen: dict = {}
    _stop_before_the_campaign(monkeypatch, script, seen)
    with pytest.raises(CampaignRan):
        script.main(["--out", str(tmp_path), "--speed-range", "0.3", "3",
                     "--vehicle", "mass_kg=30", "--vehicle", "max_speed_mps=3"])  # fmt: skip
    assert (seen["model"].mass_kg, seen["model"].max_speed_mps) == (30.0, 3.0)


def test_a_gd_range_in_cubic_metres_is_refused_before_the_campaign(tmp_path, monkeypatch, capsys):
    """``--gd-range 1e-4 8e-4`` (m^3, not 1e-6 m^3) trained, silently, on roads a million times
    too smooth; the loop refused the files only later (track GD outside the domain)."""
    script = load_example("train_emulator")
    _stop_before_the_campaign(monkeypatch, script, {})
    with pytest.raises(SystemExit) as exc:
        script.main(["--out", str(tmp_path), "--gd-range", "1e-4", "8e-4"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "GD is Gd(n0) in units of 1e-6 m^3" in err
    assert "a range given in m^3 is --gd-range 100 800" in err


def test_a_speed_range_beyond_the_top_speed_says_how_to_raise_it(tmp_path, capsys):
    with pytest.raises(SystemExit):
        load_example("train_emulator").main(["--out", str(tmp_path), "--speed-range", "0.3", "3"])
    assert "(a faster robot: --vehicle max_speed_mps=...)" in capsys.readouterr().err


def test_a_robot_faster_than_the_campaigns_road_trains_and_drives(tmp_path):
    """A 3 m/s robot could not train at all: the campaign refused ``road_length_m=21.0 is too
    short: a 1000-sample window at 3 m/s ... needs >= 26.52 m``, though ``--keep-s`` lengthens
    every road (here to 64 m at 3 m/s), and the script gives the user no road length to set."""
    load_example("train_emulator").main(
        ["--out", str(tmp_path), "--n-runs", "24", "--keep-s", "20", "--n-iter", "200",
         "--cases", "A", "--features", "band", "--speed-range", "0.3", "3",
         "--gd-range", "100", "800", "--vehicle", *ROBOT]
    )  # fmt: skip
    emu = gpmsa.load(tmp_path / "emulators" / "jackal_A.gpmsa")
    assert emu.domain["v"] == pytest.approx((0.3, 3.0))
    assert emu.domain["GD"] == pytest.approx((100.0, 800.0))
    assert emu.metadata["design"]["anchor_speeds"] == [1.0, 3.0]
    robot = control.emulator_vehicle(emu)
    assert (robot.mass_kg, robot.wheel_radius_m, robot.max_speed_mps) == (30.0, 0.13, 3.0)
    track = roadgen.track([(12, 150), (12, 600)], seed=3)
    simplex = control.Simplex(gd_min=250, gd_max=500, v_max=3.0, v_safe=0.8)
    with pytest.raises(control.EmulatorMismatchError, match="made for another vehicle"):
        # the default Jackal: said so, not "v_max = 3 m/s exceeds the vehicle's top speed 2"
        control.run_closed_loop(track, emu, seed=1, simplex=simplex)
    r = control.run_closed_loop(track, emu, model=robot, seed=1, simplex=simplex)
    assert r.command.max() > 2.0  # faster than the default Jackal could go
    assert (r.status == "ok").mean() > 0.5


def test_a_simplex_band_below_the_emulators_gds_is_refused():
    """``Simplex(gd_min=2.5e-4, gd_max=3.5e-4)`` (m^3) drove a whole track in safety mode: every
    estimate exceeds such a gd_max, and nothing said so."""
    emu = control.shipped_emulator("A")
    with pytest.raises(control.EmulatorMismatchError, match="not above the emulator's lowest GD"):
        control.check_emulator(emu, simplex=control.Simplex(gd_min=2.5e-4, gd_max=3.5e-4))
    with pytest.raises(control.EmulatorMismatchError, match="gd_max = 200 is not above"):
        control.run_closed_loop(
            roadgen.track([(8, 300)], seed=1), emu, simplex=control.Simplex(gd_min=100, gd_max=200)
        )
    control.check_emulator(emu, simplex=control.Simplex(gd_min=150, gd_max=201))  # inside


@pytest.mark.parametrize(
    "change, message",
    [
        ({"vehicle": {"mass_kg": 40.0}}, "mass_kg: band 18.431 vs window 40.0"),
        ({"noise_std": 0.3}, "noise sd: band 0 vs window 0.3 m/s^2"),
    ],
)
def test_closed_loop_refuses_a_cases_two_emulators_made_for_different_robots(
    tmp_path, capsys, change, message
):
    """Retraining one file of a case (``--features band`` or another ``--vehicle``) into a folder
    left the other from the earlier training: closed_loop.py drove each method on the robot its
    file recorded and printed the two side by side as one case (RMSE 119-137 against 27-177)."""
    band, window = (control.shipped_emulator("A", kind) for kind in ("band", "window"))
    meta = dict(window.metadata)
    for key, value in change.items():
        meta[key] = {**meta[key], **value} if isinstance(value, dict) else value
    window.metadata = meta
    band.save(tmp_path / "jackal_A.gpmsa")
    window.save(tmp_path / "jackal_A_window.gpmsa")
    with pytest.raises(SystemExit) as exc:
        load_example("closed_loop").main(
            ["--out", str(tmp_path / "out"), "--runs", "1", "--track", "10:300", "--cases", "A",
             "--emulator-dir", str(tmp_path)]
        )  # fmt: skip
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "case A's jackal_A.gpmsa and jackal_A_window.gpmsa were trained for different" in err
    assert message in err
    assert not (tmp_path / "out").exists()


def test_a_scatter_refused_after_failed_runs_names_them(tmp_path, capsys):
    """GD 100-50000 on this robot: 17 of 32 runs left the road (all but one of those above
    1.5 m/s) and the block scatter was singular at 2.46 m/s; the error said only "raise --n-runs
    or --keep-s", where the failed runs were the cause."""
    with pytest.raises(SystemExit):
        load_example("train_emulator").main(
            ["--out", str(tmp_path), "--n-runs", "24", "--keep-s", "20", "--n-iter", "20",
             "--cases", "A", "--features", "band", "--speed-range", "0.3", "3",
             "--gd-range", "100", "50000", "--vehicle", *ROBOT]
        )  # fmt: skip
    captured = capsys.readouterr()
    assert "failed runs are left out" in captured.out
    assert "is singular" in captured.err
    assert "runs failed (the vehicle left the road" in captured.err
    assert "lower --gd-range HI or --speed-range HI" in captured.err
