"""Mutation testing of control/training.py (s89): exact, hand-computed answers of the batch
means, the kernel weights, the node and argument checks at their boundaries, the Student-t dof
decision, and what `fit_band_emulator` / `fit_window_emulator` hand to the fit and record."""

import dataclasses
import warnings

import numpy as np
import pytest
from scipy import stats

import control
from control.errors import ControlError
from control.sensor_checks import MAX_ACCEL_MPS2
from control.training import (
    BlockStatistics,
    block_scatter,
    block_statistics,
    covariance_rank,
    feature_statistics,
    fit_band_emulator,
    fit_window_emulator,
    weight_beyond_rank,
)

# two features of one run, 7 blocks: batches of 2 leave the last block out of the batch means
RUN = np.array([[0, 1], [2, 1], [4, 1], [0, 1], [1, 1], [5, 1], [9, 8]], dtype=float)


def _stats(covs) -> BlockStatistics:
    """Runs of the given (m, K, K) covariances, mean 0 and 40 random blocks each."""
    covs = np.asarray(covs, dtype=float)
    m, k = covs.shape[0], covs.shape[1]
    rng = np.random.default_rng(0)
    return BlockStatistics(mean=np.zeros((m, k)), cov=covs, features=rng.normal(size=(m, 40, k)))


def test_feature_statistics_is_the_batch_means_by_hand():
    """Run 0: means (3, 2); deviations of the first 6 blocks in batches of 2 give batch means
    (-2, -1), (-1, -1), (0, -1); their sum of products / (3 - 1) x 2 = [[5, 3], [3, 3]].
    Run 1 = 2 run 0 + 1: means (7, 5), covariance 4 times as large."""
    out = feature_statistics(np.stack([RUN, 2 * RUN + 1]), batch=2)
    np.testing.assert_allclose(out.mean, [[3.0, 2.0], [7.0, 5.0]], rtol=1e-15)
    np.testing.assert_allclose(out.cov[0], [[5.0, 3.0], [3.0, 3.0]], rtol=1e-14)
    np.testing.assert_allclose(out.cov[1], [[20.0, 12.0], [12.0, 12.0]], rtol=1e-14)
    assert out.features.shape == (2, 7, 2)


def test_block_statistics_are_frozen_and_compared_by_identity():
    a = feature_statistics(np.stack([RUN, RUN]), batch=2)
    b = feature_statistics(np.stack([RUN, RUN]), batch=2)
    assert a != b and a == a and isinstance(hash(a), int)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.mean = b.mean


def test_covariance_rank_defaults_to_batches_of_8():
    assert covariance_rank(17) == 2 and covariance_rank(16) == 1


def test_block_scatter_is_the_kernel_weighted_covariance_by_hand():
    """Runs at 1.0 and 1.15 m/s, the default bandwidth 0.15 m/s: at each node the nearer run
    weighs 1 and the other exp(-1/2), normalised."""
    a, b = np.diag([1.0, 2.0]), np.array([[3.0, 1.0], [1.0, 2.0]])
    e = np.exp(-0.5)
    scatter = block_scatter(np.array([1.0, 1.15]), _stats([a, b]), nodes=[1.0, 1.15])
    np.testing.assert_allclose(scatter.cov[0], (a + e * b) / (1 + e), rtol=1e-12)
    np.testing.assert_allclose(scatter.cov[1], (e * a + b) / (1 + e), rtol=1e-12)
    share = weight_beyond_rank(np.array([1.0, 1.15]), 1, 2, np.array([1.0, 1.15]))
    np.testing.assert_allclose(share, [e / (1 + e)] * 2, rtol=1e-12)  # the farther run's
    assert weight_beyond_rank(np.array([1.0, 1.15]), 1, 1, np.array([1.0])) == pytest.approx(1.0)
    with pytest.raises(ControlError, match="run_rank and dim must be integers >= 1"):
        weight_beyond_rank(np.array([1.0, 1.15]), 1, 0, np.array([1.0]))


def test_a_tiny_but_regular_covariance_is_accepted():
    """The singularity check is relative to the trace: a covariance of 1e-14 I is regular."""
    tiny = _stats([1e-14 * np.eye(2)] * 2)
    scatter = block_scatter(np.array([1.0, 1.1]), tiny, nodes=[1.0, 1.1])
    np.testing.assert_allclose(scatter.cov, 1e-14 * np.eye(2)[None].repeat(2, 0), rtol=1e-12)


def test_the_nodes_are_checked_at_their_boundaries():
    speed, st = np.array([1.0, 2.0]), _stats([np.eye(2), np.eye(2)])
    # exactly 30 bandwidths (0.25 m/s) from the run at 2 m/s: still informed
    assert block_scatter(speed, st, nodes=[1.0, 9.5], bandwidth=0.25).cov.shape == (2, 2, 2)
    with pytest.raises(ControlError, match=r"speed node 9.75 m/s lies more than 30 bandwidths"):
        block_scatter(speed, st, nodes=[1.0, 9.75], bandwidth=0.25)
    # a run far from every node is no node far from every run
    three = _stats([np.eye(2)] * 3)
    assert block_scatter(np.array([1.0, 1.1, 20.0]), three, nodes=[1.0, 1.1]).cov.shape[0] == 2
    for nodes in ([1.0, 1.0], [1.0, np.nan], [[1.0, 2.0]]):
        with pytest.raises(ControlError, match="nodes must be >= 2 increasing finite speeds"):
            block_scatter(speed, st, nodes=nodes)
    for bad in (np.array([1.0, 2.0, 3.0]), np.array([1.0, np.nan])):
        with pytest.raises(ControlError, match=r"speed must hold one finite value per run \(2\)"):
            block_scatter(bad, st, nodes=[1.0, 2.0])


def test_accelerations_at_the_limit_and_batches_of_two_are_accepted():
    accel = np.random.default_rng(3).standard_normal((2, 125 * 4))
    accel[0, 7] = MAX_ACCEL_MPS2
    out = block_statistics(accel, control.FeatureSpec(), batch=2)
    assert out.mean.shape == (2, 10) and np.all(np.isfinite(out.cov))


def _features(seed: int, nu: float, n: int = 64) -> np.ndarray:
    """Two runs of n blocks of 2 features, Student t of nu dof (0: Gaussian), scales 1 and 10."""
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((2, n, 2))
    if nu:
        z = z / np.sqrt(rng.chisquare(nu, (2, n, 1)) / nu)
    return z * np.array([1.0, 10.0])[:, None, None] + np.array([[0.0, 1.0], [5.0, -2.0]])[:, None]


def _dof_case(seed: int, nu: float, n: int = 64):
    """block_scatter's dof and, computed here, the F(2, nu) negative log-likelihood of the
    blocks' d2 / 2 (each run's about its mean, with the covariance of its own node) and the
    Gaussian's."""
    feats = _features(seed, nu, n)
    st = feature_statistics(feats, batch=2)
    speed = np.array([1.0, 3.0])
    scatter = block_scatter(speed, st, nodes=speed)
    dev = feats - st.mean[:, None]
    inv = np.linalg.inv(scatter.cov)
    x = np.concatenate([np.einsum("bi,ij,bj->b", dev[r], inv[r], dev[r]) for r in range(2)]) / 2
    gauss = -np.sum(stats.chi2.logpdf(2 * x, 2) + np.log(2))
    return scatter.dof, (lambda nu_: -np.sum(stats.f.logpdf(x, 2, nu_))), gauss


@pytest.mark.parametrize("seed, nu", [(1, 4.0), (0, 10.0)])  # improvements 8.8 and 1.3
def test_the_dof_is_the_maximum_likelihood_where_it_beats_the_gaussian_by_more_than_1(seed, nu):
    dof, nll, gauss = _dof_case(seed, nu)
    assert 2.5 < dof < 1000.0
    assert nll(dof) <= min(nll(dof * 1.01), nll(dof / 1.01))
    assert nll(dof) < gauss - 1.0


@pytest.mark.parametrize("seed", [0, 2])
def test_gaussian_blocks_have_infinite_dof(seed):
    dof, nll, gauss = _dof_case(seed, 0.0)
    best = min(nll(g) for g in np.geomspace(2.5, 1000.0, 400))
    assert best >= gauss - 1.0 and dof == np.inf


def test_the_heaviest_tails_read_the_smallest_dof_searched():
    dof, nll, _ = _dof_case(0, 0.7, n=400)
    assert dof == pytest.approx(2.5, rel=1e-3) and nll(2.5) < nll(2.6)


# the fits: 4 runs (the fewest), GD up to GD_MIN_HI, tiny chains
SPEED4, GD4 = np.array([0.5, 1.0, 0.5, 1.0]), np.array([0.5, 0.5, 1.0, 1.0])
FAST = {"n_iter": 2, "tune": False, "seed": 0}


def _quiet(fit, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit(*args, **kwargs)


def test_the_window_emulator_fits_the_log_variance_of_the_last_1000_samples():
    rng = np.random.default_rng(4)
    accel = rng.standard_normal((4, 1500)) * np.array([1.0, 2.0, 3.0, 4.0])[:, None]
    accel[:, :500] *= 100.0  # outside the window
    accel[:, 100] = np.nan
    em = _quiet(fit_window_emulator, SPEED4, GD4, accel, noise_std=0.1, **FAST)
    np.testing.assert_allclose(em.y[:, 0], np.log(np.var(accel[:, -1000:], axis=1)), rtol=1e-12)
    assert em.metadata["feature"] == control.PAPER_WINDOW.to_dict()
    lam = em.priors.lamWs
    assert (lam.a, lam.b, lam.lower, lam.upper) == (1.0, 1e-3, 1.0, 1e5)
    exact = _quiet(fit_window_emulator, SPEED4, GD4, accel[:, 500:], noise_std=0.1, **FAST)
    np.testing.assert_allclose(exact.y, em.y, rtol=1e-12)  # exactly 1,000 samples
    for bad in (accel[:, 501:], np.where(np.arange(1500) == 600, np.nan, accel)):
        with pytest.raises(ControlError, match=">= 1000 finite samples per run"):
            fit_window_emulator(SPEED4, GD4, bad, noise_std=0.1, **FAST)
    with pytest.raises(ControlError, match=r"metadata\['feature'\] = .* differs"):
        fit_window_emulator(SPEED4, GD4, accel, noise_std=0.1, metadata={"feature": {}}, **FAST)


def _band_runs():
    """15 runs (5 speeds x 3 GDs) of 2,000 samples: two batches of 8 blocks of 125."""
    rng = np.random.default_rng(0)
    speed, gd = np.repeat([0.6, 0.9, 1.2, 1.5, 1.8], 3), np.tile([200.0, 400.0, 600.0], 5)
    return speed, gd, rng.standard_normal((15, 2000)) * np.sqrt(gd * speed)[:, None] / 10


def test_the_band_emulator_fits_the_run_means_and_records_the_scatter():
    speed, gd, accel = _band_runs()
    em = _quiet(fit_band_emulator, speed, gd, accel, noise_std=0.3, **FAST)
    spec = control.FeatureSpec()
    st = block_statistics(accel, spec)  # batches of 8, as the fit's default
    np.testing.assert_array_equal(em.y, st.mean)
    assert em.p_u == 8  # the default n_pc
    assert em.metadata["feature"] == spec.to_dict()
    assert em.metadata["block_scatter"] == block_scatter(speed, st).to_dict()
    assert em.metadata["noise_std"] == 0.3
    with pytest.raises(ControlError, match=r"metadata\['block_scatter'\] = .* differs"):
        fit_band_emulator(speed, gd, accel, noise_std=0.3, metadata={"block_scatter": 1}, **FAST)
    with pytest.raises(ControlError, match="feature must be a control.FeatureSpec"):
        fit_band_emulator(speed, gd, accel, noise_std=0.3, feature="band", **FAST)


def test_the_fewest_runs_and_the_boundary_values_are_accepted_or_refused_as_documented():
    accel = np.random.default_rng(5).standard_normal((4, 1000))
    em = _quiet(fit_window_emulator, SPEED4, GD4, accel, noise_std=0.0, **FAST)  # 4 runs, GD 1
    assert em.m == 4
    with pytest.raises(ControlError, match="noise_std must be"):
        fit_window_emulator(SPEED4, GD4, accel, noise_std=np.inf, **FAST)
    with pytest.raises(ControlError, match=r"Then gd \* 1e6, in \[900000, 950000\]"):
        fit_window_emulator(SPEED4, np.array([0.9, 0.9, 0.95, 0.95]), accel, noise_std=0.1)
    with pytest.raises(ControlError, match=r"metadata\['noise_std'\] = array"):  # not comparable
        fit_window_emulator(SPEED4, GD4, accel, noise_std=0.3,
                            metadata={"noise_std": np.array([0.3, 0.3])})  # fmt: skip
