"""Simplex controller: the paper's band, the default continuous law, risk posture, faults."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy import stats

from control import FAULT_STATUSES, STATUSES, ControlError, Estimate, Simplex
from gpmsa import Posterior
from gpmsa.calibration.posterior import GridMarginal


def gaussian_estimate(mean: float, sd: float) -> Estimate:
    grid = np.linspace(200, 600, 801)
    marginal = GridMarginal.from_log_density(grid, stats.norm.logpdf(grid, mean, sd))
    post = Posterior(grids={"GD": marginal}, draw=lambda: {}, info={"names": ("GD",)})
    return Estimate(
        time=10.0,
        position=20.0,
        status="ok",
        gd_mean=post.mean("GD"),
        gd_sd=post.sd("GD"),
        interval=post.interval("GD", 0.9),
        posterior=post,
    )


def test_linear_law_matches_the_band_and_is_continuous_at_gd_max():
    s = Simplex()
    assert s.gain == pytest.approx(0.01)
    assert s.performance_speed(200) == pytest.approx(2.0)
    assert s.performance_speed(250) == pytest.approx(2.0)
    assert s.performance_speed(300) == pytest.approx(1.5)
    assert s.performance_speed(350 - 1e-9) == pytest.approx(s.v_safe)
    # The command steps neither up nor down where safety mode takes over.
    below, above = s.command(gaussian_estimate(349.9, 2)), s.command(gaussian_estimate(350.1, 2))
    assert below.mode == "performance" and above.mode == "safety"
    assert abs(below.speed - above.speed) < 0.01


def test_speed_never_increases_with_gd():
    s = Simplex()
    speeds = [s.command(gaussian_estimate(gd, 3)).speed for gd in np.linspace(210, 590, 60)]
    assert np.all(np.diff(speeds) <= 1e-12)
    assert min(speeds) == pytest.approx(s.v_safe) and max(speeds) == pytest.approx(s.v_max)


def test_paper_law_as_written_stops_the_robot_mid_band():
    s = Simplex(law="paper")
    assert s.performance_speed(250) == pytest.approx(2.0)
    assert s.performance_speed(300) == pytest.approx(0.0)  # eq. 8 literally
    assert s.performance_speed(340) == 0.0  # negative speeds are clipped
    assert s.command(gaussian_estimate(400, 2)).speed == pytest.approx(1.0)


def test_switch_law_is_two_speeds():
    s = Simplex(law="switch")
    assert s.command(gaussian_estimate(340, 2)).speed == 2.0
    assert s.command(gaussian_estimate(360, 2)).speed == 1.0
    with pytest.raises(ControlError, match=r"kp has no effect with law='switch'"):
        Simplex(law="switch", kp=0.01)  # it was ignored


def test_any_fault_means_safety_mode():
    s = Simplex()
    for status in ("filling", "sensor_fault", "out_of_domain", "stale", "calibration_failed"):
        cmd = s.command(Estimate(time=1.0, position=1.0, status=status, reason="x"))
        assert cmd.mode == "safety" and cmd.speed == s.v_safe and status in cmd.reason


def test_risk_posture_is_more_cautious_than_the_mean():
    est = gaussian_estimate(330, 30)  # mean inside the band, P(GD > 350) ~ 0.25
    assert Simplex().command(est).mode == "performance"
    assert Simplex(risk=0.1).command(est).mode == "safety"
    assert Simplex(risk=0.4).command(est).mode == "performance"


@given(mean=st.floats(260, 440), sd=st.floats(2, 60), alpha=st.floats(0.02, 0.5))
def test_risk_switches_exactly_when_prob_above_max_exceeds_alpha(mean, sd, alpha):
    est = gaussian_estimate(mean, sd)
    p = est.prob_above(350)
    if abs(p - alpha) < 1e-9:  # a tie: either mode is right
        return
    cmd = Simplex(risk=alpha).command(est)
    assert (cmd.mode == "safety") == (p > alpha)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"gd_min": 400}, "gd_min must be < gd_max"),
        ({"v_safe": 3.0}, "v_safe must be <= v_max"),
        ({"risk": 1.5}, "risk must be None or lie in"),
        ({"kp": -1}, "kp must be finite"),
        ({"law": "pid"}, "law must be one of"),
        ({"after_fault": "ignore"}, "after_fault must be one of"),
        ({"latch_p": 0.0}, "latch_p must lie in"),
        ({"v_max": float("nan")}, "v_max must be finite"),
        ({"speed_step_mps": -0.1}, r"speed_step_mps must lie in \[0, v_max\]"),
        ({"speed_step_mps": float("inf")}, "speed_step_mps must lie in"),
        ({"gd_min": "250"}, "Simplex.gd_min must be a real number"),
        ({"risk": "0.1"}, "Simplex.risk must be a real number or None"),
        ({"kp": True}, "Simplex.kp must be a real number or None"),
    ],
)
def test_bad_settings_raise(kwargs, match):
    with pytest.raises(ControlError, match=match):
        Simplex(**kwargs)


def bare_estimate(status: str, time: float = 1.0) -> Estimate:
    return Estimate(time=time, position=1.0, status=status, reason=f"why {status}")


def test_a_fault_latches_safety_mode_until_reset():
    run = Simplex().start()
    assert run.command(gaussian_estimate(260, 5)).mode == "performance"
    assert run.command(bare_estimate("sensor_fault", time=3.5)).speed == 1.0
    cmd = run.command(gaussian_estimate(260, 5))  # clean data again: the BCR is ok, the robot not
    assert run.latched and cmd.mode == "safety" and cmd.speed == 1.0
    assert "status 'sensor_fault' at 3.50 s (why sensor_fault)" in cmd.reason
    run.reset()
    assert not run.latched and run.command(gaussian_estimate(260, 5)).mode == "performance"


def test_an_implausible_block_latches_only_below_latch_p():
    def implausible(p: float) -> Estimate:
        return Estimate(time=1.0, position=1.0, status="implausible", plausibility_p=p)

    for p, latches in ((1e-9, False), (1e-13, True), (float("nan"), True)):
        run = Simplex().start()
        assert run.command(implausible(p)).mode == "safety"  # this block: safety mode anyway
        assert run.latched == latches
        assert (run.command(gaussian_estimate(260, 5)).mode == "safety") == latches


def test_resume_returns_to_the_law_at_the_next_ok_estimate():
    run = Simplex(after_fault="resume").start()
    assert run.command(bare_estimate("implausible")).mode == "safety"
    assert not run.latched and run.command(gaussian_estimate(260, 5)).mode == "performance"


@pytest.mark.parametrize("status", sorted(set(STATUSES) - set(FAULT_STATUSES) - {"ok"}))
def test_statuses_that_are_not_sensor_faults_do_not_latch(status):
    run = Simplex().start()
    assert run.command(bare_estimate(status)).mode == "safety"
    assert not run.latched and run.command(gaussian_estimate(260, 5)).mode == "performance"


@given(
    steps=st.lists(
        st.one_of(st.floats(210, 590), st.sampled_from(sorted(set(STATUSES) - {"ok"}))),
        min_size=1,
        max_size=30,
    ),
    after_fault=st.sampled_from(["latch", "resume"]),
)
def test_a_run_never_commands_more_than_the_memoryless_law(steps, after_fault):
    """Property: the run's command never exceeds Simplex.command's for the same estimate, and
    with the latch it is the safe speed at and after the first fault, whatever follows."""
    simplex = Simplex(after_fault=after_fault)
    run = simplex.start()
    faulted = False
    for step in steps:
        est = gaussian_estimate(step, 5) if isinstance(step, float) else bare_estimate(step)
        faulted |= est.status in FAULT_STATUSES
        cmd = run.command(est)
        assert cmd.speed <= simplex.command(est).speed
        if after_fault == "latch" and faulted:
            assert cmd.speed == simplex.v_safe and cmd.mode == "safety"


@given(gd=st.floats(200, 600), law=st.sampled_from(["linear", "paper"]))
def test_the_speed_grid_rounds_the_law_down_onto_its_steps(gd, law):
    """Property: the command is the law's speed or the grid point below it, within one step."""
    plain, grid = Simplex(law=law, speed_step_mps=0), Simplex(law=law)  # default grid: 0.1 m/s
    est = gaussian_estimate(gd, 3)
    law_speed, speed = plain.command(est).speed, grid.command(est).speed
    assert law_speed - 0.1 - 1e-9 < speed <= law_speed
    steps_above_safe = (speed - grid.v_safe) / 0.1
    assert speed == grid.v_max or abs(steps_above_safe - round(steps_above_safe)) < 1e-9


def test_the_speed_grid_keeps_its_end_points_and_stops():
    s = Simplex(speed_step_mps=0.1)
    assert s.on_speed_grid(2.0) == 2.0 and s.on_speed_grid(1.0) == 1.0
    assert s.on_speed_grid(1.3) == pytest.approx(1.3) and s.on_speed_grid(1.3) <= 1.3  # stays
    assert s.on_speed_grid(1.2999) == pytest.approx(1.2)
    assert Simplex(law="paper", speed_step_mps=0.3).on_speed_grid(0.05) == 0.0  # not negative
    assert Simplex(v_max=1.95, speed_step_mps=0.1).on_speed_grid(1.95) == 1.95  # v_max is on it
    assert Simplex(speed_step_mps=0).on_speed_grid(1.2345) == 1.2345  # no grid: the law as is


@pytest.mark.parametrize("speed", [-1.0, -1e-12, np.nan, np.inf, "1.5", None, True])
@pytest.mark.parametrize("step", [0.1, 0.0])
def test_the_speed_grid_refuses_a_speed_that_is_no_finite_number_at_least_0(speed, step):
    """-1 came back as -1, NaN and inf as themselves, a string as a bare TypeError."""
    with pytest.raises(ControlError, match=r"speed must be a finite real number >= 0, m/s, got"):
        Simplex(speed_step_mps=step).on_speed_grid(speed)


def test_on_the_speed_grid_an_invisible_change_of_the_estimate_changes_no_command():
    s = Simplex(speed_step_mps=0.1)
    gds = np.linspace(251, 349, 200)
    speeds = [s.command(gaussian_estimate(gd, 3)).speed for gd in gds]
    nudged = [s.command(gaussian_estimate(gd * (1 + 1e-9), 3)).speed for gd in gds]
    assert speeds == nudged
    assert len(set(speeds)) == 10  # 1.0, 1.1, ..., 1.9: one command per step of the law


@pytest.mark.parametrize("law", ["linear", "paper", "switch"])
@pytest.mark.parametrize("gd", [float("nan"), float("inf")])
def test_an_ok_estimate_without_a_finite_gd_means_safety_mode(gd, law):
    estimate = Estimate(time=1.0, position=1.0, status="ok", gd_mean=gd)
    for controller in (Simplex(law=law), Simplex(law=law, speed_step_mps=0.0)):
        command = controller.command(estimate)
        assert (command.mode, command.speed) == ("safety", controller.v_safe)
        assert controller.start().command(estimate).speed == controller.v_safe


@pytest.mark.parametrize("risk", [None, 0.1])
def test_an_estimate_at_the_emulators_upper_edge_means_safety(risk):
    from dataclasses import replace

    s = Simplex(risk=risk)
    low = gaussian_estimate(300, 20)
    assert s.command(low).mode == "performance"
    beyond = s.command(replace(low, domain_edge="upper"))
    assert beyond.mode == "safety" and beyond.speed == s.v_safe
    assert "roughest GD" in beyond.reason
    assert s.command(replace(low, domain_edge="lower")).mode == "performance"
