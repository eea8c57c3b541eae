"""The Simplex's release dwell (`Simplex.release_m`): once the run has driven in performance mode,
safety mode returns to it only after the law has read performance mode over ``release_m`` metres
in a row. Off by default (0: the commands of a run as without it)."""

import dataclasses

import numpy as np
import pytest

import control
import roadgen
from control import ControlError, Estimate, Simplex, SimplexRun
from tests._examples import load_benchmark, load_example


def ok(position: float, gd: float) -> Estimate:
    return Estimate(
        time=position, position=position, status="ok", gd_mean=gd, gd_sd=10.0,
        interval=(gd - 20.0, gd + 20.0),
    )  # fmt: skip


def filling(position: float) -> Estimate:
    return Estimate(time=position, position=position, status="filling")


def _same(a, b) -> bool:
    """Whether two Commands hold the same fields, NaN (a filling estimate's gd_used) equal to
    NaN: from Python 3.13 a dataclass's ``==`` compares field by field, where NaN != NaN."""
    pairs = zip(dataclasses.astuple(a), dataclasses.astuple(b), strict=True)
    return type(a) is type(b) and all(x == y or (x != x and y != y) for x, y in pairs)


def drive(run: SimplexRun, readings) -> list:
    """(position, mode, speed) of each command of ``run`` for ``readings`` ((position, GD or
    None for a buffer-filling estimate), ...)."""
    out = []
    for pos, gd in readings:
        c = run.command(filling(pos) if gd is None else ok(pos, gd))
        out.append((pos, c.mode, c.speed))
    return out


# 0-2 m: buffer filling; 3-9 m: GD 300 (performance); 10-12 m: GD 400 (safety); then GD 300
ROAD = [(float(p), None if p < 3 else 400.0 if 10 <= p <= 12 else 300.0) for p in range(30)]


def test_the_dwell_holds_safety_mode_for_release_m_metres_after_the_law_reads_performance():
    steps = drive(Simplex(release_m=5.0).start(), ROAD)
    modes = {pos: mode for pos, mode, _ in steps}
    assert [modes[p] for p in range(3)] == ["safety"] * 3
    # the start's safety mode has no dwell: performance at the first ok estimate
    assert all(modes[p] == "performance" for p in range(3, 10))
    assert all(modes[p] == "safety" for p in range(10, 13))
    # the law reads performance from 13 m on: safety until 13 + 5 = 18 m
    assert all(modes[p] == "safety" for p in range(13, 18))
    assert all(modes[p] == "performance" for p in range(18, 30))
    held = Simplex(release_m=5.0).start()
    drive(held, ROAD[:16])
    c = held.command(ok(16.0, 300.0))
    assert (c.mode, c.speed, c.gd_used) == ("safety", 1.0, 300.0)
    assert (
        c.reason == "release dwell: the law has read performance mode over 3.00 of release_m = 5 m"
    )


def test_a_safety_reading_during_the_dwell_starts_the_count_again():
    road = [(p, 400.0 if p == 15.0 else gd) for p, gd in ROAD]
    modes = {pos: mode for pos, mode, _ in drive(Simplex(release_m=5.0).start(), road)}
    assert all(modes[p] == "safety" for p in range(10, 21))  # 16 + 5
    assert all(modes[p] == "performance" for p in range(21, 30))


def test_an_update_without_a_finite_position_counts_no_metres():
    run = Simplex(release_m=5.0).start()
    drive(run, ROAD[:13])  # in safety mode at 12 m
    assert run.command(ok(13.0, 300.0)).mode == "safety"
    nan = Estimate(time=14.0, position=np.nan, status="ok", gd_mean=300.0, gd_sd=10.0,
                   interval=(280.0, 320.0))  # fmt: skip
    assert run.command(nan).mode == "safety"
    assert run.clear_since_m is None
    assert [run.command(ok(p, 300.0)).mode for p in (15.0, 19.0, 20.0)] == [
        "safety", "safety", "performance",
    ]  # fmt: skip


def test_the_dwell_follows_a_reset_latch():
    run = Simplex(release_m=5.0).start()
    drive(run, ROAD[:8])
    fault = Estimate(time=8.0, position=8.0, status="sensor_fault", reason="x")
    assert run.command(fault).mode == "safety" and run.latched
    assert run.command(ok(9.0, 300.0)).mode == "safety"
    run.reset()
    assert [run.command(ok(p, 300.0)).mode for p in (10.0, 14.0, 15.0)] == [
        "safety", "safety", "performance",
    ]  # fmt: skip


def test_no_dwell_by_default_gives_the_memoryless_law_bit_for_bit():
    assert Simplex().release_m == 0.0
    rng = np.random.default_rng(3)
    gds = rng.uniform(200.0, 450.0, 200)
    readings = [(float(i), None if i % 17 == 0 else float(g)) for i, g in enumerate(gds)]
    simplex = Simplex()
    run = simplex.start()
    for pos, gd in readings:
        est = filling(pos) if gd is None else ok(pos, gd)
        assert _same(run.command(est), simplex.command(est))
    assert drive(Simplex(release_m=0.0).start(), readings) == drive(simplex.start(), readings)


@pytest.mark.parametrize(
    "value, says",
    [
        (-1.0, "release_m must be a finite distance >= 0, m, got -1.0"),
        (float("nan"), "release_m must be a finite distance >= 0, m, got nan"),
        (float("inf"), "release_m must be a finite distance >= 0, m, got inf"),
        ("5", "Simplex.release_m must be a real number, got '5' (str)"),
        (True, "Simplex.release_m must be a real number, got True (bool)"),
        (None, "Simplex.release_m must be a real number, got None"),
    ],
)
def test_a_bad_release_m_is_refused_naming_it(value, says):
    with pytest.raises(ControlError, match="release_m") as info:
        Simplex(release_m=value)
    assert says in str(info.value)
    assert Simplex(release_m=np.float32(2.5)).release_m == 2.5
    assert type(Simplex(release_m=np.float32(2.5)).release_m) is float


def test_the_example_refuses_a_bad_release_m_as_a_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        load_example("closed_loop").main(["--out", str(tmp_path), "--release-m", "-2"])
    assert exit_info.value.code == 2
    assert "--release-m: release_m must be a finite distance >= 0" in capsys.readouterr().err


def test_in_closed_loop_the_dwell_keeps_a_low_gain_slow_until_it_is_flagged(
    emulator_b, likelihood_b
):
    """A gain of 0.7 from 5 s on 6 m of GD 300 then 14 m of GD 500 (seed 4, in safety mode
    from before the GD-500 part): without the dwell the fault reads as smoother ground and the
    robot left safety mode on GD 500 (4.3 m faster than v_safe there, its fault-free twin 0);
    with 10 m of dwell the quiet-signal check flags the fault first."""
    track = roadgen.track([(6.0, 300.0), (14.0, 500.0)], seed=4)
    fast, held = {}, {}
    for release in (0.0, 10.0):
        run = control.run_closed_loop(
            track, emulator_b, noise_std=1.0, seed=4, likelihood=likelihood_b,
            simplex=Simplex(release_m=release),
            faults=[control.SensorFault(5.0, 1e6, "scale", 0.7)],
        )  # fmt: skip
        fast[release] = run.metrics.fast_on_rough_m
        held[release] = np.sum((run.mode == "safety") & (run.status == "ok") & (run.gd_mean < 350))
    assert fast[0.0] > 4.0 and fast[10.0] == 0.0
    assert held[0.0] == 0 and held[10.0] > 0  # the law read performance mode; the dwell held


def test_the_benchmark_quick_mode_prints_its_table(monkeypatch, capsys, likelihood_b):
    bench = load_benchmark("release_dwell")
    monkeypatch.setattr(bench.control, "ObservationModel", lambda emulator: likelihood_b)
    bench.main(["--quick"])
    lines = capsys.readouterr().out.splitlines()
    rows = [line.split() for line in lines if line.startswith("B ")]
    assert [row[:3] for row in rows] == [["B", "0.7", "10"]]
    assert rows[0][4:6] == ["of", "1"]
    assert lines[-1].endswith(" cores")
