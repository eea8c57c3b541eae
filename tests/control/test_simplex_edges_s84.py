"""Simplex edges pinned to its docstrings (mutation testing found each one free): a user's
K_p, GD exactly at GD_max, the paper law at GD_min, a risk posture without a posterior, NaN GD."""

import numpy as np
import pytest

from control import ControlError, Estimate, Simplex


def ok_estimate(gd: float, position: float = 5.0) -> Estimate:
    return Estimate(time=1.0, position=position, status="ok", gd_mean=gd, gd_sd=1.0,
                    interval=(gd - 2.0, gd + 2.0))  # fmt: skip


def test_a_users_kp_sets_the_slope_of_the_laws():
    """v = v_max - K_p (GD - GD_min) clipped to [v_safe, v_max] ("linear"), and eq. 8,
    K_p ((GD_min + GD_max) / 2 - GD) clipped to [0, v_max] from GD_min on ("paper")."""
    linear = Simplex(kp=0.005, speed_step_mps=0.0)
    assert linear.gain == 0.005
    assert linear.performance_speed(300.0) == pytest.approx(2.0 - 0.005 * 50.0)
    paper = Simplex(law="paper", kp=0.01, speed_step_mps=0.0)
    assert paper.performance_speed(260.0) == pytest.approx(0.01 * (300.0 - 260.0))
    assert paper.performance_speed(250.0) == pytest.approx(0.01 * 50.0)  # at GD_min: eq. 8
    assert paper.performance_speed(249.0) == 2.0  # v_max below GD_min


def test_gd_max_itself_is_performance_mode_at_v_safe():
    """Safety mode starts above GD_max; the linear law reaches v_safe at GD_max."""
    command = Simplex().command(ok_estimate(350.0))
    assert (command.mode, command.speed, command.reason) == ("performance", 1.0, "")
    assert Simplex().command(ok_estimate(350.0001)).mode == "safety"


def test_a_risk_posture_without_a_posterior_is_safety_mode():
    command = Simplex(risk=0.1).command(ok_estimate(260.0))
    assert command.mode == "safety" and command.speed == 1.0
    assert "needs the posterior" in command.reason


@pytest.mark.parametrize("gd", [np.nan, "300", None])
def test_performance_speed_refuses_what_is_not_a_gd(gd):
    with pytest.raises(ControlError, match="gd must be a real number"):
        Simplex().performance_speed(gd)


@pytest.mark.parametrize("gd", [np.nan, np.inf, -np.inf, -5.0, 0.0])
def test_an_ok_estimate_whose_gd_is_not_a_roughness_is_safety_mode(gd):
    """No roughness reads below 0 or at 0, and none is infinite: safety mode, GD used NaN."""
    command = Simplex().command(ok_estimate(gd))
    assert command.mode == "safety" and command.speed == 1.0 and np.isnan(command.gd_used)


def test_a_smooth_road_is_top_speed():
    command = Simplex().command(ok_estimate(0.5))
    assert (command.mode, command.speed) == ("performance", 2.0)


def fault(time: float = 0.5) -> Estimate:
    return Estimate(time=time, position=4.0, status="sensor_fault", reason="stuck sensor")


@pytest.mark.parametrize("release_m", [0.5, 1.0])
def test_a_fault_ends_the_start_for_a_short_release_dwell(release_m):
    """With the release dwell, a fault ends the start's safety mode (which has no dwell): after
    it, performance mode again only once the law has read it over ``release_m`` metres of
    travel; an update without a finite position restarts the count."""
    run = Simplex(release_m=release_m, after_fault="resume").start()
    assert run.command(fault()).mode == "safety"
    modes = []
    for position in (5.0, np.nan, 5.1, 5.1 + release_m / 2, 5.1 + release_m):
        modes.append(run.command(ok_estimate(260.0, position=position)).mode)
    assert modes == ["safety"] * 4 + ["performance"]


def test_a_plausibility_at_latch_p_does_not_latch():
    """An "implausible" estimate latches only when its plausibility_p is below latch_p."""
    s = Simplex()
    at = Estimate(time=1.0, position=5.0, status="implausible", plausibility_p=s.latch_p)
    run = s.start()
    run.command(at)
    assert not run.latched
    run.command(Estimate(time=2.0, position=6.0, status="implausible",
                         plausibility_p=s.latch_p / 2))  # fmt: skip
    assert run.latched
