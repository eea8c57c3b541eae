"""Review of the Simplex's release dwell: it never commands more than the law (the paper's law
reads performance mode below v_safe), and a fault at the start arms it (a run latched before its
first performance mode holds the dwell after reset())."""

import copy

import pytest
from test_release_dwell_s82 import ok

from control import Estimate, Simplex


def fault(position: float) -> Estimate:
    return Estimate(time=position, position=position, status="sensor_fault", reason="x")


def filling(position: float) -> Estimate:
    return Estimate(time=position, position=position, status="filling")


@pytest.mark.parametrize("law", ["paper", "linear", "switch"])
def test_the_dwell_never_commands_more_than_the_law(law):
    # performance, safety (GD 400), then the law reads performance at GD 330/340/280/320
    gds = [300.0, 300.0, 400.0, 330.0, 340.0, 280.0, 320.0, 300.0, 300.0]
    law_run, held_run = Simplex(law=law).start(), Simplex(law=law, release_m=5.0).start()
    held_modes = []
    for pos, gd in enumerate(gds):
        free, held = law_run.command(ok(float(pos), gd)), held_run.command(ok(float(pos), gd))
        assert held.speed <= free.speed
        held_modes.append(held.mode)
    assert held_modes == ["performance"] * 2 + ["safety"] * 6 + ["performance"]
    if law == "paper":  # the law reads 0.0 m/s at GD 330 and 340: the dwell held 1.0 before
        paper = Simplex(law="paper", release_m=5.0).start()
        speeds = [paper.command(ok(float(p), gd)).speed for p, gd in enumerate(gds[:6])]
        assert speeds[3:] == [0.0, 0.0, pytest.approx(0.8)]


@pytest.mark.parametrize("after_fault", ["latch", "resume"])
def test_a_fault_before_the_first_performance_mode_arms_the_dwell(after_fault):
    run = Simplex(release_m=5.0, after_fault=after_fault).start()
    assert run.command(filling(0.0)).mode == "safety"
    assert run.command(fault(1.0)).mode == "safety"
    assert run.performed
    if after_fault == "latch":
        assert run.command(ok(2.0, 300.0)).mode == "safety" and run.latched
        run.reset()
    modes = [run.command(ok(p, 300.0)).mode for p in (3.0, 7.0, 8.0)]
    assert modes == ["safety", "safety", "performance"]


def test_the_start_without_a_fault_has_no_dwell_and_a_copy_keeps_its_own_count():
    run = Simplex(release_m=5.0).start()
    assert [run.command(e).mode for e in (filling(0.0), ok(1.0, 400.0), ok(2.0, 300.0))] == [
        "safety", "safety", "performance",
    ]  # fmt: skip
    assert run.performed and not run.in_safety
    run.command(ok(3.0, 400.0))
    twin = copy.copy(run)
    assert twin.command(ok(4.0, 300.0)).mode == "safety"
    assert (twin.clear_since_m, run.clear_since_m) == (4.0, None)
