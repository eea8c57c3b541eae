"""Bad input to the online calibration, the emulator's construction and the torch backend:
refused with a GPMSAError naming the problem, never read silently wrong."""

import warnings

import numpy as np
import pandas as pd
import pytest

import gpmsa
from gpmsa import GPMSAError
from tests._extras import TORCH
from tests.gpmsa._backend_cases import multi_data

PARAMS = {"betaU": [[2.0], [1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}


def _two_input_emulator() -> gpmsa.Emulator:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 2)), rng.uniform(size=(30, 1))
    y = 2 * x[:, :1] + 0.5 * x[:, 1:] + t
    sim = gpmsa.SimData(x=x, t=t, y=y, x_names=["a", "b"], t_names=["t"])
    return gpmsa.Emulator.from_params(sim, PARAMS)


def test_tables_of_inputs_are_read_by_column_name_everywhere():
    emu = _two_input_emulator()
    table = pd.DataFrame({"a": [0.2, 0.5], "b": [0.9, 0.3]})
    y = 2 * table["a"].to_numpy()[:, None] + 0.5 * table["b"].to_numpy()[:, None] + 0.4
    swapped = table[["b", "a"]]
    one = gpmsa.Calibrator(emu, seed=0).update(table, y).mean("t")
    assert gpmsa.Calibrator(emu, seed=0).update(swapped, y).mean("t") == one
    assert abs(one - 0.4) < 0.05
    with pytest.raises(GPMSAError, match=r"x_obs has the columns \['c', 'b'\]; expected"):
        gpmsa.Calibrator(emu).update(table.rename(columns={"a": "c"}), y)
    # a joint fit's ObsData and a SimData made from tables: by name too
    sim = gpmsa.SimData(x=pd.DataFrame(emu.x_unit, columns=["b", "a"]), t=emu.t_unit, y=emu.y,
                        x_names=["a", "b"], t_names=["t"])  # fmt: skip
    np.testing.assert_array_equal(sim.x, emu.x_unit[:, ::-1])
    named = gpmsa.SimData(x=pd.DataFrame(emu.x_unit, columns=["a", "b"]), t=emu.t_unit, y=emu.y)
    assert named.x_names == ("a", "b")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = _two_input_emulator()
        data = gpmsa.SimData(x=base.x_unit, t=base.t_unit, y=base.y, x_names=["a", "b"])
        fits = [gpmsa.fit(data, gpmsa.ObsData(x=obs_x, y=y), n_iter=30, tune=False, seed=0)
                for obs_x in (table, swapped)]  # fmt: skip
    np.testing.assert_array_equal(fits[0].calibration["theta"], fits[1].calibration["theta"])


def test_from_params_refuses_transposed_or_unknown_parameters():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    s = np.linspace(0, 1, 6)
    sim = gpmsa.SimData(x=x, t=t, y=np.outer(x[:, 0], 1 + s) + np.outer(t[:, 0], s**2), index=s)
    base = gpmsa.Emulator.from_params(sim, PARAMS | {"betaU": [[1.0], [1.0]]}, n_pc=1)
    p_u = 3
    betaU = np.array([[1.0, 2.0, 3.0], [0.5, 0.6, 0.7]])
    params = {"betaU": betaU, "lamUz": [1.0] * p_u, "lamWs": [1e4] * p_u, "lamWOs": [1e4]}
    emu = gpmsa.Emulator.from_params(sim, params, n_pc=p_u)
    np.testing.assert_array_equal(emu.params["betaU"], betaU)
    flat = gpmsa.Emulator.from_params(sim, params | {"lamUz": [[1.0] * p_u]}, n_pc=p_u)
    assert flat.params["lamUz"].shape == (p_u,)  # (1, p_u), as SEPIA stores it
    transposed = r"params\['betaU'\] must have shape \(2, 3\), got \(3, 2\)"
    with pytest.raises(GPMSAError, match=transposed):
        gpmsa.Emulator.from_params(sim, params | {"betaU": betaU.T}, n_pc=p_u)
    with pytest.raises(GPMSAError, match=r"params has unknown keys \['foo'\]"):
        gpmsa.Emulator.from_params(sim, params | {"foo": 1.0}, n_pc=p_u)
    with pytest.raises(GPMSAError, match="params must be a dict"):
        gpmsa.Emulator.from_params(sim, None)
    assert base.p_u == 1


def _fitted():
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    return gpmsa.fit(gpmsa.SimData(x=x, t=t, y=x + t), n_iter=40, tune=False, seed=0)


@TORCH
def test_calibrator_refuses_the_emulators_draws_off_numpy():
    # a constraint off numpy: taken on torch, refused on pyro (test_walkthrough_s74.py)
    with pytest.raises(GPMSAError, match="emulator_params='draws' needs backend='numpy'"):
        gpmsa.Calibrator(_fitted(), method="mcmc", backend="torch", emulator_params="draws")


def test_calibrator_refuses_at_construction_what_every_update_would():
    fitted = _fitted()
    with pytest.raises(GPMSAError, match=r"drop mcmc_options\['fast'\] = False"):
        gpmsa.Calibrator(fitted, method="mcmc", emulator_params="draws",
                         mcmc_options={"fast": False})  # fmt: skip
    mcmc = gpmsa.Calibrator(fitted, method="mcmc",
                            mcmc_options={"seed": 1, "n_samples": 200, "n_burn": 50})  # fmt: skip
    with pytest.raises(GPMSAError, match="prior= on the MCMC path must be a callable"):
        mcmc.update([[0.5]], [[0.9]], prior=np.zeros(129))
    # this update's seed wins over mcmc_options' seed
    a, b = (mcmc.update([[0.5]], [[0.9]], seed=s).samples["t0"] for s in (9, 10))
    again = mcmc.update([[0.5]], [[0.9]], seed=9).samples["t0"]
    assert not np.array_equal(a, b) and np.array_equal(a, again)


def test_grid_priors_have_the_grids_shape():
    rng = np.random.default_rng(2)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 2))
    sim = gpmsa.SimData(x=x, t=t, y=x + t[:, :1] - t[:, 1:], t_names=["u", "w"])
    emu = gpmsa.Emulator.from_params(sim, PARAMS | {"betaU": [[1.0], [1.0], [1.0]]})
    cal = gpmsa.Calibrator(emu, n_grid=9, seed=0)
    table = np.zeros((9, 9))
    table[:, :4] = -50.0  # the second parameter's low half unlikely: rows are the first
    post = cal.update([[0.5]], [[0.5]], prior=table)
    np.testing.assert_allclose(
        post.mean("w"), cal.update([[0.5]], [[0.5]], prior=table.reshape(-1)).mean("w")
    )
    assert post.mean("w") > 0.5
    with pytest.raises(GPMSAError, match=r"of shape \(81,\) or \(9, 9\) .*got \(81, 1\)"):
        cal.update([[0.5]], [[0.5]], prior=table.reshape(81, 1))


def test_a_collinear_mean_basis_and_a_non_finite_one_are_refused_by_fit():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    sim = gpmsa.SimData(x=x, t=t, y=x + t)
    with pytest.raises(GPMSAError, match="collinear on the simulation design: its 2 columns have "
                                         "rank 1"):  # fmt: skip
        gpmsa.fit(sim, n_iter=20, mean_basis=lambda z: np.ones((len(z), 2)))
    with pytest.raises(GPMSAError, match="mean_basis returned NaN, inf or values beyond"):
        gpmsa.fit(sim, n_iter=20, mean_basis=lambda z: np.full((len(z), 1), np.nan))


@TORCH
def test_torch_devices_and_float32_fits():
    sim, obs = multi_data()
    for device in ("gpu", "mps", 5, None):
        with pytest.raises(GPMSAError, match="device must be 'cpu' or 'cuda'"):
            gpmsa.fit(sim, n_iter=10, backend="torch", device=device, tune=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=40, backend="torch", seed=2, tune=False,
                        dtype="float32", discrepancy="linear",
                        fixed={"lamWOs": 1234.5678})  # fmt: skip
    assert emu.params["lamWOs"][0] == 1234.5678  # exactly, not its float32 neighbour
    for name, value in emu.params.items():  # a point estimate within its draws' range
        draws = emu.draws[name]
        assert np.all(draws.min(axis=0) <= value) and np.all(value <= draws.max(axis=0)), name
    assert all(v.dtype == np.float64 for v in emu.draws.values())


def test_a_malformed_expected_hash_is_named(tmp_path):
    emu = _two_input_emulator()
    path = emu.save(tmp_path / "e.gpmsa")
    with pytest.raises(GPMSAError, match="sha256 must be 64 hexadecimal digits, got 'xyz'"):
        gpmsa.load(path, sha256="xyz")
    with pytest.raises(GPMSAError, match="folds must be None .* got 2.0"):
        gpmsa.cross_validate(emu, folds=2.0, draws=False)


def _vector_sim():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    s = np.linspace(0, 1, 8)
    return gpmsa.SimData(x=x, t=t, y=np.outer(x[:, 0], 1 + s) + np.outer(t[:, 0], s**2), index=s)


def test_a_fixed_matrix_in_another_layout_is_refused_not_reshuffled():
    sim, betaU = _vector_sim(), np.array([[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]])
    with pytest.raises(GPMSAError, match=r"fixed\['betaU'\] must be a scalar or have shape "
                                         r"\(2, 3\), got \(3, 2\)"):  # fmt: skip
        gpmsa.fit(sim, n_iter=20, n_pc=3, fixed={"betaU": betaU.T})
    emu = gpmsa.fit(sim, n_iter=20, n_pc=3, fixed={"betaU": betaU})
    np.testing.assert_array_equal(emu.params["betaU"], betaU)


def test_mean_basis_callables_get_a_copy_and_must_be_consistent():
    sim = _vector_sim()

    def zeroes_its_input(z):
        z *= 0.0
        return np.ones((len(z), 1))

    edited = gpmsa.fit(sim, n_iter=30, tune=False, seed=0, mean_basis=zeroes_its_input)
    plain = gpmsa.fit(sim, n_iter=30, tune=False, seed=0, mean_basis="constant")
    np.testing.assert_allclose(edited.predict([[0.3]], [[0.7]])[0],
                               plain.predict([[0.3]], [[0.7]])[0])  # fmt: skip

    def more_columns_for_one_point(z):
        return np.column_stack([np.ones(len(z))] + ([z[:, 0]] if len(z) == 1 else []))

    emu = gpmsa.fit(sim, n_iter=20, mean_basis=more_columns_for_one_point)
    with pytest.raises(GPMSAError, match="returned 2 columns for n = 1 points, but 1 on the"):
        emu.predict([[0.5]], [[0.5]])
    for basis, match in (
        (lambda z: 1e200 * np.ones((len(z), 1)), "values beyond 1e"),
        (lambda z: np.ones((len(z), 0)), r"k >= 1, for n = 2 points, got shape \(2, 0\)"),
        (lambda z: np.ones((len(z), 1)) * (1 + 1j), "must return real numbers"),
    ):
        with pytest.raises(GPMSAError, match=match):
            gpmsa.fit(sim, n_iter=20, mean_basis=basis)


def test_callables_keep_several_chains_in_this_process():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 2))
    sim = gpmsa.SimData(x=x, t=t, y=x + t[:, :1] + t[:, 1:])
    obs = gpmsa.ObsData(x=[[0.2], [0.5]], y=[[0.9], [1.1]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a short fit: not converged
        emu = gpmsa.fit(
            sim, obs, n_iter=20, n_chains=2, seed=0, constraint=lambda th: bool(th[0] + th[1] < 1.2)
        )  # a lambda: no pickle
    assert np.all(emu.calibration["theta_native"].sum(axis=1) < 1.2)
    msg = "mean_basis is a callable of this process: it cannot go to executor"
    with pytest.raises(GPMSAError, match=msg):
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(1) as ex:
            gpmsa.fit(sim, n_iter=20, n_chains=2, mean_basis=lambda z: np.ones(len(z)),
                      executor=ex)  # fmt: skip


def test_a_categorical_theta_start_is_a_level_the_end_levels_included():
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(30, 1))
    level = (np.arange(30) % 2).astype(float)[:, None]
    emu = gpmsa.fit(gpmsa.SimData(x=x, t=level, y=x + level, t_categorical=[0]), n_iter=40,
                    tune=False, seed=0)  # fmt: skip
    xo, yo, not_zero = [[0.3], [0.6]], [[1.3], [1.6]], (lambda th: th[0] != 0)
    post = gpmsa.calibrate(emu, xo, yo, constraint=not_zero, theta_init=[1], n_samples=60,
                           n_burn=10, seed=0)  # fmt: skip
    assert set(np.unique(post.samples["t0"])) == {1.0}
    with pytest.raises(GPMSAError, match=r"t0 must be one of its training levels \[0, 1\], got"):
        gpmsa.calibrate(emu, xo, yo, constraint=not_zero, theta_init=[0.9], n_samples=60, n_burn=10)


def test_study_labels_and_per_model_errors_name_the_model():
    from tests.gpmsa._study_cases import emulator, observations

    emu = emulator()
    x, y = observations(0.4, 3, 0.05, np.random.default_rng(0))
    for labels, match in ((["a\n", "b"], "model label 'a\\\\n'"), ("ab", "labels must be a seq"),
                          (["A", "a"], "also in more than case")):  # fmt: skip
        with pytest.raises(GPMSAError, match=match):
            gpmsa.calibrate_study([emu, emu], [x, x], [y, y], labels=labels, shared=["t"],
                                  n_samples=20, n_burn=5)  # fmt: skip
    with pytest.raises(GPMSAError, match=r"model 'second': y_obs must have one row per x_obs"):
        gpmsa.calibrate_study([emu, emu], [x, x], [y, y[:2]], labels=["first", "second"],
                              shared=["t"], n_samples=20, n_burn=5)  # fmt: skip
    with pytest.warns(UserWarning, match="lam_a=2.0 and lam_b=0.001 set the gamma prior"):
        gpmsa.HyperPriors(lam_a=2.0)
