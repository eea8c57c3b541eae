"""control.observation_model against closed forms and at the edges of its checks, pinned where a
mutation run of the module (session 87) changed behaviour without a test failing: the block
likelihood with all its constants (docs/closed-loop.md: a Gaussian or Student-t block law about
the emulator's mean), and the scatter's and the mean table's checks."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from control import ControlError
from control.observation_model import MAX_TABLE_NODES, BlockScatter, ObservationModel

SPEED = (0.5, 2.0)
GD = (100.0, 600.0)
COV = np.array([[[0.04, 0.01], [0.01, 0.09]], [[0.16, -0.02], [-0.02, 0.25]]])  # at 0.5, 2 m/s


def mean_feature(v, gd):
    """A 2-output emulator mean, linear in speed (so the model's table interpolates it exactly)."""
    v, gd = np.asarray(v, float), np.asarray(gd, float)
    return np.stack([np.log(gd) + 0.3 * v, 2.0 - 0.5 * v], axis=-1)


def stand_in(k: int = 2):
    """The attributes ObservationModel reads of a gpmsa Emulator (speed x, GD t, k outputs)."""
    return SimpleNamespace(
        p=1, q=1, l_sim=k, x_names=["v"], t_names=["GD"], domain={"v": SPEED, "GD": GD},
        predict_mean=lambda v, g: np.tile(mean_feature(v, g)[..., :1], (1, k)) if k != 2
        else mean_feature(v, g),
    )  # fmt: skip


def scatter(dof=np.inf):
    return BlockScatter(np.array(SPEED), COV, dof)


@pytest.mark.parametrize("dof", [np.inf, 7.0])
@pytest.mark.parametrize("v", [0.5, 0.6, 1.1, 2.0])
def test_loglik_is_the_block_laws_log_density_with_all_its_constants(dof, v):
    """log p(y | GD) = log N(y; mu(v, GD), Sigma(v)) (nu = inf) or log t_nu(...) at each GD
    node, mu and Sigma(v) linear in v between the table's and the scatter's nodes (speed nodes
    0.5, 1, 1.5, 2 m/s: the first and last intervals too)."""
    model = ObservationModel(stand_in(), scatter(dof), n_grid=16, n_speed=4)
    y = np.array([5.6, 1.3])
    a = (v - SPEED[0]) / (SPEED[1] - SPEED[0])
    sigma = (1 - a) * COV[0] + a * COV[1]
    mu = mean_feature(np.full(model.gd.size, v), model.gd)
    if np.isinf(dof):
        expected = [stats.multivariate_normal.logpdf(y, m, sigma) for m in mu]
    else:
        expected = [stats.multivariate_t.logpdf(y, m, sigma, df=dof) for m in mu]
    assert np.allclose(model.loglik(y, v), expected, rtol=0, atol=1e-10)
    assert np.allclose(model.gd, np.geomspace(*GD, 16))


def test_a_speed_rounded_past_the_domain_edge_reads_as_the_edge():
    """`within` takes a speed 1e-9 of the width past an end (rounding): it reads the end's mean
    and Sigma, bit for bit, not an extrapolation."""
    model = ObservationModel(stand_in(), scatter(), n_grid=16, n_speed=4)
    y, past = np.array([5.6, 1.3]), 0.5e-9 * (SPEED[1] - SPEED[0])
    assert np.array_equal(model.loglik(y, SPEED[1] + past), model.loglik(y, SPEED[1]))
    assert np.array_equal(model.loglik(y, SPEED[0] - past), model.loglik(y, SPEED[0]))


def test_n_speed_needs_two_nodes_and_the_table_at_most_max_table_nodes():
    emu = stand_in(k=1)
    k1 = BlockScatter(np.array(SPEED), np.array([[[0.04]], [[0.09]]]))
    with pytest.raises(ControlError, match="n_speed must be an integer >= 2"):
        ObservationModel(emu, k1, n_grid=16, n_speed=1)
    assert ObservationModel(emu, k1, n_grid=16, n_speed=2).speed.tolist() == list(SPEED)
    with pytest.raises(ControlError, match="above MAX_TABLE_NODES"):
        ObservationModel(emu, k1, n_grid=1001, n_speed=1000)
    at_most = ObservationModel(emu, k1, n_grid=MAX_TABLE_NODES // 1000, n_speed=1000)
    assert at_most.gd.size * at_most.speed.size == MAX_TABLE_NODES


def test_a_scatter_needs_increasing_speed_nodes_and_square_covariances():
    cov3 = np.stack([COV[0], COV[0], COV[1]])
    with pytest.raises(ControlError, match="speed must be >= 2 increasing finite nodes"):
        BlockScatter(np.array([0.5, 0.5, 2.0]), cov3)  # a repeated node
    with pytest.raises(ControlError, match=r"cov must have shape \(2, K, K\)"):
        BlockScatter(np.array(SPEED), np.zeros((2, 2, 3)))


def test_the_symmetry_check_is_relative_to_each_nodes_own_size():
    """Asymmetry is judged against each node's largest entry (1e-10 of it): the same matrices
    in any unit (x 1e-8, x 1e8) read the same, and a node is not judged by a larger one."""
    skew = np.array([[0.0, 1e-12], [0.0, 0.0]])  # 1e-12 of an entry ~0.1: round-off, taken
    for unit in (1e-8, 1.0, 1e8):
        assert BlockScatter(np.array(SPEED), (COV + skew) * unit).cov.shape == (2, 2, 2)
    lopsided = np.array([[[0.04, 0.01], [0.01 + 1e-9, 0.09]], np.eye(2) * 1e4])
    with pytest.raises(ControlError, match="cov must hold symmetric matrices"):
        BlockScatter(np.array(SPEED), lopsided)  # 1e-8 of its own size, 1e-13 of the other's
    for unit in (1e-8, 1e8):
        with pytest.raises(ControlError, match="cov must hold symmetric matrices"):
            BlockScatter(np.array(SPEED), (COV + 1e3 * skew) * unit)


def test_the_remembered_last_block_answers_only_the_same_block():
    """The last (y, v) is remembered (the BCR asks twice): an integer y asked again gets the
    same answer, and a y of another shape with the same bytes is still refused."""
    model = ObservationModel(stand_in(), scatter(), n_grid=16, n_speed=4)
    y = np.array([5, 1])
    first = model.loglik(y, 1.1)
    assert np.array_equal(model.loglik(y, 1.1), first)
    assert np.array_equal(first, model.loglik(y.astype(float), 1.1))
    with pytest.raises(ControlError, match=r"y must be 2 finite numbers \(K,\)"):
        model.loglik(y.astype(float)[None, :], 1.1)


def test_band_gain_reads_the_level_offset_at_the_nearest_gd_as_a_gain():
    """exp(offset / 2), offset the bands' mean log-power difference from the emulator's mean at
    the GD node where it is smallest: 1 at a GD node, 0.1 for a block 100 times quieter in power
    than the smoothest GD, 10 for one 100 times louder than the roughest."""
    model = ObservationModel(stand_in(), scatter(), n_grid=16, n_speed=4)
    v = 1.1
    mu = mean_feature(np.full(model.gd.size, v), model.gd)
    for bands in (slice(0, 1), slice(0, 2)):  # GD moves channel 0 only
        assert model.band_gain(mu[5], v, bands) == pytest.approx(1.0, abs=1e-12)
        quiet, loud = mu[0] - 2 * np.log(10), mu[-1] + 2 * np.log(10)
        assert model.band_gain(quiet, v, bands) == pytest.approx(0.1, rel=1e-12)
        assert model.band_gain(loud, v, bands) == pytest.approx(10.0, rel=1e-12)
