"""A constraint on two calibration parameters on the Calibrator's grid: no draw outside it, and
the grid's moments and quantiles those of its density cut exactly at the boundary.

The reference is the grid's own (bilinear) unconstrained density on 1,024 x 1,024 cell midpoints,
the constraint applied per point. Tolerance: linear interpolation with node spacing h errs by at
most h^2 / 8 max|f''| in a density f, about (h / sd)^2 / 8 of its peak for a density of scale
sd: the grid's normal interpolation error, which the cut at the boundary must stay within (in sd
units). The old cut (forbidden nodes zero, the density ramping down across the crossed cells)
missed it by 3 to 30 times, and 1 % (0.1 %) of the draws lay outside."""

import numpy as np
import pytest
from _calib_cases import two_param_emulator
from scipy.interpolate import RegularGridInterpolator
from test_calib_grid_posterior import symmetric_two_param_emulator

from gpmsa import Calibrator
from gpmsa.errors import GPMSAError

N_REF = 1024


def below_line(a, b):
    """The broad case's allowed region (native a, b): through the unconstrained mean."""
    return a + b <= 1.1556


def below_slope(a, b):
    """The two-peak case's allowed region: through both peaks, below their b = 0.5."""
    return b <= 0.5 + 0.2 * (a - 0.5)


def broad_case():
    """One observation: a broad, skewed posterior on the fixed 65 x 65 grid."""
    return two_param_emulator(), [[0.3]], [[np.sin(0.6 + 0.6) + 0.8 * 0.6 * 0.3]], below_line


def peaks_case():
    """Two narrow peaks (a near 0.3 and 0.7): a refined grid."""
    x = np.linspace(0.05, 0.95, 12)[:, None]
    y = (0.3 - 0.5) ** 2 * (1 + x) + 0.3 * 0.5 * x
    return symmetric_two_param_emulator(), x, y, below_slope


def cut_posterior(case, n_draws=20_000):
    """The posterior, and the grid (native axes) and unconstrained log density it came from."""
    emu, x, y, allowed = case
    cal = Calibrator(emu, n_draws=n_draws, seed=4,
                     constraint=lambda th: bool(allowed(th[0], th[1])))  # fmt: skip
    seen = {}
    inner = cal._posterior

    def spy(axes, free, ok, margs, key, prior):
        seen.update(axes=axes, free=free)
        return inner(axes, free, ok, margs, key, prior)

    cal._posterior = spy
    post = cal.update(x, y)
    std = emu.standardizer
    axes = [a * (std.t_max[k] - std.t_min[k]) + std.t_min[k] for k, a in enumerate(seen["axes"])]
    return post, axes, seen["free"]


def exact_cut(axes, free, allowed):
    """Per parameter: (midpoints (N_REF,), marginal masses (N_REF,)) of the bilinear density of
    ``free`` on ``axes``, zero where ``allowed`` (a, b) is False, point by point."""
    f = np.exp(free - free.max()).reshape(axes[0].size, axes[1].size)
    mid = [a[0] + (np.arange(N_REF) + 0.5) * (a[-1] - a[0]) / N_REF for a in axes]
    A, B = np.meshgrid(*mid, indexing="ij")
    g = RegularGridInterpolator(axes, f)(np.column_stack([A.ravel(), B.ravel()]))
    g = np.where(allowed(A, B), g.reshape(A.shape), 0.0)
    g /= g.sum()
    return [(mid[0], g.sum(axis=1)), (mid[1], g.sum(axis=0))]


@pytest.mark.parametrize("case", [broad_case, peaks_case], ids=["fixed_grid", "refined_grid"])
def test_two_parameter_cut_matches_the_exact_cut_and_no_draw_is_outside(case):
    allowed = case()[3]
    post, axes, free = cut_posterior(case())
    assert post.info["refined"] is (case is peaks_case)
    draws = post.samples
    assert np.count_nonzero(~allowed(draws["a"], draws["b"])) == 0
    for k, name in enumerate(("a", "b")):
        mid, mass = exact_cut(axes, free, allowed)[k]
        mean = mass @ mid
        sd = np.sqrt(mass @ (mid - mean) ** 2)
        tol = (np.diff(axes[k]).min() / sd) ** 2 / 8  # sd units; the finest (refined) spacing
        assert abs(post.mean(name) - mean) <= tol * sd
        edges = mid + 0.5 * (mid[1] - mid[0])  # the reference's CDF at its cells' upper edges
        for p in (0.1, 0.5, 0.9):
            assert abs(post.quantile(name, p) - np.interp(p, np.cumsum(mass), edges)) <= tol * sd
        if case is broad_case:  # the draws follow the grid density (4 Monte-Carlo errors)
            assert abs(draws[name].mean() - post.mean(name)) < 4 * post.sd(name) / np.sqrt(20_000)


def test_draws_are_redrawn_until_the_constraint_holds():
    """A constraint that forbids more than the grid sees (a disc inside one cell, touching no
    node) loses no draw and keeps none inside the disc; one that forbids everything the grid
    allows is refused with the reason."""
    emu, x, y, _ = broad_case()
    centre = np.array([0.5, 0.5])
    hole = lambda th: bool(np.hypot(*(th - centre)) > 0.004)  # noqa: E731
    post = Calibrator(emu, n_draws=5000, seed=1, constraint=hole).update(x, y)
    d = np.hypot(post.samples["a"] - 0.5, post.samples["b"] - 0.5)
    assert d.size == 5000 and d.min() > 0.004
    calls = iter(range(10**9))
    nodes_only = lambda th: next(calls) < 65 * 65  # noqa: E731 (False after the grid's nodes)
    post = Calibrator(emu, n_draws=100, constraint=nodes_only).update(x, y)
    with pytest.raises(GPMSAError, match="the constraint rejected .* draws from the grid density"):
        post.samples  # noqa: B018
