"""roadgen's array inputs given as torch tensors that record gradients: numpy's conversion
raised torch's RuntimeError "Can't call numpy() on Tensor that requires grad" from Road, the
PSD functions, gd_spectrum and a track's height_at / gd_at; roadgen reads only the values, so
they now give the plain arrays' results (a plain tensor already did)."""

import numpy as np
import pytest

import roadgen

torch = pytest.importorskip("torch")


def _grad(values) -> torch.Tensor:
    return torch.tensor(np.asarray(values, dtype=float), requires_grad=True)


def test_tensors_that_require_grad_give_the_plain_arrays_results():
    p = roadgen.iso8608_profile(10.0, gd=450, seed=0)
    road = roadgen.Road(_grad(p.x), _grad(p.z), p.dx_m)
    assert roadgen.estimate_gd(road) == roadgen.estimate_gd(p)
    for got, want in zip(roadgen.profile_psd(road), roadgen.profile_psd(p), strict=True):
        np.testing.assert_array_equal(got, want)
    n = np.array([0.1, 0.5, 2.0])
    np.testing.assert_array_equal(roadgen.gd_spectrum(_grad(n), 450), roadgen.gd_spectrum(n, 450))
    tr = roadgen.track([(5, 300), (5, 500)], seed=0)
    s = np.array([1.0, 7.0, 3.5])
    np.testing.assert_array_equal(tr.height_at(_grad(s)), tr.height_at(s))
    np.testing.assert_array_equal(tr.gd_at(_grad(s)), tr.gd_at(s))
