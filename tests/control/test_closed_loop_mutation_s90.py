"""Mutation testing of control/closed_loop.py (session 90): exact expectations for `gd_key`,
`LoopMetrics` (``rmse``, ``as_dict``, ``real_time_factor``), the argument checks and refusals of
`run_closed_loop`, and the assembly of a `ClosedLoopResult` from hand-built traces: the vehicle
(`vehicle.Simulation`), the BCR and the wall clock are replaced by scripted doubles, so a run
takes no Exudyn drive and every trace, metric and setting has a hand-computed value."""

from __future__ import annotations

import copy
import json
import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

import roadgen
import vehicle
from control import (
    BCRSettings,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    SensorFault,
    Simplex,
)
from control import closed_loop as cl
from control.closed_loop import ClosedLoopResult, LoopMetrics, gd_key, simulated_sensor_settings
from control.estimate import Estimate
from control.metrics import GDError
from control.sensor_checks import SensorLimits

# --- gd_key -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("gd", "key"),
    [
        (300.0, "300"),
        (450.123456, "450.123456"),
        (1e-7, "1e-07"),
        (300.1000061, "300.1000061"),  # %g: 300.1 (six digits), which reads back as another GD
        (float(np.float32(300.1)), "300.1000061035156"),
        (0.1 + 0.2, "0.30000000000000004"),
        (np.float64(250.0), "250"),
    ],
)
def test_gd_key_is_g_where_it_reads_back_else_every_digit(gd, key):
    assert gd_key(gd) == key
    assert float(gd_key(gd)) == gd


# --- LoopMetrics --------------------------------------------------------------------------------


def _metrics(**overrides) -> LoopMetrics:
    """Three parts: GD 300 (4 estimates, SSE 400: RMSE 10), 500 (1, SSE 900: RMSE 30), 600
    (none: RMSE NaN)."""
    fields = dict(
        gd_errors=(GDError(300.0, 400.0, 4), GDError(500.0, 900.0, 1), GDError(600.0, 0.0, 0)),
        detection_delay_m=(2.5, np.nan),
        fast_on_rough_m=1.25,
        traversal_time_s=10.0,
        wall_time_s=4.0,
        latency_median_s=0.003,
        latency_max_s=0.004,
        ok_fraction=0.75,
    )
    fields.update(overrides)
    return LoopMetrics(**fields)


def test_loop_metrics_defaults_are_nan():
    m = _metrics()
    assert math.isnan(m.coverage) and math.isnan(m.latched_at_s)


def test_real_time_factor_is_simulated_over_wall_seconds_nan_without_wall_time():
    assert _metrics().real_time_factor == 2.5
    assert math.isnan(_metrics(wall_time_s=0.0).real_time_factor)
    assert math.isnan(_metrics(wall_time_s=-1.0).real_time_factor)
    assert _metrics(wall_time_s=1e-300, traversal_time_s=1e-300).real_time_factor == 1.0


def test_rmse_of_each_part():
    m = _metrics()
    assert m.rmse(300) == 10.0 and m.rmse(500.0) == 30.0 and m.rmse(np.int64(300)) == 10.0
    assert math.isnan(m.rmse(600))


def test_rmse_matches_a_gd_within_a_relative_1e_6_and_takes_the_nearest():
    m = _metrics(gd_errors=(GDError(300.0, 400.0, 4), GDError(300.0002, 900.0, 1)))
    assert m.rmse(300.0) == 10.0 and m.rmse(300.0002) == 30.0  # each its own part
    assert m.rmse(300.00015) == 30.0 and m.rmse(300.00005) == 10.0  # both within: the nearer
    assert m.rmse(300.0 * (1 - 0.9e-6)) == 10.0
    with pytest.raises(ControlError, match=r"^no part of the track has prescribed GD 299\.999"):
        m.rmse(300.0 * (1 - 1.1e-6))
    f32 = float(np.float32(300.1))
    m = _metrics(gd_errors=(GDError(f32, 16.0, 1),))
    assert m.rmse(300.1) == 4.0  # a GD that went through float32 finds its part
    with pytest.raises(ControlError, match=r"^no part of the track has prescribed GD 300\.2; its "):
        m.rmse(300.2)


def test_rmse_tolerance_includes_its_end():
    # a GD of 0: the tolerance is 0 and the part matches exactly (<=, not <)
    m = _metrics(gd_errors=(GDError(0.0, 9.0, 1), GDError(300.0, 400.0, 4)))
    assert m.rmse(0) == 3.0 and m.rmse(0.0) == 3.0


def test_rmse_refuses_a_gd_the_track_lacks_with_its_gds():
    m = _metrics(gd_errors=(GDError(300.0, 4.0, 1), GDError(300.1000061, 4.0, 1)))
    with pytest.raises(ControlError) as err:
        m.rmse(400)
    assert str(err.value) == (
        "no part of the track has prescribed GD 400; its GDs: 300, 300.1000061"
    )
    with pytest.raises(ControlError) as err:
        m.rmse(-300)
    assert str(err.value) == (
        "no part of the track has prescribed GD -300; its GDs: 300, 300.1000061"
    )


def test_rmse_of_a_track_without_parts_is_refused():
    with pytest.raises(ControlError) as err:
        _metrics(gd_errors=()).rmse(300)
    assert str(err.value) == "no part of the track has prescribed GD 300; its GDs: "


@pytest.mark.parametrize(
    ("gd", "message"),
    [
        ("300", "gd must be a real number, got '300' (str)"),
        (None, "gd must be a real number, got None (NoneType)"),
        (True, "gd must be a real number, got True (bool)"),
        (np.nan, "gd must be finite, got nan"),
        (np.inf, "gd must be finite, got inf"),
        (-np.inf, "gd must be finite, got -inf"),
    ],
)
def test_rmse_refuses_what_is_not_a_finite_number(gd, message):
    with pytest.raises(ControlError) as err:
        _metrics().rmse(gd)
    assert str(err.value) == message


def test_as_dict_is_the_exact_strict_json_summary():
    m = _metrics(
        gd_errors=(GDError(300.0, 400.0, 4), GDError(300.1000061, 9.0, 1), GDError(600.0, 0.0, 0)),
        coverage=0.5,
    )
    want = {
        "rmse": {"300": 10.0, "300.1000061": 3.0, "600": None},
        "n_estimates": {"300": 4, "300.1000061": 1, "600": 0},
        "detection_delay_m": [2.5, None],
        "fast_on_rough_m": 1.25,
        "traversal_time_s": 10.0,
        "wall_time_s": 4.0,
        "real_time_factor": 2.5,
        "latency_median_s": 0.003,
        "latency_max_s": 0.004,
        "ok_fraction": 0.75,
        "coverage": 0.5,
        "latched_at_s": None,
    }
    got = m.as_dict()
    assert got == want and list(got) == list(want)
    assert json.loads(json.dumps(got, allow_nan=False)) == want
    assert _metrics(latched_at_s=3.5).as_dict()["latched_at_s"] == 3.5


# --- ClosedLoopResult's repr --------------------------------------------------------------------


def test_a_result_prints_its_estimates_span_statuses_and_samples():
    r = _scripted_result()
    assert repr(r) == (
        "ClosedLoopResult(3 estimates over 0.5 s, 6.8 m: filling 1, ok 2; 7 sensor samples)"
    )


# --- the small checks ---------------------------------------------------------------------------


def test_run_seed():
    assert cl._run_seed(None) is None
    assert cl._run_seed(0) == 0 and type(cl._run_seed(np.int64(7))) is int
    assert cl._run_seed(np.int64(7)) == 7
    want = int(np.random.default_rng(5).integers(2**63))
    got = cl._run_seed(np.random.default_rng(5))
    assert got == want and type(got) is int
    for bad, shown in ((-1, "-1"), (True, "True"), (1.5, "1.5"), ("3", "'3'")):
        with pytest.raises(ControlError) as err:
            cl._run_seed(bad)
        assert str(err.value) == (
            f"seed must be None or an integer >= 0, got {shown} (or a numpy Generator)"
        )


def test_check_faults():
    a, b = SensorFault(1.0, 1.0), SensorFault(3.0, 0.5, "drop")
    assert cl._check_faults([a, b]) == (a, b) and cl._check_faults(()) == ()
    assert cl._check_faults(iter([b])) == (b,)
    for bad, message in (
        (a, "faults must be a sequence of SensorFault: pass [fault]"),
        (5, "faults must be a sequence of SensorFault, got 5"),
        ([a, "x", 3], "faults must hold SensorFault objects, got 'x'"),
    ):
        with pytest.raises(ControlError) as err:
            cl._check_faults(bad)
        assert str(err.value) == message


def test_record_path_under_a_file_or_a_folder_not_writable_is_refused(tmp_path, monkeypatch):
    cl._check_record_path(tmp_path / "run.mcap")  # a new file in a writable folder
    cl._check_record_path(tmp_path / "new" / "deeper" / "run.mcap")  # its folders made later
    plain = tmp_path / "a.txt"
    plain.write_text("data")
    with pytest.raises(ControlError) as err:
        cl._check_record_path(plain / "run.mcap")
    assert str(err.value) == f"record={str(plain / 'run.mcap')!r}: cannot write under {plain}"
    real = cl.os.access
    monkeypatch.setattr(cl.os, "access", lambda p, mode: False if p == tmp_path else real(p, mode))
    with pytest.raises(ControlError) as err:
        cl._check_record_path(tmp_path / "run.mcap")
    assert str(err.value) == f"record={str(tmp_path / 'run.mcap')!r}: cannot write under {tmp_path}"


@pytest.mark.parametrize(
    ("assumed", "noise_std", "want"),
    [(None, 0.5, None), (1.0, 1.0, 1.0), (1.0, 2.0, 1.0), (1.0, 0.5, 0.5), (1.0, 0.0, None)],
)
def test_the_sensor_checks_noise_sd_is_at_most_the_simulated(assumed, noise_std, want):
    sensor = SensorLimits(noise_sd_mps2=assumed)
    got = cl._within_simulated_noise(sensor, noise_std)
    assert got.noise_sd_mps2 == want and type(got.noise_sd_mps2) is type(want)
    assert got == SensorLimits(noise_sd_mps2=want)


def test_simulated_sensor_settings_shorten_the_silence_and_lower_the_noise():
    got = simulated_sensor_settings(BCRSettings(sensor=SensorLimits(noise_sd_mps2=1.0)), 0.25)
    assert got.max_silence_s == 0.5 / 120.0 and got.sensor.noise_sd_mps2 == 0.25
    assert got == BCRSettings(max_silence_s=0.5 / 120.0, sensor=SensorLimits(noise_sd_mps2=0.25))
    short = BCRSettings(max_silence_s=0.001)
    assert simulated_sensor_settings(short, 0.0) == short


@pytest.mark.parametrize(
    ("length", "why", "need"),
    [
        (0.05, "shorter than the vehicle's wheel radius", "0.098"),
        (0.098, "not longer than the vehicle's wheelbase", "0.262"),  # = the radius: not shorter
        (0.262, "not longer than the vehicle's wheelbase", "0.262"),
    ],
)
def test_a_track_the_vehicle_cannot_drive_is_refused(length, why, need):
    with pytest.raises(ControlError) as err:
        cl._check_track_fits(SimpleNamespace(length_m=length), vehicle.Jackal())
    assert str(err.value) == (
        f"track is {length:g} m long, {why} {need} m: the vehicle cannot drive it; lengthen the "
        "track (to more than the wheelbase, 0.262 m)"
    )


def test_a_track_just_longer_than_the_wheelbase_fits():
    assert cl._check_track_fits(SimpleNamespace(length_m=0.2620001), vehicle.Jackal()) is None


@pytest.mark.parametrize(
    ("limit", "message"),
    [
        (
            4.0,
            "max_time_s = 4 s ended the run at 3.0 of 10.0 m after 12 s: the track takes at "
            "least 5 s at v_max",
        ),  # fmt: skip
        (5.0, "the vehicle stood or crawled: 3.0 of 10.0 m after 12 s (max_time_s = 5)"),
        (6.5, "the vehicle stood or crawled: 3.0 of 10.0 m after 12 s (max_time_s = 6.5)"),
    ],
)
def test_timeout_messages(limit, message):
    sim = SimpleNamespace(position=3.0, time=12.0)
    assert cl._timeout_message(sim, SimpleNamespace(length_m=10.0), Simplex(), limit) == message


# --- a scripted loop: no drive ------------------------------------------------------------------

TRACK = roadgen.track([(5, 300), (5, 500)], seed=1, lead_in_m=0.0)  # parts [0, 5), [5, 10.002]


def _chunk(t, position, speed, accel) -> vehicle.simulation.Samples:
    arrays = [np.asarray(a, dtype=float) for a in (t, position, speed, accel)]
    t, position, speed, accel = arrays
    return vehicle.simulation.Samples(
        t=t, position=position, accel_front=accel, accel_front_true=accel, speed=speed,
        contact=np.ones(t.size, bool), accel_rear=accel, accel_rear_true=accel,
    )  # fmt: skip


CHUNKS = (
    _chunk([0.05, 0.1, 0.2], [0.25, 0.5, 1.0], [1.0, 1.0, 1.0], [0.05, 0.1, -0.1]),
    _chunk([0.3, 0.4], [1.5, 2.0], [1.0, 1.0], [0.2, -0.2]),
    _chunk([0.5, 0.6], [6.0, 7.0], [1.5, 1.5], [0.3, -0.3]),
)
ESTIMATES = (
    Estimate(0.2, 1.0, "filling", "filling the first block", latency_s=0.001),
    Estimate(
        0.4,
        2.0,
        "ok",
        gd_mean=310.0,
        gd_sd=5.0,
        interval=(300.0, 320.0),
        latency_s=0.004,
        prob_change=0.25,
    ),  # fmt: skip
    Estimate(
        0.6,
        5.5,
        "ok",
        gd_mean=480.0,
        gd_sd=5.0,
        interval=(470.0, 490.0),
        latency_s=0.002,
        prob_change=0.75,
        domain_edge="upper",
    ),  # fmt: skip
)


class _Scripted:
    """The doubles of one run: a vehicle that yields ``chunks`` (then, with ``times``, stands
    at those times), a BCR that answers ``estimates``, a wall clock that reads 100 then 100.25."""

    def __init__(self, chunks=CHUNKS, estimates=ESTIMATES, times=None):
        self.chunks, self.estimates, self.times = list(chunks), list(estimates), times
        self.sims, self.advances, self.updates, self.bcrs = [], [], [], []
        self.clock = iter([100.0, 100.25])

    def install(self, monkeypatch) -> _Scripted:
        script = self

        class Sim:
            def __init__(self, model, track, **kwargs):
                script.sims.append((model, track, kwargs))
                self.time, self.position, self.left = 0.0, 0.0, list(script.chunks)

            @property
            def finished(self):
                return not self.left

            def advance(self, dt, speed):
                script.advances.append((dt, speed))
                samples = self.left.pop(0)
                if len(samples):
                    self.time, self.position = float(samples.t[-1]), float(samples.position[-1])
                return samples

        class BCR:
            def __init__(self):
                self.last = Estimate(0.0, 0.0, "filling", "no samples yet")

            @classmethod
            def from_emulator(cls, emulator, bcr):
                script.bcrs.append((emulator, bcr))
                return cls()

            def update(self, t, position, accel, speed, now):
                script.updates.append((t, position, accel, speed, now))
                return script.estimates.pop(0)

        monkeypatch.setattr(vehicle, "Simulation", Sim)
        monkeypatch.setattr(cl, "BCR", BCR)
        monkeypatch.setattr(cl, "_time", SimpleNamespace(perf_counter=lambda: next(self.clock)))
        return self


EMULATOR = SimpleNamespace(metadata={})  # (check=False: never read but for its metadata)


def _run(monkeypatch, script=None, emulator=EMULATOR, **kwargs):
    script = (script or _Scripted()).install(monkeypatch)
    kwargs = {"check": False, "bcr": BCRSettings(), **kwargs}
    return script, cl.run_closed_loop(TRACK, emulator, **kwargs)


def _scripted_result() -> ClosedLoopResult:
    with pytest.MonkeyPatch.context() as mp:
        return _run(mp)[1]


def test_a_scripted_run_assembles_its_traces(monkeypatch):
    script, r = _run(monkeypatch, seed=7, noise_std=0.25, substeps=3)
    np.testing.assert_array_equal(r.time, [0.2, 0.4, 0.6])
    np.testing.assert_array_equal(r.position, [1.0, 2.0, 7.0])  # the vehicle's, not 5.5
    np.testing.assert_array_equal(r.gd_mean, [np.nan, 310.0, 480.0])
    np.testing.assert_array_equal(r.gd_lo, [np.nan, 300.0, 470.0])
    np.testing.assert_array_equal(r.gd_hi, [np.nan, 320.0, 490.0])
    np.testing.assert_array_equal(r.gd_true, [300.0, 300.0, 500.0])
    assert r.status.tolist() == ["filling", "ok", "ok"]
    assert r.reason.tolist() == ["filling the first block", "", ""] and r.reason.dtype == object
    assert r.domain_edge.tolist() == ["", "", "upper"] and r.domain_edge.dtype == object
    np.testing.assert_array_equal(r.prob_change, [np.nan, 0.25, 0.75])
    np.testing.assert_array_equal(r.command, [1.0, 1.4, 1.0])
    assert r.mode.tolist() == ["safety", "performance", "safety"]
    np.testing.assert_array_equal(r.latency_s, [0.001, 0.004, 0.002])
    np.testing.assert_array_equal(r.sample_time, [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    np.testing.assert_array_equal(r.sample_position, [0.25, 0.5, 1.0, 1.5, 2.0, 6.0, 7.0])
    np.testing.assert_array_equal(r.sample_speed, [1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 1.5])
    np.testing.assert_array_equal(r.sample_accel, [0.05, 0.1, -0.1, 0.2, -0.2, 0.3, -0.3])


def test_a_scripted_run_scores_itself(monkeypatch):
    _, r = _run(monkeypatch)
    m = r.metrics
    assert m.gd_errors == (GDError(300.0, 100.0, 1), GDError(500.0, 400.0, 1))
    assert m.rmse(300) == 10.0 and m.rmse(500) == 20.0
    assert m.detection_delay_m == (2.0,)  # 480 > 400 (the midpoint) 2 m past the change at 5
    assert m.fast_on_rough_m == 1.0  # 6 -> 7 m at 1.5 m/s on GD 500 > 350
    assert m.traversal_time_s == 0.6 and m.wall_time_s == 0.25 and m.real_time_factor == 2.4
    assert m.latency_median_s == 0.003 and m.latency_max_s == 0.004  # of the ok estimates
    assert m.ok_fraction == 2 / 3
    assert m.coverage == 0.5  # [300, 320] holds 300 (its end), [470, 490] misses 500
    assert math.isnan(m.latched_at_s)


def test_a_scripted_run_drives_with_its_settings_and_commands(monkeypatch):
    script, r = _run(monkeypatch, seed=7, noise_std=0.25, substeps=3)
    bcr = simulated_sensor_settings(BCRSettings(), 0.25)
    rng = np.random.default_rng(7)
    noise_seed = int(rng.integers(2**63))
    [(model, track, kwargs)] = script.sims
    assert model == vehicle.Jackal() and track is TRACK
    assert kwargs == {"rate_hz": 120.0, "noise_std": 0.25, "seed": noise_seed, "substeps": 3}
    assert type(kwargs["seed"]) is int
    assert script.bcrs == [(EMULATOR, bcr)]
    # the first advance at the command for the BCR's estimate before any sample, then each
    # at the command for the last update's estimate; an update's samples last 42 / 120 s
    assert script.advances == [(0.35, 1.0), (0.35, 1.0), (0.35, 1.4)]
    assert [u[4] for u in script.updates] == [0.2, 0.4, 0.6]
    for update, chunk in zip(script.updates, CHUNKS, strict=True):
        for got, want in zip(update[:4], (chunk.t, chunk.position, chunk.accel_front,
                                          chunk.speed), strict=True):  # fmt: skip
            np.testing.assert_array_equal(got, want)
    assert r.settings == {
        "model": vehicle.Jackal(),
        "noise_std": 0.25,
        "seed": 7,
        "bcr": bcr,
        "simplex": Simplex(),
        "faults": (),
        "substeps": 3,
    }
    assert r.settings["bcr"].max_silence_s == 0.5 / 120.0


def test_a_scripted_run_records_its_faults_and_a_drawn_seed(monkeypatch):
    fault = SensorFault(50.0, 1.0)  # (after the run: changes no sample)
    _, r = _run(monkeypatch, seed=np.random.default_rng(3), faults=[fault])
    assert r.settings["seed"] == int(np.random.default_rng(3).integers(2**63))
    assert r.settings["faults"] == (fault,) and type(r.settings["faults"]) is tuple


def test_a_fault_that_latches_is_timed(monkeypatch):
    fault = Estimate(0.4, 2.0, "sensor_fault", "a NaN sample", latency_s=0.003)
    script = _Scripted(estimates=(ESTIMATES[0], fault, ESTIMATES[2]))
    _, r = _run(monkeypatch, script)
    assert r.metrics.latched_at_s == 0.4
    assert r.mode.tolist() == ["safety"] * 3 and r.command.tolist() == [1.0] * 3
    assert r.metrics.latency_median_s == 0.002 == r.metrics.latency_max_s  # the ok one alone
    assert r.metrics.ok_fraction == 1 / 3


def test_a_scripted_run_without_samples_is_empty(monkeypatch):
    script = _Scripted(chunks=(_chunk([], [], [], []),), estimates=())
    _, r = _run(monkeypatch, script)
    for name in ("time", "position", "gd_mean", "command", "sample_time", "sample_accel"):
        assert getattr(r, name).size == 0, name
    m = r.metrics
    assert m.traversal_time_s == 0.0 and m.ok_fraction == 0.0
    assert math.isnan(m.latency_median_s) and math.isnan(m.latency_max_s)
    assert m.gd_errors == (GDError(300.0, 0.0, 0), GDError(500.0, 0.0, 0))
    assert script.advances == [(0.35, 1.0)] and script.updates == []
    assert repr(r) == "ClosedLoopResult(no estimate; 0 sensor samples)"
    assert (r.settings["noise_std"], r.settings["seed"], r.settings["substeps"]) == (0.0, None, 5)


def test_a_run_checks_its_emulator_by_default(monkeypatch):
    script = _Scripted().install(monkeypatch)
    with pytest.raises(
        ControlError, match=r"^emulator must be a gpmsa.Emulator .* got 'A' \(str\)$"
    ):
        cl.run_closed_loop(TRACK, "A", bcr=BCRSettings())
    assert script.sims == []


def test_a_run_is_stopped_only_past_its_time_limit(monkeypatch):
    # the limit reached exactly goes on
    _, r = _run(monkeypatch, max_time_s=0.4)
    assert r.time.tolist() == [0.2, 0.4, 0.6]
    with pytest.raises(ControlError) as err:
        _run(monkeypatch, max_time_s=0.3)
    assert str(err.value) == (
        "max_time_s = 0.3 s ended the run at 2.0 of 10.0 m after 0.4 s: the track takes at "
        "least 5 s at v_max"
    )


@pytest.mark.parametrize(("v_safe", "shown"), [(1.0, "200.04"), (0.5, "400.08")])
def test_the_default_time_limit_is_20_times_the_track_at_the_safe_speed(monkeypatch, v_safe, shown):
    limit = 20.0 * TRACK.length_m / v_safe
    stand = [_chunk([limit], [7.0], [0.0], [0.0]), _chunk([limit + 1], [7.0], [0.0], [0.0])]
    filling = Estimate(0.0, 7.0, "filling")
    script = _Scripted(chunks=(*CHUNKS, *stand, *stand), estimates=(*ESTIMATES, *[filling] * 4))
    with pytest.raises(ControlError) as err:
        _run(monkeypatch, script, simplex=Simplex(v_safe=v_safe))
    assert str(err.value) == (
        f"the vehicle stood or crawled: 7.0 of 10.0 m after {limit + 1:.3g} s (max_time_s = "
        f"{shown})"
    )
    assert len(script.advances) == 5  # the update at the limit exactly went on


def test_the_progress_bar_follows_the_position(monkeypatch):
    bars = []

    class Bar:
        def __init__(self, *args, **kwargs):
            self.args, self.kwargs, self.n, self.steps = args, kwargs, 0, []
            bars.append(self)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def update(self, k):
            self.steps.append(k)
            self.n += k

    monkeypatch.setattr(cl, "progress_bar", Bar)
    stand = _chunk([0.7], [7.0], [0.0], [0.0])  # no further metre: a step of 0
    script = _Scripted(chunks=(*CHUNKS, stand), estimates=(*ESTIMATES, ESTIMATES[2]))
    _run(monkeypatch, script, progress=True)
    [bar] = bars
    assert bar.args == (True, 10, None, "m") and bar.kwargs == {"mininterval": 0.1, "leave": False}
    assert bar.steps == [1, 1, 5, 0] and bar.n == 7
    _run(monkeypatch)  # none by default
    assert bars[1].args == (False, 10, None, "m") and bars[1].steps == [1, 1, 5]


# --- refusals before the drive ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"check": "yes"}, "check must be True or False, got 'yes'"),
        ({"progress": 1}, "progress must be True or False, got 1"),
        ({"bcr": "x"}, "bcr must be a control.BCRSettings, got 'x' (str)"),
        ({"max_time_s": -1}, "max_time_s must be None or a finite number > 0, s, got -1"),
        ({"max_time_s": 0}, "max_time_s must be None or a finite number > 0, s, got 0"),
        ({"max_time_s": "5"}, "max_time_s must be None or a finite number > 0, s, got '5'"),
        ({"max_time_s": True}, "max_time_s must be None or a finite number > 0, s, got True"),
        (
            {"max_time_s": float("inf")},
            "max_time_s must be None or a finite number > 0, s, got inf",
        ),
        ({"seed": -1}, "seed must be None or an integer >= 0, got -1 (or a numpy Generator)"),
        (
            {"simplex": Simplex(v_max=2.0 + 1e-11)},
            "Simplex v_max = 2.00000000001 m/s exceeds the vehicle's top speed 2 m/s",
        ),
    ],
)
def test_arguments_are_refused_before_the_drive(monkeypatch, kwargs, message):
    script = _Scripted()
    with pytest.raises(ControlError) as err:
        _run(monkeypatch, script, **kwargs)
    assert str(err.value) == message
    assert script.sims == [] and script.bcrs == []


def test_a_simplex_within_a_relative_1e_12_of_the_top_speed_drives(monkeypatch):
    fast = Simplex(v_max=2.0 * (1 + 1e-12))
    _, r = _run(monkeypatch, simplex=fast, max_time_s=1.0)
    assert r.settings["simplex"] is fast


def test_a_result_is_frozen_and_equal_only_to_itself(monkeypatch):
    import dataclasses

    _, r = _run(monkeypatch)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.metrics = None
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.metrics.coverage = 1.0
    assert (r == copy.copy(r)) is False and (r == r) is True  # (no field-wise == of arrays)


# --- the emulator's checks (the shipped emulator of case A; scripted drive) ---------------------


def test_check_false_skips_the_check_of_a_recorded_vehicle(monkeypatch, emulator_a):
    heavy = vehicle.Jackal(mass_kg=20.0)
    script, r = _run(monkeypatch, emulator=emulator_a, model=heavy)
    assert r.settings["model"] is heavy and len(script.sims) == 1
    with pytest.raises(EmulatorMismatchError) as err:
        _run(monkeypatch, emulator=emulator_a, model=heavy, check=True)
    assert str(err.value) == (
        "emulator was made for another vehicle (mass_kg: model 20.0 vs emulator 18.431)"
    )


def test_a_checked_run_checks_its_noise_against_the_emulator(monkeypatch, emulator_a):
    with pytest.warns(ControlWarning) as record:
        script, r = _run(
            monkeypatch, emulator=emulator_a, model=vehicle.Jackal(), bcr=None, noise_std=1.0,
            check=True,
        )  # fmt: skip
    assert [str(w.message) for w in record] == [
        "noise_std = 1 m/s^2 in the data but the emulator was trained with noise_std = 0: the GD "
        "estimates will be biased"
    ]
    assert len(script.sims) == 1 and r.settings["noise_std"] == 1.0


def test_a_default_model_without_a_recorded_vehicle_is_warned_of(monkeypatch, emulator_a):
    bare = copy.copy(emulator_a)
    bare.metadata = {k: v for k, v in emulator_a.metadata.items() if k != "vehicle"}
    with pytest.warns(ControlWarning) as record:
        script, r = _run(monkeypatch, emulator=bare, bcr=None, check=True)
    assert [str(w.message) for w in record] == [
        "model= was not given, so the default vehicle.Jackal() drives, and the emulator's "
        "metadata records no 'vehicle' to check it against: pass model=, the vehicle the "
        "emulator was trained for"
    ]
    assert record[0].filename == __file__  # (the user's line)
    assert r.settings["model"] == vehicle.Jackal() and len(script.sims) == 1


def test_a_scripted_run_is_recorded_where_asked_after_the_drive(monkeypatch, tmp_path):
    import control.robot.record

    calls = []
    monkeypatch.setattr(control.robot.record, "check_can_record", lambda: calls.append("check"))
    monkeypatch.setattr(control.robot.record, "record_run", lambda r, p: calls.append((r, p)))
    path = tmp_path / "run.mcap"
    _, r = _run(monkeypatch, record=path)
    assert calls == ["check", (r, path)]
    _, r = _run(monkeypatch)
    assert len(calls) == 2  # no record: nothing written
    script = _Scripted()
    with pytest.raises(ControlError) as err:  # a folder: refused before the drive
        _run(monkeypatch, script, record=tmp_path)
    assert str(err.value) == f"record={str(tmp_path)!r} is a folder; name the .mcap file to write"
    assert script.sims == [] and len(calls) == 2


def test_an_unchecked_run_of_a_default_model_does_not_warn(monkeypatch):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, r = _run(monkeypatch)  # (check=False, and the emulator records no vehicle)
    assert r.settings["model"] == vehicle.Jackal()


def test_a_given_model_without_a_recorded_vehicle_is_warned_of(monkeypatch, emulator_a):
    bare = copy.copy(emulator_a)
    bare.metadata = {k: v for k, v in emulator_a.metadata.items() if k != "vehicle"}
    with pytest.warns(ControlWarning) as record:
        _run(monkeypatch, emulator=bare, bcr=None, check=True, model=vehicle.Jackal())
    assert [str(w.message) for w in record] == [
        "emulator metadata has no 'vehicle'; cannot check it was made for Jackal"
    ]
