"""A robot runs the BCR all day: its state stays bounded and it forgets as fast after hours.

Guards of a long-duration soak (3 h of 120 Hz samples per method, a Calibrator updated 100,000
times): memory, latency, the run-length posterior and the detection delay held there; these
tests check the same properties cheaply, by the size and values of the state after many updates.
"""

import numpy as np
import pytest

import roadgen
import vehicle
from control import ChangePointFilter, ChangePointSettings

GD = np.geomspace(200.0, 600.0, 121)


def _block_loglik(gd_true: float, sd: float = 0.5) -> np.ndarray:
    """A block's log-likelihood on GD: normal in log GD about the true value."""
    return -0.5 * ((np.log(GD) - np.log(gd_true)) / sd) ** 2


def _blocks_to_detect(f: ChangePointFilter, ds: float = 1.5) -> int:
    """Blocks of GD 500 until the posterior mean passes 400 (the middle of the step)."""
    for k in range(1, 200):
        f.update(_block_loglik(500.0), ds)
        if f.gd_mass @ GD > 400.0:
            return k
    return -1


@pytest.mark.parametrize("sd", [0.15, 0.5])  # a sharp and a vague block law
def test_filter_after_hours_of_steady_ground_stays_bounded_and_detects_as_fast(sd):
    """After 3,000 steady blocks (4.5 km, the merged run far beyond ``max_runs``) the state
    keeps ``max_runs`` rows of finite masses, and a step 300 -> 500 is detected in as many
    blocks as after 150 blocks of the same ground."""
    settings = ChangePointSettings()
    early, late = ChangePointFilter(GD, settings), ChangePointFilter(GD, settings)
    for n, f in ((150, early), (3000, late)):
        for _ in range(n):
            f.update(_block_loglik(300.0, sd), 1.5)
    mass, dist, _ = late.state()
    assert mass.shape == (settings.max_runs, GD.size)
    assert np.all(np.isfinite(mass)) and np.all(mass >= 0) and np.isclose(mass.sum(), 1.0)
    assert np.all(np.isfinite(dist)) and np.all(np.diff(dist) > 0)
    assert 0.0 <= late.prob_change_within(5.0) <= 1.0
    assert _blocks_to_detect(late) == _blocks_to_detect(early) > 0


@pytest.fixture(scope="module")
def drive():
    """40 s of a simulated Jackal at 1.5 m/s over GD 300 (t, accel), noise-free."""
    track = roadgen.track([(70.0, 300.0)], seed=3)
    sim = vehicle.Simulation(vehicle.Jackal(), track, rate_hz=120.0, seed=1)
    sim.advance(2.0, 1.5)  # (getting under way)
    s = sim.advance(40.0, 1.5)
    return np.asarray(s.accel_front, dtype=float)


def _stream(accel: np.ndarray, repeats: int, t0: float, p0: float):
    """``repeats`` copies of ``accel`` at 120 Hz and 1.5 m/s, time stamps and positions going
    on from ``t0``, ``p0``; a 10 s stop and a stretch of NaN samples in the middle."""
    a = np.tile(accel, repeats)
    v = np.full(a.size, 1.5)
    mid = a.size // 2
    v[mid : mid + 1200] = 0.0  # a stop (the accelerometer reads its rest noise)
    a[mid : mid + 1200] = np.random.default_rng(0).normal(0.0, 0.02, 1200)
    a[mid + 3000 : mid + 3060] = np.nan  # a sensor fault
    t = t0 + np.arange(a.size) / 120.0
    p = p0 + np.concatenate([[0.0], np.cumsum((v[1:] + v[:-1]) / 2.0 / 120.0)])
    return t, p, a, v


def test_bcr_state_stays_bounded_over_a_long_stream_at_large_stamps(new_bcr, drive):
    """Fed minutes of samples with a stop and a fault, a BCR keeps its buffers, run lengths and
    quiet-check memory bounded, its masses finite, and ends "ok"; at time stamps of 1e5 s
    and positions of 50 km it gives the same statuses and GDs (to rounding)."""
    runs = []
    for t0, p0 in ((0.0, 0.0), (1e5, 5e4)):
        bcr = new_bcr("A")
        t, p, a, v = _stream(drive, 6, t0, p0)
        every = bcr.settings.samples_per_update
        out = [
            bcr.update(t[i : i + every], p[i : i + every], a[i : i + every], v[i : i + every])
            for i in range(0, t.size - every + 1, every)
        ]
        for phase in bcr._phases:
            mass, dist, _ = phase.filter.state()
            assert mass.shape[0] == dist.size <= bcr.settings.changepoint.max_runs
            assert np.all(np.isfinite(mass)) and np.all(np.isfinite(dist))
            assert len(phase.levels) <= bcr.settings.quiet_blocks
        assert bcr._acc.size == bcr._t.size == bcr.buffer
        assert out[-1].status == "ok"
        assert {"ok", "stale", "sensor_fault"} <= {e.status for e in out}
        runs.append(out)
    assert [e.status for e in runs[0]] == [e.status for e in runs[1]]
    gd0, gd1 = (np.array([e.gd_mean for e in r]) for r in runs)
    np.testing.assert_allclose(gd1, gd0, rtol=1e-9)
