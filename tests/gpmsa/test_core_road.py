"""The road case: the joint GD posterior agrees with GPM/SA (Octave) and SEPIA within MC error."""

import json

import numpy as np
import pytest

import gpmsa


@pytest.fixture(scope="module")
def case(data_dir_module):
    d = np.load(data_dir_module / "case.npz")
    ref = json.loads((data_dir_module / "reference_posteriors.json").read_text())
    sim = gpmsa.SimData(x=d["v"], t=d["GD"], y=d["f"], x_names=["v"], t_names=["GD"])
    obs = gpmsa.ObsData(x=d["v_obs"][:, None], y=d["f_obs"][:, None])
    return sim, obs, ref


@pytest.fixture(scope="module")
def data_dir_module():
    from pathlib import Path

    return Path(__file__).parents[1] / "data"


def check_against_references(emu, ref):
    """|ours - ref| < 4 combined MC standard errors, ours from the chain's ESS."""
    theta = emu.calibration["theta_native"][:, 0]
    ess = emu.diagnostics["theta"]["ess"][0]
    mean, sd = theta.mean(), theta.std(ddof=1)
    assert ess > 50, f"ESS {ess} too small for a meaningful comparison"
    for key, ref_ess in (("sepia_full_joint", ref["sepia_full_joint"]["ess"]),
                         ("gpmsa_matlab_octave_full_joint", 774)):  # fmt: skip
        r = ref[key]
        se_mean = np.hypot(sd / np.sqrt(ess), r["sd"] / np.sqrt(ref_ess))
        se_sd = np.hypot(sd / np.sqrt(2 * ess), r["sd"] / np.sqrt(2 * ref_ess))
        assert abs(mean - r["mean"]) < 4 * se_mean, (key, mean, r["mean"], se_mean)
        assert abs(sd - r["sd"]) < 4 * se_sd, (key, sd, r["sd"], se_sd)
    return mean, sd, ess


def test_joint_fit_short_run_matches_references(case):
    sim, obs, ref = case
    emu = gpmsa.fit(sim, obs=obs, n_iter=2500, seed=2024)
    check_against_references(emu, ref)
    # emulator parameters near SEPIA's posterior means (loose: short chain)
    sep = ref["sepia_full_joint_posterior_means_unit_scale"]
    assert emu.params["betaU"][0, 0] == pytest.approx(sep["betaU"][0], rel=0.3)
    assert emu.params["lamUz"][0] == pytest.approx(sep["lamUz"][0], rel=0.5)
    assert emu.settings["n_burn"] == 500 and emu.n_draws <= 1000


@pytest.mark.slow
def test_joint_fit_long_run_matches_references(case):
    sim, obs, ref = case
    emu = gpmsa.fit(sim, obs=obs, n_iter=30_000, n_chains=2, seed=7)
    mean, sd, ess = check_against_references(emu, ref)
    assert ess > 1500
    assert max(emu.diagnostics["theta"]["rhat"]) < 1.02


def test_from_params_at_sepia_means_predicts_training_runs(case):
    sim, _, ref = case
    params = ref["sepia_calibration_only"]["fixed_emulator_params_unit_scale"]
    emu = gpmsa.Emulator.from_params(sim, params, metadata={"case": "road"})
    assert emu.params["betaU"].shape == (2, 1) and emu.params["lamWOs"].shape == (1,)
    assert emu.n_draws == 0 and emu.metadata == {"case": "road"}
    mean, var = emu.predict(sim.x[:20], sim.t[:20])
    resid = (sim.y[:20] - mean) / np.sqrt(var)
    # at the training points the mean interpolates up to the nugget; residuals are small
    assert np.all(np.abs(resid) < 3)
    loo = emu.loo()
    assert 0.85 < loo.coverage95 <= 1.0
    assert abs(np.mean(loo.z)) < 0.3 and 0.6 < np.std(loo.z) < 1.4
    # GD posterior would need calibration; here: the emulator is smooth in GD
    m1, _ = emu.predict([[1.25]], [[400.0]])
    m2, _ = emu.predict([[1.25]], [[450.0]])
    assert m2[0, 0] > m1[0, 0]
