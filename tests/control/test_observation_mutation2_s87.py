"""control.observation_model's second mutation run (session 87: its sites past the likelihood
class): one block's likelihood at a grid node (`one_block_logliks`) against scipy's densities,
Sigma(v) between and beyond the scatter's own speed nodes, and the edges of the emulator checks."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats
from scipy.linalg import cholesky

from control import EmulatorMismatchError, FeatureSpec
from control.observation_model import (
    BlockScatter,
    ObservationModel,
    _cholesky_lower,
    check_emulator_inputs,
    check_feature_outputs,
    one_block_logliks,
    output_unit_slip,
)
from control.sensor_checks import MAX_SPEED_MPS

SPEED = (0.5, 2.0)
GD = (100.0, 600.0)
COV = np.array([[[0.04, 0.01], [0.01, 0.09]], [[0.16, -0.02], [-0.02, 0.25]]])  # at 0.5, 2 m/s


def mean_feature(v, gd):
    """A 2-output emulator mean, linear in speed (so the model's table interpolates it exactly)."""
    v, gd = np.asarray(v, float), np.asarray(gd, float)
    return np.stack([np.log(gd) + 0.3 * v, 2.0 - 0.5 * v + 0.1 * np.log(gd)], axis=-1)


def stand_in(**attrs):
    """The attributes ObservationModel reads of a gpmsa Emulator (speed x, GD t, 2 outputs)."""
    base = dict(p=1, q=1, l_sim=2, x_names=["v"], t_names=["GD"], domain={"v": SPEED, "GD": GD},
                predict_mean=mean_feature)  # fmt: skip
    return SimpleNamespace(**{**base, **attrs})


def log_density(y, mu, sigma, dof):
    """log N(y; mu, sigma) (dof inf) or log t_dof(y; mu, sigma), one row of mu at a time."""
    if np.isinf(dof):
        return np.array([stats.multivariate_normal.logpdf(y, m, sigma) for m in mu])
    return np.array([stats.multivariate_t.logpdf(y, m, sigma, df=dof) for m in mu])


@pytest.mark.parametrize("dof", [np.inf, 5.0])
@pytest.mark.parametrize("v", [0.8, 2.0])
def test_one_block_logliks_is_the_block_laws_log_density_up_to_a_constant(dof, v):
    """Row r: log p(y | GD) on ``gd`` of a block whose feature y is the emulator's mean at
    (v, gd[at[r]]), Sigma(v) interpolated in speed: scipy's density less a constant per row."""
    gd = np.geomspace(*GD, 9)
    at = (0, -1, 3)
    scatter = BlockScatter(np.array(SPEED), COV, dof)
    rows = one_block_logliks(stand_in(), scatter, v, gd, at)
    assert rows.shape == (3, 9)
    a = (v - SPEED[0]) / (SPEED[1] - SPEED[0])
    sigma = (1 - a) * COV[0] + a * COV[1]
    mu = mean_feature(np.full(gd.size, v), gd)
    for row, k in zip(rows, at, strict=True):
        expected = log_density(mu[k], mu, sigma, dof)
        assert np.argmax(row) == np.arange(gd.size)[k]
        assert np.allclose(row - row[k], expected - expected[k], rtol=0, atol=1e-10)


def test_one_block_logliks_reads_at_the_top_node_by_default():
    """``at`` defaults to the grid's last node (the top of the GD domain)."""
    gd = np.geomspace(*GD, 9)
    scatter = BlockScatter(np.array(SPEED), COV)
    top = one_block_logliks(stand_in(), scatter, 1.1, gd)
    assert top.shape == (1, 9) and np.argmax(top[0]) == 8
    assert np.array_equal(top, one_block_logliks(stand_in(), scatter, 1.1, gd, (-1,)))


@pytest.mark.parametrize(
    ("v", "node", "a"),
    [(0.5, 0, 0.0), (0.7, 0, 0.0), (0.8, 0, 0.0), (1.0, 0, 0.5), (1.2, 1, 0.0), (1.5, 1, 0.75),
     (1.6, 1, 1.0), (2.0, 1, 1.0)],
)  # fmt: skip
def test_sigma_is_linear_between_the_scatters_nodes_and_constant_beyond(v, node, a):
    """The scatter's speed nodes (0.8, 1.2, 1.6 m/s) need not be the emulator's: Sigma(v) is
    linear between them and the end node's beyond them (`BlockScatter`, `_interp_cov`)."""
    covs = np.stack([COV[0], 0.5 * (COV[0] + COV[1]) + np.diag([0.1, 0.0]), COV[1]])
    scatter = BlockScatter(np.array([0.8, 1.2, 1.6]), covs)
    model = ObservationModel(stand_in(), scatter, n_grid=16, n_speed=4)
    y = np.array([5.6, 1.9])
    sigma = (1 - a) * covs[node] + a * covs[node + 1]
    mu = mean_feature(np.full(model.gd.size, v), model.gd)
    expected = log_density(y, mu, sigma, np.inf)
    assert np.allclose(model.loglik(y, v), expected, rtol=0, atol=1e-10)


LOG, G = "log((m/s^2)^2)", "g"  # FeatureSpec.units()' log power and quantile channels


@pytest.mark.parametrize("label", ["gal", "Gal", "mg", "ln (cm/s^2)^2", "log (mm/s²)²"])
def test_gal_milli_g_and_a_log_power_in_cm_unbracketed_are_other_units(label):
    """`_output_units` knows gal and milli-g as accelerations, and a log power's unit need not
    be bracketed after the log: each is another unit than the feature's m/s^2 or g."""
    assert output_unit_slip(label, LOG) == "an acceleration in another unit than m/s^2"
    assert "where the feature's are in g" in output_unit_slip(label, G)


def test_a_log_power_in_m_s2_unbracketed_is_the_features_own_unit():
    assert output_unit_slip("ln (m/s^2)^2", LOG) == output_unit_slip("log m^2/s^4", LOG) == ""


def test_a_block_scatter_of_another_dimension_than_the_recorded_feature_is_refused():
    """The emulator's metadata ``block_scatter`` must be the recorded feature's (K, K) blocks."""
    feature = FeatureSpec(name="log_var")  # one output
    for k, ok in ((3, False), (1, True)):
        emu = SimpleNamespace(l_sim=1, metadata={"block_scatter": {"cov": np.ones((2, k, k))}})
        if ok:
            check_feature_outputs(emu, feature)
            continue
        with pytest.raises(EmulatorMismatchError, match="block_scatter is 3-dimensional but its "
                           "feature 'log_var' has 1 outputs"):  # fmt: skip
            check_feature_outputs(emu, feature)


def test_a_stand_in_without_input_names_or_domain_is_not_checked():
    """`check_emulator_inputs` checks only the attributes an object has."""
    check_emulator_inputs(SimpleNamespace(x_names=["v", "w"]))  # no t_names
    check_emulator_inputs(SimpleNamespace(t_names=["GD", "A"]))  # no x_names
    check_emulator_inputs(SimpleNamespace(x_names=["v"], t_names=["GD"]))  # no domain


@pytest.mark.parametrize(("x", "t"), [(["v", "payload"], ["GD"]), (["v"], ["GD", "A"])])
def test_a_second_known_input_or_parameter_is_refused(x, t):
    with pytest.raises(EmulatorMismatchError, match="one known input x, the speed"):
        check_emulator_inputs(SimpleNamespace(x_names=x, t_names=t))


def test_a_speed_domain_starting_above_max_speed_reads_as_gd_and_speed_swapped():
    """A lowest speed beyond MAX_SPEED_MPS (not at it) is refused naming both spans."""
    at_max = stand_in(domain={"v": (MAX_SPEED_MPS, 600.0), "GD": (0.5, 2.0)})
    check_emulator_inputs(at_max)
    swapped = stand_in(domain={"v": (100.0, 600.0), "GD": (0.5, 2.0)})
    with pytest.raises(EmulatorMismatchError, match=r"x = 'v' spans \[100, 600\], beyond any "
                       r".* its GD t = 'GD' spans \[0.5, 2\]: GD fitted as x"):  # fmt: skip
        check_emulator_inputs(swapped)


def test_the_factor_is_scipys_lower_cholesky_and_scipys_error_where_not_positive_definite():
    c = COV[0] + 0.01
    assert np.allclose(_cholesky_lower(c), cholesky(c, lower=True), rtol=0, atol=1e-15)
    for bad in ([[1.0, 2.0], [2.0, 1.0]], [[-1.0, 0.0], [0.0, 1.0]]):  # (LAPACK info 2, 1)
        with pytest.raises(np.linalg.LinAlgError):
            _cholesky_lower(np.array(bad))


@pytest.mark.parametrize("v", [0.6, 1.2, 1.9, 2.0])
def test_the_mean_is_linear_in_speed_between_the_tables_nodes(v):
    """mu(v, GD) is tabulated at n_speed nodes (0.5, 1, 1.5, 2 m/s) and interpolated linearly
    between the two about v (the module docstring): for a mean curved in speed, not the
    emulator's value at v nor an extrapolation from another interval."""

    def curved(s, gd):
        return mean_feature(s, gd) + np.stack([np.asarray(s, float) ** 2, 0 * gd], axis=-1)

    model = ObservationModel(stand_in(predict_mean=curved), BlockScatter(np.array(SPEED), COV),
                             n_grid=16, n_speed=4)  # fmt: skip
    lo = min(int((v - 0.5) / 0.5), 2)
    a = (v - 0.5) / 0.5 - lo
    at = [curved(np.full(model.gd.size, 0.5 + 0.5 * k), model.gd) for k in (lo, lo + 1)]
    mu = (1 - a) * at[0] + a * at[1]
    y = np.array([5.6, 1.9])
    sigma = (1 - (v - 0.5) / 1.5) * COV[0] + (v - 0.5) / 1.5 * COV[1]
    expected = log_density(y, mu, sigma, np.inf)
    assert np.allclose(model.loglik(y, v), expected, rtol=0, atol=1e-10)


def test_an_integer_block_with_the_last_blocks_bytes_is_not_the_last_block():
    """The remembered last block answers only the same numbers: an int64 y whose bytes are
    those of the last float y (values ~4.6e18) is its own block, far from every GD."""
    model = ObservationModel(stand_in(), BlockScatter(np.array(SPEED), COV), n_grid=16, n_speed=4)
    y = np.array([5.6, 1.9])
    near = model.loglik(y, 1.1)
    far = model.loglik(y.view(np.int64), 1.1)
    assert np.all(far < near.min() - 1e30)
