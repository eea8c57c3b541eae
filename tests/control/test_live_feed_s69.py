"""A robot's own loop feeding `BCR.update` in chunks of any size (session 69): the reasons of the
stream faults do not depend on the chunking, as the estimates do not."""

import numpy as np
import pytest
from control_doubles import FakeBlockModel, stream

from control import BCR

EVERY = 42


def _feed(t, p, a, v, chunk, now=True):
    """(estimates made by the updates, estimates returned by the calls) of a new BCR fed in
    chunks of ``chunk`` samples, with ``now=`` the newest sample's time."""
    bcr = BCR(FakeBlockModel())
    made = []
    estimate = bcr._estimate
    bcr._estimate = lambda: made.append(estimate()) or made[-1]
    returned = []
    for k in range(0, t.size, chunk):
        part = slice(k, k + chunk)
        clock = float(t[part][-1]) if now else None
        returned.append(bcr.update(t[part], p[part], a[part], v[part], now=clock))
    return made, returned


def _faulty_stream():
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 12, seed=3)
    a[420:462] = np.nan  # a whole update's accelerations
    v[505:507], v[520] = np.nan, 1e3  # NaN speeds, a wild one, in one update
    t[600] = t[599]  # a repeated stamp
    t[700:] += 1.0 / 120  # a dropped sample ...
    t[703:] += 2.0 / 120  # ... and two more, in the same update
    return t, p, a, v


@pytest.mark.parametrize("chunk", [1, 7, 50])
def test_fault_reasons_do_not_depend_on_the_chunking(chunk):
    """Before: each chunk's reason was kept once per update, with its own counts: fed one
    sample a call, an update whose 42 accelerations were all NaN read "1 sample(s) with
    non-finite accel", and two gaps in one update were named as two."""
    t, p, a, v = _faulty_stream()
    reference, _ = _feed(t, p, a, v, EVERY)
    made, _ = _feed(t, p, a, v, chunk)
    assert [e.status for e in made] == [e.status for e in reference]
    assert [e.reason for e in made] == [e.reason for e in reference]
    faults = [e.reason for e in reference if e.status == "sensor_fault"]
    assert faults[0].startswith("42 sample(s) with non-finite accel;"), faults
    assert any(r.startswith("2 sample(s) with non-finite speed and 1 sample(s) with |speed| up to")
               for r in faults), faults  # fmt: skip
    assert any(r.startswith("a gap of 0.025 s (about 2 dropped samples);") for r in faults)


def test_silence_while_broken_samples_arrive_names_them_in_any_chunking():
    """Before: fed one sample a call, samples that arrived NaN for more than max_silence_s read
    "no samples for 0.53 s" between updates (only the updates named the NaN samples)."""
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 4, seed=3)
    a[126:] = np.nan
    for chunk in (1, EVERY):
        _, returned = _feed(t, p, a, v, chunk)
        silent = [e for e in returned if "no samples for" in e.reason]
        assert silent and all("sample(s) with non-finite accel" in e.reason for e in silent)


def test_a_bcr_pickled_before_session_69_reports_its_pending_fault():
    """Its pending fault was one string (``_fault``), without ``_breaks``."""
    import pickle

    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 2, seed=3)
    bcr = BCR(FakeBlockModel())
    bcr.update(t[:130], p[:130], a[:130], v[:130])
    del bcr.__dict__["_breaks"]
    bcr._fault = "a gap of 1 s (about 119 dropped samples)"
    restored = pickle.loads(pickle.dumps(bcr))
    est = restored.update(t[130:168], p[130:168], a[130:168], v[130:168])
    assert est.status == "sensor_fault" and est.reason.startswith("a gap of 1 s (about 119")
