"""Session 88: the output bases (``gpmsa.model.basis``) pinned where mutation testing found the
tests loose: the PCA basis against numpy's SVD of the standardised outputs (scaling by sqrt(m),
the variance-fraction choice of p_u), the discrepancy basis against its documented
normalisation (one float division by the largest row norm), the variance shares, the
interpolation onto another grid of the same size and the reorder search's limit."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from gpmsa.errors import BasisWarning
from gpmsa.model import basis
from gpmsa.model.priors import GammaPrior


def _outputs_with_shares(shares, m=12, l_sim=7, seed=0):
    """Standardised outputs (m, l_sim) whose singular values give the cumulative variance
    shares ``shares`` exactly (to rounding): y = A diag(s) B^T with orthonormal A, B."""
    rng = np.random.default_rng(seed)
    s2 = np.diff(np.concatenate([[0.0], shares]))
    A = np.linalg.qr(rng.normal(size=(m, len(s2))))[0]
    B = np.linalg.qr(rng.normal(size=(l_sim, len(s2))))[0]
    return (A * np.sqrt(s2 * 50.0)) @ B.T


def test_pca_basis_is_u_s_over_sqrt_m_of_numpys_svd():
    y = np.random.default_rng(1).normal(size=(9, 6)) @ np.diag([3.0, 2, 1, 0.5, 0.1, 0.01])
    u, s, _ = np.linalg.svd(y.T, full_matrices=False)
    K = basis.pca_basis(y, n_pc=3)
    np.testing.assert_array_equal(K, u[:, :3] * s[:3] / np.sqrt(9))
    # sign-free: K^T K is the leading eigenvalues of y^T y / m, K K^T their part of it
    lam = np.linalg.eigvalsh(y.T @ y / 9)[::-1]
    np.testing.assert_allclose(K.T @ K, np.diag(lam[:3]), atol=1e-12)
    # the weights of the runs on it have unit root mean square (the priors' scale)
    w = basis.basis_weights(y, K)
    np.testing.assert_allclose(np.sqrt(np.mean(w**2, axis=0)), 1.0, rtol=1e-12)


@pytest.mark.parametrize(
    ("n_pc", "expected"),
    [(None, 5), (0.5, 1), (0.8, 2), (0.81, 3), (0.95, 3), (0.96, 4), (2, 2), (5, 5)],
)
def test_the_fewest_components_reaching_the_variance_fraction(n_pc, expected):
    """Cumulative shares 0.5, 0.8, 0.95, 0.99, 1: a fraction equal to a share takes that many
    components, one just above it one more; the default 0.995 all five."""
    y = _outputs_with_shares([0.5, 0.8, 0.95, 0.99, 1.0])
    assert basis.pca_basis(y, n_pc=n_pc).shape == (7, expected)


def test_a_fraction_argument_and_a_scalar_output():
    y = _outputs_with_shares([0.5, 0.8, 0.95, 0.99, 1.0])
    assert basis.pca_basis(y, fraction=0.9).shape == (7, 3)
    assert basis.pca_basis(y, fraction=1.0).shape == (7, 5)
    np.testing.assert_array_equal(basis.pca_basis(y[:, :1], n_pc=1), [[1.0]])


def test_discrepancy_basis_is_one_division_by_the_largest_row_norm():
    """D / sqrt(max_i sum_k D_ik^2), the same float operations (no rescaling where the squares
    neither over- nor underflow); a list: one scale over all experiments; scaled_as divides
    another D by it, basis_scale is it."""
    rng = np.random.default_rng(2)
    D = rng.normal(size=(8, 3))
    norm = np.sqrt(np.max(np.sum(D**2, axis=1)))
    np.testing.assert_array_equal(basis.discrepancy_basis(D, np.linspace(0, 1, 8)), D / norm)
    assert basis.basis_scale([D]) == norm
    D2 = 3.0 * rng.normal(size=(5, 3))
    norm2 = np.sqrt(max(np.max(np.sum(D**2, axis=1)), np.max(np.sum(D2**2, axis=1))))
    out = basis.discrepancy_bases([D, D2], [np.linspace(0, 1, 8), np.linspace(0, 1, 5)])
    np.testing.assert_array_equal(out[0], D / norm2)
    np.testing.assert_array_equal(out[1], D2 / norm2)
    E = rng.normal(size=(4, 3))
    np.testing.assert_array_equal(basis.scaled_as([D, D2], E), E / norm2)
    # squares that underflow: rescaled by the largest |value| first, the same basis to rounding
    tiny = [1e-200 * D, 1e-200 * D2]
    np.testing.assert_allclose(basis.scaled_as(tiny, 1e-200 * E), E / norm2, rtol=1e-14)
    np.testing.assert_allclose(basis.basis_scale(tiny), 1e-200 * norm2, rtol=1e-14)


def test_named_discrepancy_bases_on_a_grid():
    g = np.array([0.0, 0.5, 2.0])
    np.testing.assert_array_equal(basis.discrepancy_basis("constant", g), np.ones((3, 1)))
    lin = np.column_stack([np.ones(3), g]) / np.sqrt(1.0 + 4.0)
    np.testing.assert_array_equal(basis.discrepancy_basis("linear", g), lin)
    assert basis.discrepancy_basis(None, g) is None


def test_variance_shares_and_a_zero_total():
    w = np.array([[1.0, 2.0], [3.0, -1.0]])
    lam = np.array([2.0, 0.5])
    np.testing.assert_allclose(basis.variance_shares(w, lam, 10.0), [2.0, 0.25])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = basis.variance_shares(w, lam, 0.0)
    assert np.all(np.isnan(out))


def test_interpolating_onto_another_grid_of_the_same_size():
    grid = np.array([0.0, 1.0, 2.0])
    K = np.array([[1.0, 0.0], [3.0, 1.0], [5.0, 4.0]])
    assert basis.interpolate_basis(K, grid, grid.copy()) is K
    new = np.array([0.5, 1.5, 2.0])
    np.testing.assert_allclose(basis.interpolate_basis(K, grid, new),
                               [[2.0, 0.5], [4.0, 2.5], [5.0, 4.0]])  # fmt: skip


def test_the_reorder_search_stays_within_its_limit():
    """One group of 5 columns: 5! 2^5 = 3840 candidates, every order; of 6: 6! 2^6 = 46080,
    beyond REORDER_LIMIT: the given order alone (its signs)."""
    assert len(basis._orders([0] * 5, [0] * 5)) == 120
    assert basis._orders([0] * 6, [0] * 6) == [list(range(6))]
    assert basis._orders([0] * 14, [0] * 14) == []


def test_the_weight_scale_warning_names_the_unused_columns():
    prior = GammaPrior(5.0, 5.0, 0.3)
    rng = np.random.default_rng(3)
    w = np.column_stack([1e3 * rng.normal(size=20), 1e-11 * rng.normal(size=20)])
    with pytest.warns(BasisWarning, match=r"Column\(s\) \[1\] hold none"):
        basis.warn_weight_scale(w, prior)
    y = _outputs_with_shares([0.6, 1.0])
    with warnings.catch_warnings():  # the PCA basis's weights: unit scale, no warning
        warnings.simplefilter("error")
        basis.warn_weight_scale(basis.basis_weights(y, basis.pca_basis(y, n_pc=2)), prior)
