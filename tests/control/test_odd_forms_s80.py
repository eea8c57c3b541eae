"""Legitimate values in unusual forms on the online side: numpy scalars in the settings (a
float32 field made the Simplex's law and the window filter's hazard run in float32; a numpy
int ``quiet_blocks`` passed the settings and broke the BCR with a TypeError), time stamps as
datetime64 (refused, now with the remedy), and the forms that already gave the same estimates
bit for bit: lists, tuples, pandas Series, big-endian, read-only, strided and narrower float
arrays of the same values, any chunking, a copy or a pickle mid-stream, two threads on one
model."""

import copy
import pickle
import re
import threading
from dataclasses import fields, replace

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

from control import (
    BCR,
    PAPER_WINDOW,
    BCRSettings,
    ControlError,
    Estimate,
    Simplex,
)
from control.changepoint import ChangePointSettings
from control.sensor_checks import SensorLimits
from control.tracker import TrackerSettings


def _key(e: Estimate) -> str:
    """Everything an estimate says, NaN equal to NaN."""
    return repr((e.status, e.reason, e.time, e.position, e.gd_mean, e.gd_sd, e.interval,
                 e.speed, e.data_time, e.prob_change, e.plausibility_p, e.domain_edge,
                 None if e.feature is None else np.ravel(e.feature).tolist()))  # fmt: skip


def _feed(bcr, samples, chunk=42):
    """The estimates of ``samples`` (four sequences) fed ``chunk`` samples a call."""
    cut = [getattr(x, "iloc", x) for x in samples]  # (a pandas Series: by position)
    return [
        _key(bcr.update(*(x[i : i + chunk] for x in cut))) for i in range(0, len(samples[0]), chunk)
    ]


def _per_update(bcr, samples, chunks):
    """The estimate of every update (``bcr.last`` where a call ends on an update's end)."""
    out, i, k, n = {}, 0, 0, samples[0].size
    every = bcr.settings.samples_per_update
    while i < n:
        c = chunks[k % len(chunks)]
        k += 1
        bcr.update(*(x[i : i + c] for x in samples))
        i += c
        if (i % every == 0 or i >= n) and i >= every:
            out[min(i, n) // every] = _key(bcr.last)
    return out


@pytest.fixture(scope="module")
def samples():
    """40 s at 1.2 m/s over GD 300 then 500, as a float32 sensor gives them (exact in float64)."""
    t, p, a, v = stream(lambda s: np.where(s < 24.0, 300.0, 500.0), 1.2, 40.0, seed=80)
    return t, p, a.astype(np.float32).astype(float), v


def _numpy_twin(value):
    """``value`` as a numpy scalar of the same value (float32 where exact), else None."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    if isinstance(value, int):
        return np.int32(value)
    return np.float32(value) if float(np.float32(value)) == value else np.float64(value)


@pytest.mark.parametrize(
    "settings",
    [Simplex(), TrackerSettings(), ChangePointSettings(), SensorLimits(), BCRSettings()],
    ids=lambda s: type(s).__name__,
)
def test_settings_store_numpy_scalars_as_python_numbers(settings):
    """A numpy scalar field is kept as the Python number of its value (FeatureSpec's rule), so
    that arithmetic with it runs in float64 as with a Python float."""
    for f in fields(settings):
        twin = _numpy_twin(getattr(settings, f.name))
        if twin is None:
            continue
        got = getattr(replace(settings, **{f.name: twin}), f.name)
        assert type(got) is type(getattr(settings, f.name)), (f.name, type(got))
        assert got == twin


def test_a_float32_simplex_commands_as_its_float64_twin():
    """np.float32 fields made the law's arithmetic float32 (NEP 50): the continuous law read
    1.899999976 m/s for 1.9, and GD 350.00001 was not above a float32 GD_max 350."""
    f32 = {k: np.float32(v) for k, v in dict(gd_min=250, gd_max=350, v_max=2, v_safe=1).items()}
    for step in (0.0, 0.1):
        ref, odd = Simplex(speed_step_mps=step), Simplex(speed_step_mps=step, **f32)
        for gd in (200.0, 260.0, 299.99, 333.3, 350.0, 350.00001, 400.0):
            est = Estimate(1.0, 1.0, "ok", gd_mean=gd, gd_sd=1.0, interval=(gd - 1, gd + 1))
            assert odd.command(est) == ref.command(est), (step, gd)
    assert Simplex(**f32).command(Estimate(1.0, 1.0, "ok", gd_mean=350.00001)).mode == "safety"


def test_a_float32_tracker_setting_gives_the_float64_estimates(samples):
    """TrackerSettings(mean_segment_m=np.float32(25.0)) moved every estimate of the filter."""
    make = {"method": "filter", "feature": PAPER_WINDOW}
    odd = TrackerSettings(mean_segment_m=np.float32(25.0), drift_per_sqrt_m=np.float64(0.01))
    ref = _feed(BCR(FakeCalibrator(), **make), samples)
    assert _feed(BCR(FakeCalibrator(), tracker=odd, **make), samples) == ref


def test_a_numpy_int_quiet_blocks_and_update_every_make_a_bcr(samples):
    """BCRSettings took np.int64(16) as quiet_blocks; the BCR then raised TypeError ('an
    integer is required', from its deque)."""
    ref = _feed(BCR(FakeBlockModel(), quiet_blocks=16, update_every=42), samples)
    bcr = BCR(FakeBlockModel(), quiet_blocks=np.int64(16), update_every=np.int16(42))
    assert _feed(bcr, samples) == ref


@pytest.mark.parametrize("kind", ["datetime64[ns]", "timedelta64[ms]"])
def test_datetime_stamps_are_refused_with_the_remedy(samples, kind):
    t, p, a, v = (x[:42] for x in samples)
    stamps = (t * 1000).astype("timedelta64[ms]").astype(kind)
    message = rf"^t must hold real numbers, got dtype {re.escape(kind)}: give the times as seconds"
    with pytest.raises(ControlError, match=message + r" as float64 .*np\.timedelta64\(1, 's'\)"):
        BCR(FakeBlockModel()).update(stamps, p, a, v)


FORMS = {
    "list": lambda x: x.tolist(),
    "tuple": lambda x: tuple(x.tolist()),
    "big-endian": lambda x: x.astype(">f8"),
    "read-only": lambda x: np.lib.stride_tricks.as_strided(x, writeable=False),
    "negative stride": lambda x: x[::-1].copy()[::-1],
    "every other": lambda x: np.repeat(x, 2)[::2],
    "float32 accel": lambda x: x.astype(np.float32) if x.dtype == float else x,
}


@pytest.mark.parametrize("method", ["changepoint", "window"])
def test_arrays_of_the_same_values_in_other_forms_give_the_same_estimates(samples, method):
    model = FakeBlockModel() if method == "changepoint" else FakeCalibrator()
    make = {} if method == "changepoint" else {"method": "window", "feature": PAPER_WINDOW}
    ref = _feed(BCR(model, **make), samples)
    for name, form in FORMS.items():
        odd = [form(x) for x in samples[:2]] + [form(samples[2])] + [form(samples[3])]
        if name == "float32 accel":  # the samples' values are float32's (the fixture)
            odd = [*samples[:2], samples[2].astype(np.float32), samples[3]]
        assert _feed(BCR(model, **make), odd) == ref, name
    pd = pytest.importorskip("pandas")
    as_series = [pd.Series(x, index=np.arange(x.size) + 7) for x in samples]
    assert _feed(BCR(model, **make), as_series) == ref


@pytest.mark.parametrize("method", ["changepoint", "window", "filter", "tempered"])
def test_every_update_is_the_same_in_any_chunking(samples, method):
    """One sample a call, primes, empty calls and all 4,800 samples in one call."""
    model = FakeBlockModel() if method == "changepoint" else FakeCalibrator()
    make = {} if method == "changepoint" else {"method": method, "feature": PAPER_WINDOW}
    every = BCR(model, **make).settings.samples_per_update
    ref = _per_update(BCR(model, **make), samples, [every])
    for chunks in ([1], [7, 0, 13, 997], [samples[0].size]):
        got = _per_update(BCR(model, **make), samples, chunks)
        assert got and all(got[k] == ref[k] for k in got), chunks
    assert len(_per_update(BCR(model, **make), samples, [1])) == len(ref)


@pytest.mark.parametrize("method", ["changepoint", "filter"])
def test_a_copy_and_a_pickle_mid_stream_go_on_as_the_original(samples, method):
    model = FakeBlockModel() if method == "changepoint" else FakeCalibrator()
    make = {} if method == "changepoint" else {"method": method, "feature": PAPER_WINDOW}
    head, tail = [x[:2011] for x in samples], [x[2011:] for x in samples]  # mid-update
    bcr = BCR(model, **make)
    _feed(bcr, head, 37)
    twins = copy.deepcopy(bcr), pickle.loads(pickle.dumps(bcr))
    ref = _feed(bcr, tail, 37)
    assert all(_feed(twin, tail, 37) == ref for twin in twins)


def test_two_threads_sharing_one_model_give_the_serial_estimates(samples, likelihood_a):
    """docs: BCRs on several threads may share one ObservationModel (its cache holds no lock)."""
    from control import bcr_settings_for

    settings = bcr_settings_for(likelihood_a.emulator)
    louder = (*samples[:2], 1.5 * samples[2], samples[3])
    streams = (samples, louder)
    serial = [_feed(BCR(likelihood_a, settings), s, 13) for s in streams]
    shared = copy.deepcopy(likelihood_a)  # a fresh cache, for the threads alone
    got = [None, None]

    def run(i):
        got[i] = _feed(BCR(shared, settings), streams[i], 13)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert got == serial
