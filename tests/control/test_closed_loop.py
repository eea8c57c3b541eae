"""The closed loop with the shipped emulators: traces, metrics, faults, set-up guards."""

import shutil
import warnings

import numpy as np
import pytest

import control
import roadgen
import vehicle
from control import (
    PAPER_WINDOW,
    BCRSettings,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    FeatureSpec,
    SensorFault,
    Simplex,
    run_closed_loop,
)


@pytest.fixture(scope="module")
def short_run(emulator_a, likelihood_a):
    track = roadgen.track([(25, 300), (25, 500)], seed=3)
    return track, run_closed_loop(track, emulator_a, seed=3, likelihood=likelihood_a)


def test_the_loop_drives_to_the_end_and_scores_itself(short_run):
    track, r = short_run
    assert r.sample_position[-1] > track.length_m - 0.1
    ok = r.status == "ok"
    assert ok.mean() > 0.9  # an estimate from every block, bar the start-up
    assert np.all((r.command >= 1.0) & (r.command <= 2.0))
    assert np.all(r.gd_lo[ok] <= r.gd_mean[ok]) and np.all(r.gd_mean[ok] <= r.gd_hi[ok])
    smooth = ok & (r.position > 8) & (r.position < 25)
    rough = ok & (r.position > 33)
    assert r.gd_mean[rough].mean() > r.gd_mean[smooth].mean() + 100
    m = r.metrics
    assert m.traversal_time_s == pytest.approx(r.sample_time[-1])
    assert {e.gd for e in m.gd_errors} == {300.0, 500.0}
    assert 0 < m.latency_median_s < 0.05
    assert len(m.detection_delay_m) == 1 and m.detection_delay_m[0] < 10
    assert 0.5 < m.coverage <= 1.0
    assert np.all((r.prob_change[ok] >= 0) & (r.prob_change[ok] <= 1))
    assert set(m.as_dict()) >= {"rmse", "detection_delay_m", "fast_on_rough_m", "coverage"}


def test_metrics_refuse_a_gd_the_track_lacks_and_dump_as_strict_json(short_run):
    import json

    m = short_run[1].metrics
    assert m.rmse(300) == m.rmse(np.float64(300.0)) == m.gd_errors[0].rmse
    with pytest.raises(ControlError, match="no part of the track has prescribed GD 400; its GDs: "
                       "300, 500"):  # fmt: skip
        m.rmse(400)
    for bad in ("300", None, True):
        with pytest.raises(ControlError, match="gd must be a real number"):
            m.rmse(bad)
    summary = m.as_dict()
    assert np.isnan(m.latched_at_s) and summary["latched_at_s"] is None  # never latched
    assert json.loads(json.dumps(summary, allow_nan=False)) == summary


def test_safety_mode_whenever_the_estimate_exceeds_gd_max(short_run):
    _, r = short_run
    ok = r.status == "ok"
    assert np.all(r.mode[ok & (r.gd_mean > 350)] == "safety")
    assert np.all(r.mode[ok & (r.gd_mean <= 350)] == "performance")
    assert np.all(r.command[r.mode == "safety"] == 1.0)
    assert np.all(r.mode[~ok] == "safety")


def test_a_road_rougher_than_the_emulator_knows_is_named_and_driven_in_safety_mode(
    emulator_a, likelihood_a
):
    track = roadgen.track([(20, 300), (40, 900)], seed=2)  # GD 900: beyond the domain's 600
    r = run_closed_loop(track, emulator_a, seed=2, likelihood=likelihood_a, check=False)
    named = r.domain_edge == "upper"
    assert named[r.position > 20].mean() > 0.1 and not named[r.position < 20].any()
    assert np.all(r.mode[named] == "safety") and not np.any(r.domain_edge == "lower")
    assert control.edge_counts(r.domain_edge) == {"upper": int(named.sum()), "lower": 0}
    assert all("rougher than any the emulator knows" in why for why in r.reason[named])
    assert np.all(r.gd_hi[r.status == "ok"] <= 600.0)  # the posterior stays in the domain
    assert r.domain_edge.shape == r.status.shape and np.all(r.domain_edge[r.status != "ok"] == "")


def test_an_invisible_change_of_the_signal_leaves_the_run_as_it_was(short_run, likelihood_a):
    """The speed grid (Simplex.speed_step_mps) keeps a gain error of 1e-9, which no check can
    see, from setting off the loop's chaos: every command and position stays the same. On a
    continuous law the same error moves later positions (docs/closed-loop.md, "Faults")."""
    track, clean = short_run
    emu = control.shipped_emulator("A")
    invisible = (SensorFault(start_s=5.0, duration_s=3.0, kind="scale", magnitude=1 + 1e-9),)

    def run(step: float, faults=()):
        simplex = Simplex(speed_step_mps=step)
        return run_closed_loop(
            track, emu, seed=3, likelihood=likelihood_a, faults=faults, simplex=simplex
        )

    on_grid = run(0.1, invisible)
    assert np.array_equal(on_grid.command, clean.command)
    assert np.array_equal(on_grid.sample_position, clean.sample_position)
    ok = np.isfinite(clean.gd_mean)
    assert not np.array_equal(on_grid.gd_mean[ok], clean.gd_mean[ok])  # the estimates moved
    assert not np.array_equal(run(0.0, invisible).command, run(0.0).command)


@pytest.mark.parametrize(
    ("kind", "magnitude"), [("nan", 1.0), ("drop", 1.0), ("time_nan", 1.0), ("spike", 5.0)]
)
def test_a_sensor_fault_means_safety_mode_and_the_bcr_recovers(
    emulator_a, likelihood_a, kind, magnitude
):
    track = roadgen.track([(40, 300)], seed=5)
    fault = SensorFault(start_s=14.0, duration_s=0.5, kind=kind, magnitude=magnitude)
    runs = {
        after: run_closed_loop(
            track, emulator_a, seed=5, likelihood=likelihood_a, faults=[fault],
            simplex=Simplex(after_fault=after),
        )
        for after in ("latch", "resume")
    }  # fmt: skip
    for after, r in runs.items():
        hit = (r.time >= 14.0) & (r.time < 14.5 + 3 * 125 / 120)
        # while samples are missing the last estimate stands; every block with the fault in
        # it, and the one after it, give no estimate, and the robot slows to the safe speed
        faulty = hit & (r.status != "ok")
        assert faulty.sum() >= 2 and np.all(r.mode[faulty] == "safety")
        assert np.all(r.command[faulty] == 1.0)
        assert np.all(r.status[r.time > 17.0] == "ok")  # clean blocks: estimates again
        later = r.time > 17.0
        if after == "latch":  # the robot stays at the safe speed for the rest of the run
            assert 14.0 <= r.metrics.latched_at_s < 14.5 + 2 * 125 / 120
            assert np.all(r.command[later] == 1.0) and np.all(r.mode[later] == "safety")
        else:
            assert np.isnan(r.metrics.latched_at_s)
            assert np.any(r.mode[later] == "performance")


def test_samples_missing_at_the_end_of_an_update_are_a_fault_at_that_update(
    emulator_a, likelihood_a
):
    """The simulation's clock is exact: a drop that starts one sample before an update's end
    is silence at that update (the robot must not keep its speed for another block)."""
    track = roadgen.track([(30, 300)], seed=6)
    clean = run_closed_loop(track, emulator_a, seed=6, likelihood=likelihood_a)
    j = int(np.flatnonzero(clean.time > 8.0)[0])
    fault = SensorFault(start_s=clean.time[j] - 0.5 / 120, duration_s=0.5, kind="drop")
    r = run_closed_loop(track, emulator_a, seed=6, likelihood=likelihood_a, faults=[fault])
    np.testing.assert_array_equal(r.status[:j], clean.status[:j])
    assert r.status[j] == "sensor_fault" and "no samples" in r.reason[j]
    assert r.metrics.latched_at_s == pytest.approx(clean.time[j])
    assert r.settings["bcr"].max_silence_s < 1 / 120


def test_a_gain_drop_late_in_a_noisy_block_is_a_fault_at_that_update(likelihood_b):
    """Case B: a gain of 0.04 over the last 0.4 s of an update reads quieter than the sensor's
    own N(0, 1) noise, so that update is already a fault; noise-free data with the noisy
    emulator has no noise floor (the loop lowers it to the simulated noise)."""
    emu_b = control.shipped_emulator("B")
    b = {"likelihood": likelihood_b}  # prepared once for the session
    track = roadgen.track([(25, 500)], seed=7)
    clean = run_closed_loop(track, emu_b, noise_std=1.0, seed=7, **b)
    assert clean.settings["bcr"].sensor.noise_sd_mps2 == 1.0
    assert not np.any(clean.status == "sensor_fault")
    j = int(np.flatnonzero(clean.time > 6.0)[0])
    fault = SensorFault(start_s=clean.time[j] - 0.4, duration_s=3.0, kind="scale", magnitude=0.04)
    r = run_closed_loop(track, emu_b, noise_std=1.0, seed=7, faults=[fault], **b)
    np.testing.assert_array_equal(r.status[:j], clean.status[:j])
    assert r.status[j] == "sensor_fault" and "attenuated signal" in r.reason[j]
    assert r.metrics.latched_at_s == pytest.approx(clean.time[j])
    with pytest.warns(ControlWarning, match="noise_std = 0 m/s\\^2 in the data"):
        quiet = run_closed_loop(roadgen.track([(8, 300)], seed=7), emu_b, noise_std=0.0, seed=7,
                                **b)  # fmt: skip
    assert quiet.settings["bcr"].sensor.noise_sd_mps2 is None


def test_the_papers_window_method_runs_with_its_emulator():
    emu = control.shipped_emulator("A", "window")
    track = roadgen.track([(20, 300)], seed=2)
    r = run_closed_loop(track, emu, seed=2)  # settings follow the emulator's feature
    assert r.settings["bcr"].feature == PAPER_WINDOW and r.settings["bcr"].method == "filter"
    assert r.status[0] == "filling" and (r.status == "ok").any()
    r = run_closed_loop(track, emu, seed=2, bcr=control.bcr_settings_for(emu, method="window"))
    assert (r.status == "ok").any()


def test_the_papers_law_stops_the_robot_and_the_run_still_ends(emulator_a, likelihood_a):
    """Eq. 8 commands 0 m/s at GD 300: the robot stands, the estimate goes stale, the Simplex
    falls back to the safe speed, the robot moves on, and so to the end of the track."""
    track = roadgen.track([(30, 300)], seed=4)
    r = run_closed_loop(
        track, emulator_a, seed=4, likelihood=likelihood_a, simplex=Simplex(law="paper")
    )
    assert r.sample_position[-1] > track.length_m - 0.1
    assert np.any(r.command == 0.0) and np.any(r.sample_speed == 0.0)
    assert "stale" in set(r.status)


def test_set_up_is_checked_before_the_run(emulator_a):
    track = roadgen.track([(20, 300)], seed=1)
    with pytest.raises(ControlError, match="v_max = 5 m/s exceeds the vehicle's top speed 2"):
        run_closed_loop(track, emulator_a, simplex=Simplex(v_max=5.0))
    with pytest.raises(ControlError, match="seed must be None or an integer >= 0, got -1"):
        run_closed_loop(track, emulator_a, seed=-1)
    stiffer = vehicle.Jackal(tyre_stiffness_n_per_m=30_000.0)
    with pytest.raises(
        EmulatorMismatchError,
        match=r"another vehicle \(tyre_stiffness_n_per_m: model 30000.0 vs emulator 20000.0\)",
    ):
        run_closed_loop(track, emulator_a, model=stiffer)
    far = roadgen.track([(20, 300), (20, 800)], seed=1)
    with pytest.raises(EmulatorMismatchError, match=r"track GD \[800.0\] outside .* \[200, 600\]"):
        run_closed_loop(far, emulator_a)
    with pytest.raises(EmulatorMismatchError, match="block_samples: BCR 250 vs emulator 125"):
        run_closed_loop(track, emulator_a, bcr=BCRSettings(feature=FeatureSpec(block_samples=250)))
    with pytest.raises(EmulatorMismatchError, match="name: BCR 'log_var' vs emulator"):
        run_closed_loop(track, emulator_a, bcr=BCRSettings(feature=PAPER_WINDOW, method="window"))


def test_arguments_are_checked_before_the_drive(emulator_a, likelihood_a, tmp_path):
    track = roadgen.track([(20, 300)], seed=1)
    for kwargs, match in (
        (
            {"faults": SensorFault(1.0, 1.0)},
            r"faults must be a sequence of SensorFault: pass \[fault\]",
        ),
        ({"faults": [("nan", 1, 2)]}, "faults must hold SensorFault objects"),
        ({"max_time_s": float("nan")}, "max_time_s must be None or a finite number > 0"),
        ({"max_time_s": 0.0}, "max_time_s must be None or a finite number > 0"),
        ({"simplex": "fast"}, "simplex must be a control.Simplex"),
        ({"record": tmp_path}, "is a folder; name the .mcap file"),
    ):
        with pytest.raises(ControlError, match=match):
            run_closed_loop(track, emulator_a, likelihood=likelihood_a, **kwargs)
    with pytest.raises(vehicle.VehicleError, match="model='jackal' is not allowed"):
        run_closed_loop(track, emulator_a, model="jackal")
    with pytest.raises(ControlError, match=r"max_time_s = 0.001 s ended the run .* at least 10 s"):
        run_closed_loop(track, emulator_a, likelihood=likelihood_a, max_time_s=1e-3)


def test_a_likelihood_prepared_for_another_emulator_is_refused(
    emulator_a, likelihood_a, likelihood_b
):
    track = roadgen.track([(20, 300)], seed=1)
    with pytest.raises(EmulatorMismatchError, match=r"metadata differ in \[.*'noise_std'\]"):
        run_closed_loop(track, emulator_a, likelihood=likelihood_b)
    # the same file loaded twice is the same emulator (the likelihood: of the session's load)
    control.check_likelihood(control.shipped_emulator("A"), likelihood_a)


def test_a_noise_mismatch_warns():
    emu = control.shipped_emulator("A")
    with pytest.warns(ControlWarning, match="noise_std = 1 m/s\\^2 in the data"):
        control.check_emulator(emu, noise_std=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        control.check_emulator(control.shipped_emulator("B"), noise_std=1.0)


def test_shipped_emulators_record_what_the_loop_checks():
    for case, noise in (("A", 0.0), ("B", 1.0)):
        band = control.shipped_emulator(case)
        assert band.metadata["vehicle"] == vehicle.Jackal().describe()
        assert band.metadata["noise_std"] == noise
        assert FeatureSpec.from_dict(band.metadata["feature"]) == FeatureSpec()
        scatter = control.BlockScatter.from_dict(band.metadata["block_scatter"])
        assert scatter.cov.shape[1:] == (10, 10) and scatter.speed[0] == pytest.approx(0.5)
        window = control.shipped_emulator(case, "window")
        assert FeatureSpec.from_dict(window.metadata["feature"]) == PAPER_WINDOW
    with pytest.raises(ControlError, match="case must be one of"):
        control.shipped_emulator("C")
    with pytest.raises(ControlError, match="kind must be one of"):
        control.shipped_emulator("A", "psd")


def test_an_emulator_folder_gives_its_file_or_names_the_missing_one(tmp_path):
    shutil.copy(control.shipped_emulator_path("B"), tmp_path / "jackal_B.gpmsa")
    emu = control.shipped_emulator("B", "band", tmp_path)
    assert emu.metadata == control.shipped_emulator("B").metadata
    with pytest.raises(ControlError, match=r"jackal_B_window.gpmsa is missing; make it with "
                       r"`python examples/train_emulator.py --emulator-dir .* --cases B "
                       r"--features window`"):  # fmt: skip
        control.shipped_emulator("B", "window", tmp_path)
    with pytest.raises(ControlError, match="folder is an empty path"):  # not the current folder
        control.shipped_emulator("B", "band", "")
    with pytest.raises(ControlError, match=r"folder '.*jackal_B.gpmsa' is not a folder"):
        control.shipped_emulator("B", "band", tmp_path / "jackal_B.gpmsa")


def test_bad_fault_settings_raise():
    with pytest.raises(ControlError, match="kind must be one of"):
        SensorFault(1.0, 1.0, kind="melt")
    with pytest.raises(ControlError, match="duration_s must be > 0"):
        SensorFault(1.0, 0.0)
    with pytest.raises(ControlError, match="spacing >= 1"):
        SensorFault(1.0, 1.0, kind="spike", magnitude=0.5)
