"""examples/ball_drop.py: its physics, and the worked example end to end (every figure saved)."""

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tests._examples import load_example

FIGURES = ["autocorrelation.png", "data.png", "emulator_held_out.png", "emulator_loo.png",
           "obs_projection.png", "pc_basis.png", "prediction.png", "sensitivity.png",
           "theta_pairs.png", "traces.png"]  # fmt: skip


def load_script():
    return load_example("ball_drop")


def test_simulator_is_the_closed_form_of_quadratic_drag():
    bd = load_script()
    R, Cd, g = 0.07, 0.8, 9.5
    k = 3 * bd.RHO_AIR * Cd / (8 * bd.RHO_BALL * R)
    sol = solve_ivp(lambda _, s: [s[1], g - k * s[1] ** 2], (0, 10), [0, 0], dense_output=True,
                    rtol=1e-11, atol=1e-12)  # fmt: skip
    t = bd.simulator([R], [Cd], [g])[0]
    np.testing.assert_allclose(sol.sol(t)[0], bd.HEIGHTS, rtol=1e-7)


def test_the_real_world_is_slower_than_the_simulator_at_its_own_cd_and_g():
    """Buoyancy, linear drag and the stopwatch delay all add time: the discrepancy is positive
    and at least the 0.04 s delay at every height."""
    bd = load_script()
    for R in (0.05, 0.19):
        sim = bd.simulator([R], [bd.WORLD["Cd"]], [bd.WORLD["g"]])[0]
        gap = bd.real_world(R) - sim
        assert np.all(gap >= bd.WORLD["delay"]) and np.all(np.diff(gap) > 0)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_small_run_saves_every_figure_and_the_summary(tmp_path):
    """Two sweeps of 12 runs (one run of the example, 6 s, serves both checks): every figure
    and the summary, which is JSON with null for an ESS that two draws leave undefined."""
    summary = load_script().main(["--out", str(tmp_path), "--n-iter", "2", "--runs", "12"])
    assert sorted(p.name for p in tmp_path.glob("*.png")) == FIGURES
    assert set(summary["posterior"]) == {"Cd", "g", "lamOs", "lamVz", "betaV"}
    assert set(summary["sensitivity"]) == {"R", "Cd", "g"}

    def refuse(name):
        raise AssertionError(f"summary.json holds {name}, which JSON does not allow")

    written = json.loads((tmp_path / "summary.json").read_text(), parse_constant=refuse)
    assert written["figures"] == FIGURES
    assert written["posterior"]["Cd"]["n_draws"] == 2
    assert written["posterior"]["Cd"]["ess"] is None  # fewer draws than an ESS needs


@pytest.mark.slow
def test_default_run_predicts_the_unseen_balls(tmp_path):
    """At the default settings the 90 % band of a new observation covers most of the 60 measured
    times of three balls nobody dropped, where the simulator alone (at the posterior-mean theta,
    no discrepancy) misses most of them; the emulator itself is accurate (held-out runs)."""
    summary = load_script().main(["--out", str(tmp_path)])
    p = summary["prediction_held_out_balls"]
    assert p["y_band90_coverage"] >= 0.75
    assert p["simulator_at_posterior_mean_theta_band90_coverage"] < 0.5
    assert summary["emulator"]["held_out_rmse_s"] < 0.5 * summary["world"]["noise_sd"]
