"""A nearly collinear mean basis is refused before sampling, not lost partway through a run.

The restricted likelihood factors H^T Sigma_W^-1 H (``GLS``), whose condition number is about
the basis's own squared times Sigma_W's. ``check_rank`` took any basis of full numerical rank
(condition number up to ~1e14): a callable [1, z0, z0 + 1e-10 sin(7 z1)] on 12 runs (condition
number 2.4e10, columns scaled) failed that factorisation at 58% of the proposals (rejected
silently), left 2 of 10 seeded fits (400 sweeps) in a ``ChainError`` and 6 of 10 raising "the
mean basis is collinear" at their first prediction; at 1.2e9 all 10 fits of 1,500 sweeps met it,
first at sweeps 0 to 473. Now a basis whose columns, scaled to unit length, have a condition
number above ``MAX_CONDITION`` is refused up front, naming the columns; below it the
factorisation holds over the default priors' support.
"""

import numpy as np
import pytest
from scipy.linalg import cholesky, solve_triangular

import gpmsa
from gpmsa.model.correlation import correlation
from gpmsa.model.mean_basis import MAX_CONDITION, MeanBasis, check_rank


def _sim(m: int = 12, gap: float | None = None) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x = rng.random((m, 1))
    t = rng.random((m, 1)) if gap is None else x + gap * rng.standard_normal((m, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["v"], t_names=["GD"])


def _near(eps: float):
    return lambda z: np.column_stack(
        [np.ones(len(z)), z[:, 0], z[:, 0] + eps * np.sin(7 * z[:, 1])]
    )


def test_a_nearly_collinear_callable_basis_is_refused_before_sampling():
    # before: the fit ran (GLS term failing at ~half the proposals), then predict raised
    with pytest.raises(gpmsa.GPMSAError, match=r"nearly collinear on the simulation design: its "
                       r"columns 1, 2 .*condition number 2\.\d+e\+10 .* above MAX_CONDITION = "
                       r"1e\+06.* drop one of them or orthogonalise"):  # fmt: skip
        gpmsa.fit(_sim(), n_iter=20, seed=0, tune=False, mean_basis=_near(1e-10))


def test_a_linear_basis_on_nearly_collinear_design_columns_names_them():
    sim = _sim(gap=1e-7)  # the design itself passes SimData's rank check (1e-8)
    with pytest.raises(gpmsa.GPMSAError, match=r"its columns v, GD are close to linearly"):
        gpmsa.fit(sim, n_iter=20, seed=0, tune=False, mean_basis="linear")


def test_a_basis_just_under_the_limit_factors_over_the_prior_support():
    rng = np.random.default_rng(1)
    m = 20
    z = rng.random((m, 2))
    h = _near(2.5e-6)(z)  # condition number 9.0e5, columns scaled
    check_rank(MeanBasis("callable", 2, _near(2.5e-6), 3), z)  # accepted
    q, r = np.linalg.qr(h)
    for _ in range(60):  # betaU, lamUz and the nugget across the default priors' support
        beta = 10 ** rng.uniform(-4, 3, 2)
        sigma = correlation(z, None, beta, None) / 10 ** rng.uniform(-0.5, 2)
        sigma[np.diag_indices(m)] += 10 ** rng.uniform(-5, -1)
        low = cholesky(sigma, lower=True)
        a, b = solve_triangular(low, h, lower=True), solve_triangular(low, q, lower=True)
        gram = np.sum(np.log(np.diag(cholesky(a.T @ a, lower=True))))  # raised before: no
        stable = np.sum(np.log(np.abs(np.diag(r)))) + np.sum(
            np.log(np.diag(cholesky(b.T @ b, lower=True)))
        )
        assert abs(gram - stable) < 0.5  # the log-determinant term, to within half a nat


def test_the_limit_is_scale_free_and_well_conditioned_bases_pass():
    z = np.random.default_rng(2).random((12, 2))
    check_rank(MeanBasis("linear", 2), z)
    wide = lambda u: np.column_stack([np.ones(len(u)), 1e8 * u[:, 0], 1e-6 * u[:, 1]])  # noqa: E731
    check_rank(MeanBasis("callable", 2, wide, 3), z)  # columns of very different sizes
    assert MAX_CONDITION == 1e6
