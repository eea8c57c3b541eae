"""Review of session 72's additions (separable designs, a given output scale): hostile edits of
an emulator file refused naming the field, never accepted as garbage nor a crash in numpy."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gpmsa
from gpmsa.errors import EmulatorFileError
from gpmsa.fitting.validation import kron_groups


def _record():
    """A separable emulator (x: 5 points, t: 6 points, 2 columns) with a given y_mean, y_sd
    and an x_range: every new file field at once."""
    rng = np.random.default_rng(0)
    xs, ts = np.linspace(0.0, 1.0, 5), rng.random((6, 2))
    x, t = np.repeat(xs, 6)[:, None], np.tile(ts, (5, 1))
    y = np.sin(3 * x) * np.linspace(1.0, 2.0, 3) + t[:, :1] ** 2 + 0.3 * t[:, 1:]
    sim = gpmsa.SimData(x=x, t=t, y=y, separable=[[0], [1, 2]], y_mean=0.5,
                        y_sd=[1.0, 2.0, 3.0], x_range=[[-0.5, 1.5]])  # fmt: skip
    prm = {"betaU": np.ones((3, 2)), "lamUz": [1.0, 1.0], "lamWs": [1e4] * 2, "lamWOs": [1e4]}
    return gpmsa.Emulator.from_params(sim, prm, n_pc=2).to_record()


@pytest.mark.parametrize("codes", [[0, 1e18, 1], [0, 1, 2.0**62], [0, -1, 1]])
def test_kron_factor_with_a_huge_code_is_refused_by_name(codes):
    """A factor code far beyond the inputs' number: before, np.arange(code) raised MemoryError
    (1e18) or an 'inconsistent content (ValueError: array is too big ...)' (2**62)."""
    manifest, arrays = _record()
    with pytest.raises(EmulatorFileError, match="arrays/kron_factor: .*must number"):
        gpmsa.Emulator.from_record(manifest, {**arrays, "kron_factor": np.array(codes, float)})


@pytest.mark.parametrize("value", [1e308, -1e308])
def test_a_given_y_mean_that_overflows_the_standardised_runs_is_refused(value):
    """An edited given y_mean whose standardised runs overflow float64: before, the weights'
    check compared against an infinite tolerance and passed, so the file loaded with y_mean
    1e308 (predictions near 1e308), though docs/emulator-file.md says an edited y_mean is
    refused. SimData refuses such a scale; the reader now does too."""
    manifest, arrays = _record()
    arrays = {**arrays, "y_mean": np.full(arrays["y_mean"].shape, value)}
    with pytest.raises(
        EmulatorFileError, match="arrays/y_mean and arrays/y_sd: .*overflow float64"
    ):
        gpmsa.Emulator.from_record(manifest, arrays)
    assert manifest["model"]["y_given"] == ["y_mean", "y_sd"]
    m2 = copy.deepcopy(manifest)  # the untouched record loads
    gpmsa.Emulator.from_record(m2, _record()[1])


@settings(max_examples=150, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=1, max_size=6))
def test_kron_groups_parses_or_refuses_any_codes(codes):
    """Any float codes: a partition of the inputs into at least two factors numbered 0, 1, ...,
    or an EmulatorFileError naming arrays/kron_factor; never another exception."""
    try:
        groups = kron_groups({"kron_factor": np.array(codes, dtype=float)})
    except EmulatorFileError as exc:
        assert str(exc).startswith("arrays/kron_factor: ")
        return
    assert len(groups) >= 2 and sorted(c for g in groups for c in g) == list(range(len(codes)))
    assert all(codes[c] == f for f, g in enumerate(groups) for c in g)
