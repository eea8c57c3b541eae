"""examples/train_emulator.py end to end on a small design: a file the closed loop accepts."""

import numpy as np
import pytest

import control
import roadgen
import vehicle
from control.bcr import DEFAULT_PHASES
from tests._examples import load_example


def load_script():
    return load_example("train_emulator")


def test_stretched_design_spans_the_domain_and_stays_latin():
    design = load_script().stretched_design(40, seed=3)
    original = vehicle.lhs_design(40, seed=3)
    assert design[:, 0].min() == pytest.approx(0.5) and design[:, 0].max() == pytest.approx(2.0)
    assert design[:, 1].min() == pytest.approx(200) and design[:, 1].max() == pytest.approx(600)
    for col, width in ((0, 1.5), (1, 400.0)):
        # An affine map keeps the order, and neighbours stay within about two strata.
        assert np.array_equal(np.argsort(design[:, col]), np.argsort(original[:, col]))
        assert np.max(np.diff(np.sort(design[:, col]))) <= 2.2 * width / 40


def test_arcsine_speed_spacing_keeps_the_latin_order_and_crowds_the_ends():
    script = load_script()
    uniform = script.stretched_design(200, seed=4)
    arcsine = script.stretched_design(200, seed=4, speed_spacing="arcsine")
    assert np.array_equal(arcsine[:, 1], uniform[:, 1])  # GD untouched
    assert np.array_equal(np.argsort(arcsine[:, 0]), np.argsort(uniform[:, 0]))
    assert arcsine[:, 0].min() == pytest.approx(0.5) and arcsine[:, 0].max() == pytest.approx(2.0)

    def share_near_ends(v):  # within 5% of the range of either end
        return np.mean((v < 0.575) | (v > 1.925))

    # the arcsine law puts 2 acos(0.9) / pi = 29% there, uniform spacing 10%
    assert share_near_ends(uniform[:, 0]) == pytest.approx(0.10, abs=0.02)
    assert share_near_ends(arcsine[:, 0]) == pytest.approx(0.287, abs=0.03)
    with pytest.raises(ValueError, match="speed_spacing must be one of"):
        script.stretched_design(10, seed=0, speed_spacing="chebyshev")


def test_anchor_runs_lie_on_their_speeds_one_per_gd_stratum():
    script = load_script()
    rows = script.anchor_design((1.0, 2.0), 20, seed=5, gd_range=(200.0, 600.0))
    assert rows.shape == (40, 2)
    for k, v in enumerate((1.0, 2.0)):
        line = rows[20 * k : 20 * (k + 1)]
        assert np.all(line[:, 0] == v)
        strata = np.floor((line[:, 1] - 200.0) / 20.0).astype(int)
        assert sorted(strata) == list(range(20))  # one GD in each 20-wide stratum
    # the two speeds draw their GDs apart, and the seed decides them
    assert not np.allclose(np.sort(rows[:20, 1]), np.sort(rows[20:, 1]))
    again = script.anchor_design((1.0, 2.0), 20, seed=5, gd_range=(200.0, 600.0))
    assert np.array_equal(rows, again)
    assert script.anchor_design((), 20, seed=5, gd_range=(200.0, 600.0)).shape == (0, 2)


@pytest.mark.parametrize(
    "speed_range, anchors",
    [((0.5, 2.0), [1.0, 2.0]), ((0.5, 1.5), [1.0, 1.5]), ((0.5, 1.0), [1.0]), ((1.2, 3.0), [3.0])],
)
def test_default_anchors_are_the_safe_speed_inside_the_range_and_its_top(speed_range, anchors):
    assert load_script().default_anchor_speeds(speed_range) == anchors


def test_small_training_run_gives_emulators_the_loop_accepts(tmp_path, monkeypatch):
    script = load_script()
    shipped = {p: p.stat().st_mtime_ns for p in script.EMULATOR_DIR.glob("*.gpmsa")}
    script.main(
        ["--out", str(tmp_path), "--n-runs", "24", "--n-iter", "300", "--keep-s", "18"]
    )  # fmt: skip
    import gpmsa

    # without --ship the package's emulators are left alone
    assert {p: p.stat().st_mtime_ns for p in script.EMULATOR_DIR.glob("*.gpmsa")} == shipped
    folder = tmp_path / "emulators"
    for case, noise in (("A", 0.0), ("B", 1.0)):
        for kind in ("band", "window"):
            emu = gpmsa.load(folder / control.shipped.emulator_file_name(case, kind))
            assert emu.metadata["noise_std"] == noise
            assert emu.metadata["design"]["speed_spacing"] == "uniform"
            assert emu.domain["v"] == pytest.approx((0.5, 2.0))
            assert set(emu.metadata["versions"]) >= {"numpy", "scipy", "exudyn", "python"}
            control.check_emulator(emu, model=vehicle.Jackal(), noise_std=noise)
    band = gpmsa.load(folder / "jackal_A.gpmsa")
    assert band.l_sim == 10 and "block_scatter" in band.metadata  # 8 bands, 2 quantiles
    # the band emulators add 24 // 6 runs at each of the default Simplex's speeds; the paper's
    # window emulators keep the paper's Latin hypercube
    design = band.metadata["design"]
    assert (design["n"], design["anchor_speeds"], design["anchor_runs"]) == (32, [1.0, 2.0], 4)
    assert band.m == 32 and np.sum(band.zt[:, 0] == 1.0) >= 4  # zt: inputs scaled to [0, 1]
    window = gpmsa.load(folder / "jackal_A_window.gpmsa").metadata["design"]
    assert (window["n"], window["anchor_speeds"], window["anchor_runs"]) == (24, [], 0)
    assert (tmp_path / "lhs_design.png").is_file()
    track = roadgen.track([(15, 300)], seed=1)
    r = control.run_closed_loop(track, band, seed=1)
    assert (r.status == "ok").mean() > 0.8
    # the main command runs on these emulators instead of the shipped ones
    argv = ["--out", str(tmp_path / "loop"), "--runs", "1", "--track", "12:300,12:450",
            "--emulator-dir", str(folder)]  # fmt: skip
    metrics = load_example("closed_loop").main(argv)
    assert metrics["settings"]["emulator_dir"] == str(folder)
    for case in ("A", "B"):
        rmse = metrics["ours"][case]["rmse"]
        assert set(rmse) == {"300", "450"} and all(0 < v < 400 for v in rmse.values())


def test_ship_and_emulator_dir_exclude_each_other(tmp_path):
    with pytest.raises(SystemExit):
        load_script().main(["--out", str(tmp_path), "--ship", "--emulator-dir", str(tmp_path)])


def test_vehicle_overrides_make_the_users_robot():
    script = load_script()
    model = script.vehicle_model(["mass_kg=21.5", "tyre_stiffness_n_per_m=26000", "lift_off=no"])
    assert (model.mass_kg, model.tyre_stiffness_n_per_m, model.lift_off) == (21.5, 26000.0, False)
    assert model.b1_m == vehicle.Jackal().b1_m
    with pytest.raises(ValueError, match="mass_kg"):
        script.vehicle_model(["weight=20"])


def test_block_samples_quantiles_and_n_pc_options_set_the_bcrs_block_and_the_basis(tmp_path):
    import gpmsa

    load_script().main(
        ["--out", str(tmp_path), "--n-runs", "16", "--n-iter", "200", "--keep-s", "12",
         "--cases", "A", "--features", "band", "--block-samples", "80", "--n-pc", "7",
         "--quantiles"]
    )  # fmt: skip
    emu = gpmsa.load(tmp_path / "emulators" / "jackal_A.gpmsa")
    assert emu.p_u == 7 and emu.metadata["fit"]["n_pc"] == 7 and emu.l_sim == 8
    feature = control.FeatureSpec.from_dict(emu.metadata["feature"])
    assert feature.block_samples == 80 and feature.quantiles == ()  # the band powers alone
    settings = control.bcr_settings_for(emu)
    every = -(-80 // DEFAULT_PHASES)  # the default's interleaved phases of 80-sample blocks
    assert settings.feature.block_samples == 80 and settings.samples_per_update == every
    r = control.run_closed_loop(roadgen.track([(10, 300)], seed=2), emu, seed=2)
    assert np.median(np.diff(r.time)) == pytest.approx(every / 120)
    assert (r.status == "ok").mean() > 0.7


@pytest.mark.parametrize("block", ["10", "20"])
def test_block_samples_too_short_for_the_bands_is_refused(tmp_path, block, capsys):
    with pytest.raises(SystemExit):
        load_script().main(["--out", str(tmp_path), "--block-samples", block])
    assert "--block-samples" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--n-pc", "0"], "--n-pc must be in [1, 10]"),
        (["--n-pc", "11"], "--n-pc must be in [1, 10]"),
        (["--n-pc", "9", "--quantiles"], "--n-pc must be in [1, 8]"),
        (["--quantiles", "0.9", "1.5"], "--quantiles: quantiles must be a sequence of levels"),
        (["--quantiles", "0.98", "0.9"], "--quantiles: quantiles must be increasing"),
    ],
)
def test_n_pc_beyond_the_outputs_and_bad_quantiles_are_refused(tmp_path, args, message, capsys):
    with pytest.raises(SystemExit):
        load_script().main(["--out", str(tmp_path), *args])
    assert message in capsys.readouterr().err


def test_a_slower_robots_emulators_and_a_simplex_within_their_speeds(tmp_path, capsys):
    import gpmsa

    load_script().main(
        ["--out", str(tmp_path), "--n-runs", "16", "--n-iter", "200", "--keep-s", "18",
         "--cases", "A", "--speed-range", "0.5", "1.5"]
    )  # fmt: skip
    folder = tmp_path / "emulators"
    band = gpmsa.load(folder / "jackal_A.gpmsa")
    assert band.domain["v"] == pytest.approx((0.5, 1.5))
    assert band.metadata["design"]["v_range"] == [0.5, 1.5]
    assert band.metadata["design"]["anchor_speeds"] == [1.0, 1.5]  # its safe and top speeds
    assert band.metadata["block_scatter"]["speed_mps"][-1] == pytest.approx(1.5)
    track = roadgen.track([(8, 300)], seed=3)
    with pytest.raises(control.EmulatorMismatchError, match="v_max = 2 m/s lies outside"):
        control.run_closed_loop(track, band, seed=3)  # the paper's Simplex would drive blind
    r = control.run_closed_loop(track, band, seed=3, simplex=control.Simplex(v_max=1.5))
    assert (r.status == "ok").mean() > 0.7 and r.command.max() <= 1.5
    loop = load_example("closed_loop")
    argv = ["--out", str(tmp_path / "loop"), "--runs", "1", "--track", "10:300", "--cases", "A",
            "--emulator-dir", str(folder)]  # fmt: skip
    with pytest.raises(SystemExit):
        loop.main(argv)
    assert "--v-safe / --v-max: the Simplex's v_max = 2 m/s" in capsys.readouterr().err
    metrics = loop.main([*argv, "--v-max", "0.9", "--v-safe", "0.6"])  # both below the default
    assert 0 < metrics["ours"]["A"]["rmse"]["300"] < 400


def test_too_few_finished_latin_hypercube_runs_for_the_window_fit_is_a_usage_error(
    tmp_path, monkeypatch, capsys
):
    """The check counted the anchor runs too, which the window emulators do not fit: 3 of 4
    Latin-hypercube runs finished (5 of 6 in all) and gpmsa.SimData raised a traceback."""
    import dataclasses

    script = load_script()
    real = script.vehicle.run_campaign

    def one_lhs_run_fails(design, *args, **kwargs):  # as a vehicle leaving the road would
        campaign = real(design, *args, **kwargs)
        nan, status = np.full(campaign.accel.shape[1], np.nan), campaign.status.copy()
        status[0] = "SimulationDivergedError: states out of range"
        changed = {"status": status}
        for name in ("f_full", "f_window", "f_full_noisy", "f_window_noisy"):
            changed[name] = getattr(campaign, name).copy()
            changed[name][0] = np.nan
        for name in ("accel", "accel_measured"):
            changed[name] = getattr(campaign, name).copy()
            changed[name][0] = nan
        return dataclasses.replace(campaign, **changed)

    monkeypatch.setattr(script.vehicle, "run_campaign", one_lhs_run_fails)
    with pytest.raises(SystemExit):  # 50 s: 6 batches a run, so 6 runs can give the scatter
        script.main(
            ["--out", str(tmp_path), "--n-runs", "4", "--n-pc", "4", "--n-iter", "20",
             "--keep-s", "50", "--cases", "A", "--features", "window", "band"]
        )  # fmt: skip
    err = capsys.readouterr().err
    assert "only 3 of the window emulators' 4 runs finished" in err
    assert "fewer than the 4 a fit needs" in err
    assert not list((tmp_path / "emulators").glob("*.gpmsa"))  # refused before any fit


def test_a_speed_range_too_slow_to_drive_names_the_option(tmp_path, capsys):
    """The campaign's refusal of a drive too long named --n-runs, --anchor-runs and --keep-s
    only, where --speed-range LO made it."""
    with pytest.raises(SystemExit):
        load_script().main(["--out", str(tmp_path), "--speed-range", "1e-9", "2"])
    err = capsys.readouterr().err
    assert "the campaign (--n-runs, --anchor-runs, --keep-s, --speed-range): design[" in err
    assert "(v=1e-09 m/s)" in err
