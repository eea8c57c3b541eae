"""The BCR as a control loop feeds it: any chunking, a bad time stamp or clock, odd estimates."""

import copy
import pickle

import numpy as np
import pytest

import control
import roadgen
from control import ControlError, Estimate


@pytest.fixture(scope="module")
def stream(emulator_a, likelihood_a):
    """A clean 60 m drive's samples (t, position, accel, speed)."""
    result = control.run_closed_loop(
        roadgen.track([(60, 300)], seed=1), emulator_a, seed=1, likelihood=likelihood_a
    )
    return (result.sample_time, result.sample_position, result.sample_accel,
            result.sample_speed)  # fmt: skip


def _feed(bcr, samples, chunk, **kw):
    t, p, a, s = samples
    return [bcr.update(t[i : i + chunk], p[i : i + chunk], a[i : i + chunk], s[i : i + chunk],
                       **kw) for i in range(0, t.size, chunk)]  # fmt: skip


def _new(emulator_a, likelihood_a):
    return control.BCR(likelihood_a, control.bcr_settings_for(emulator_a))


def test_one_bad_time_stamp_costs_a_block_in_any_chunking(stream, emulator_a, likelihood_a):
    t, p, a, s = stream
    late = t.copy()
    late[1000] += 1000.0  # one stamp 1,000 s in the future
    finals = {}
    for chunk in (1, 7, 42, 125):
        out = _feed(_new(emulator_a, likelihood_a), (late, p, a, s), chunk)
        faults = {e.time for e in out if e.status == "sensor_fault"}
        assert out[-1].ok and len(faults) <= 2, (chunk, len(faults))  # not deaf after it
        finals[chunk] = out[-1].gd_mean
    assert len(set(finals.values())) == 1, finals  # the same estimate, however chunked


def test_the_fault_named_does_not_depend_on_the_chunking(stream, emulator_a, likelihood_a):
    t, p, a, s = stream
    broken = a.copy()
    broken[1000] = np.nan
    for chunk in (1, 42):
        out = _feed(_new(emulator_a, likelihood_a), (t, p, broken, s), chunk)
        reasons = {e.reason for e in out if e.status == "sensor_fault"}
        assert reasons and all("non-finite accel" in r for r in reasons), (chunk, reasons)
        assert not any("gap" in r for r in reasons), (chunk, reasons)


def test_a_refused_call_and_a_wild_clock_leave_no_lasting_trace(stream, emulator_a, likelihood_a):
    t, p, a, s = stream
    bcr = _new(emulator_a, likelihood_a)
    _feed(bcr, (t[:2000], p[:2000], a[:2000], s[:2000]), 42, now=None)
    t_last = float(t[1999])
    with pytest.raises(ControlError, match="accel must have t's length 42"):
        bcr.update(t[2000:2042], p[2000:2042], a[2000:2041], s[2000:2042], now=t_last + 100.0)
    est = bcr.update(t[2000:2042], p[2000:2042], a[2000:2042], s[2000:2042], now=t[2041])
    assert est.status != "sensor_fault", est.reason  # the refused call's clock was not kept
    bcr.update([], [], [], [], now=t_last + 1e4)  # one wild clock: silence, for that call
    assert bcr.update([], [], [], [], now=t_last + 1e4).status == "sensor_fault"
    again = bcr.update(t[2042:2084], p[2042:2084], a[2042:2084], s[2042:2084], now=t[2083])
    assert "no samples for" not in again.reason  # the next sane clock is believed


def test_a_speed_that_disagrees_with_the_odometry_is_a_fault(stream, emulator_a, likelihood_a):
    t, p, a, s = stream
    flipped = s.copy()
    flipped[1000:1600] *= -1.0  # positions keep advancing
    out = _feed(_new(emulator_a, likelihood_a), (t, p, a, flipped), 42)
    during = [e for e in out if 1000 / 120 < e.time - t[0] < 1600 / 120]
    assert any(e.status == "sensor_fault" and "odometry" in e.reason for e in during)
    assert not any(e.ok and "no new information" in e.reason for e in during[3:])


def test_estimates_and_a_running_bcr_pickle_and_deepcopy(stream, emulator_a, likelihood_a):
    bcr, half = _new(emulator_a, likelihood_a), 42 * 40
    first, rest = ([x[:half] for x in stream]), ([x[half:] for x in stream])
    out = _feed(bcr, first, 42)
    est = next(e for e in reversed(out) if e.ok)
    back = pickle.loads(pickle.dumps(est))
    assert back.gd_mean == est.gd_mean and back.posterior.mean("GD") == est.posterior.mean("GD")
    np.testing.assert_array_equal(back.posterior.samples["GD"], est.posterior.samples["GD"])
    twin, clone = pickle.loads(pickle.dumps(bcr)), copy.deepcopy(bcr)
    ends = [_feed(b, rest, 42)[-1] for b in (bcr, twin, clone)]
    assert ends[0].ok and ends[0].gd_mean == ends[1].gd_mean == ends[2].gd_mean


@pytest.mark.parametrize("value", ["300", None, True, np.array([300.0]), 300 + 0j])
def test_an_estimate_holds_real_numbers_only(value):
    with pytest.raises(ControlError, match="gd_mean must be a real number"):
        Estimate(0.0, 0.0, "ok", gd_mean=value)


def test_a_gd_below_zero_is_safety_and_huge_ones_read_short():
    command = control.Simplex().command(Estimate(0.0, 0.0, "ok", gd_mean=-100.0))
    assert command.mode == "safety" and "the estimate's GD is -100" in command.reason
    command = control.Simplex().command(Estimate(0.0, 0.0, "ok", gd_mean=1e300))
    assert command.mode == "safety" and "GD 1e+300 > GD_max" in command.reason


def test_masked_samples_and_accelerations_beyond_any_sensor_are_refused(
    stream, emulator_a, likelihood_a
):
    t, p, a, s = stream
    with pytest.raises(ControlError, match=r"accel is a masked array: give NaN"):
        _new(emulator_a, likelihood_a).update(t[:42], p[:42], np.ma.masked_array(a[:42]), s[:42])
    with np.errstate(all="raise"):  # no overflow on the way: the range check comes first
        out = _feed(_new(emulator_a, likelihood_a), (t, p, a * 1e154, s), 42)
    reasons = {e.reason for e in out if e.status == "sensor_fault"}
    assert reasons and all("out of range" in r for r in reasons), reasons
