"""An estimate's posterior shares no writable array with the BCR that made it. Before: its
grid marginal's ``nodes`` were the change-point filter's (or the GD tracker's) own GD grid and
its ``weights`` the filter's trapezoid weights, so that a write into them (a unit conversion in
place) changed every later estimate, or made the next update raise a GPMSAError."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import control
import roadgen
import vehicle


def _feed(bcr: control.BCR, arrays, chunk: int = 125) -> list[control.Estimate]:
    t, p, a, v = arrays
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
        for k in range(0, t.size, chunk)
    ]


@pytest.mark.parametrize("method", ["changepoint", "window"])
def test_writing_into_an_estimates_grid_changes_no_later_estimate(method, new_bcr):
    if method == "changepoint":
        bcr = new_bcr("A")
    else:
        bcr = control.BCR.from_emulator(control.shipped_emulator("A", kind="window"), method=method)
    twin = copy.copy(bcr)  # the same model, a stream state of its own
    road = roadgen.iso8608_profile(14.0, gd=400, seed=3, lead_in_m=1.0)
    trace = vehicle.simulate(vehicle.Jackal(), road, 1.2, seed=1)  # 1,373 samples
    data = trace.t, trace.position, trace.accel_front, trace.speed
    half = [x[:1000] for x in data], [x[1000:] for x in data]
    first = [e for e in _feed(bcr, half[0]) if e.ok][-1]
    _feed(twin, half[0])
    grid = first.posterior.grids["GD"]
    for name in ("nodes", "weights"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(grid, name)[: grid.nodes.size // 2] *= 3.0
    later, expected = _feed(bcr, half[1]), _feed(twin, half[1])
    assert [e.status for e in later] == [e.status for e in expected]
    np.testing.assert_allclose([e.gd_mean for e in later], [e.gd_mean for e in expected])
