"""A robotics engineer retrains the emulators for their robot and terrain (examples/
train_emulator.py) and drives the closed loop on them (examples/closed_loop.py): session 69."""

import pytest
from _train_cases import CampaignReached, run_until_the_campaign

import control
from tests._examples import load_example


class LoopReached(Exception):
    pass


@pytest.mark.parametrize(
    "option",
    [
        ["--anchor-speeds", "1.2"],
        ["--anchor-runs", "4"],
        ["--block-samples", "60"],
        ["--quantiles", "0.5"],
        ["--n-pc", "3"],
    ],
)
def test_band_options_without_band_emulators_are_refused(tmp_path, monkeypatch, capsys, option):
    """``--features window --anchor-speeds 1.2 --anchor-runs 4 --n-pc 3 --quantiles 0.5
    --block-samples 60`` trained the window emulators and silently dropped every one of these
    (the file recorded anchor_speeds [] and no n_pc): they shape the band emulators only."""
    with pytest.raises(SystemExit) as exc:
        run_until_the_campaign(monkeypatch, tmp_path, ["--features", "window", *option])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"{option[0]} shapes the band emulators only" in err
    assert "--features window does not fit" in err


def test_a_noise_level_without_case_b_is_refused(tmp_path, monkeypatch, capsys):
    """``--cases A --noise-std 0.3`` wrote a noise-free jackal_A.gpmsa (metadata noise_std 0.0)
    and said nothing: the noise is case B's."""
    with pytest.raises(SystemExit) as exc:
        run_until_the_campaign(monkeypatch, tmp_path, ["--cases", "A", "--noise-std", "0.3"])
    assert exc.value.code == 2
    assert "--noise-std 0.3 is case B's noise" in capsys.readouterr().err
    with pytest.raises(CampaignReached):  # the defaults, and each option where it applies
        run_until_the_campaign(monkeypatch, tmp_path, ["--cases", "A"])
    with pytest.raises(CampaignReached):
        run_until_the_campaign(
            monkeypatch, tmp_path,
            ["--cases", "B", "--noise-std", "0.3", "--features", "band", "--n-pc", "6"],
        )  # fmt: skip


def loop_until_the_runs(monkeypatch, tmp_path, argv) -> dict:
    """closed_loop.main(argv) with its first run replaced: the Simplex it would drive."""
    script = load_example("closed_loop")
    seen: dict = {}

    def run_case(case, emu, seeds, method, simplex, *args, **kwargs):
        seen["simplex"] = simplex
        raise LoopReached

    monkeypatch.setattr(script, "run_case", run_case)
    with pytest.raises(LoopReached):
        script.main([*argv, "--out", str(tmp_path / "out"), "--cases", "A"])
    return seen


def test_the_loop_takes_the_simplex_gd_band(tmp_path, monkeypatch, capsys):
    """closed_loop.py had no option for the Simplex's GD band: emulators trained on rougher
    ground (``train_emulator.py --gd-range 400 900``) were refused with ``--v-safe / --v-max:
    Simplex gd_max = 350 is not above the emulator's lowest GD 400``, naming options that are
    not the cause, and no option could set the band."""
    seen = loop_until_the_runs(monkeypatch, tmp_path, ["--gd-min", "300", "--gd-max", "450"])
    assert (seen["simplex"].gd_min, seen["simplex"].gd_max) == (300.0, 450.0)
    script = load_example("closed_loop")
    with pytest.raises(SystemExit) as exc:  # the band below the shipped domain, GD 200-600
        script.main(["--out", str(tmp_path / "o"), "--gd-min", "100", "--gd-max", "150"])
    assert exc.value.code == 2
    assert "--gd-min / --gd-max: Simplex gd_max = 150 is not above" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        script.main(["--out", str(tmp_path / "o"), "--gd-min", "400", "--gd-max", "300"])
    assert "--gd-min / --gd-max: gd_min must be < gd_max" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_the_loop_says_which_runs_latched_in_safety_mode(tmp_path, capsys, monkeypatch):
    """A run that a fault latches in safety mode drives the rest of the track at v_safe: the
    tables showed 0 m fast on rough ground and a long time, and nothing said the run had
    latched (found with ``--v-safe 0.6``, whose first steady block spanned the track's flat
    lead-in and read a level jump; that is no longer a fault: a NaN burst stands in for it)."""
    script = load_example("closed_loop")
    loop = control.run_closed_loop

    def with_a_fault(*args, **kwargs):
        return loop(*args, **kwargs, faults=[control.SensorFault(1.5, 0.5, "nan")])

    monkeypatch.setattr(script.control, "run_closed_loop", with_a_fault)
    metrics = script.main(
        ["--out", str(tmp_path), "--runs", "1", "--track", "4:300", "--cases", "A",
         "--v-safe", "0.6", "--method", "changepoint"]
    )  # fmt: skip
    latched = metrics["ours"]["A"]["runs"][0]["latched_at_s"]
    assert 1.5 <= latched <= 2.5
    out = capsys.readouterr().out
    assert "runs latched in safety mode by a fault" in out
    assert f"A seed 1 (ours): at {latched:.2f} s, sensor_fault: " in out


def test_check_emulator_still_refuses_a_gd_band_outside_the_domain():
    emu = control.shipped_emulator("A")
    with pytest.raises(control.EmulatorMismatchError, match="gd_max = 150 is not above"):
        control.check_emulator(emu, simplex=control.Simplex(gd_min=100, gd_max=150))
