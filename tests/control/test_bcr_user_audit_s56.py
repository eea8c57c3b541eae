"""The BCR fed in a robot user's own loop (docs/closed-loop.md, "Guards"; session 56 audit)."""

import numpy as np
from control_doubles import FakeBlockModel, stream

from control import BCR

EVERY = 42


def test_a_silent_update_of_non_finite_readings_names_them_too():
    """Readings that arrive but are NaN leave the BCR without a finite sample: with the
    caller's clock that is silence, and the reason names both causes, not silence alone."""
    bcr = BCR(FakeBlockModel())
    t, p, a, v = stream(lambda x: 400.0 + 0 * x, 1.5, 20, seed=1)
    a = a.copy()
    a[1260:1400] = np.nan  # 1.2 s of NaN readings
    reasons = []
    for k in range(0, 1512, EVERY):
        part = slice(k, k + EVERY)
        est = bcr.update(t[part], p[part], a[part], v[part], now=float(t[k + EVERY - 1]))
        reasons.append((est.status, est.reason))
    silent = [r for s, r in reasons if s == "sensor_fault" and "no samples for" in r]
    assert silent, reasons
    assert all("42 sample(s) with non-finite accel" in r for r in silent), silent
