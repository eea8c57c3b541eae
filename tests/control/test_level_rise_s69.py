"""A signal level that rises within a block is not a sensor fault; one that drops still is
(session 69).

Found in a walkthrough of retrained emulators: with ``Simplex(v_safe=0.6)`` the first block the
BCR checks spans the simulated track's first metre, whose road fades in from flat, so the block
is quiet and then loud (x1,110-3,380): the level-jump check called it a fault and latched safety
mode at 1.05 s for the rest of the run (emulator A, every run at v_safe 0.55-0.66 m/s on GD 250
and GD 500, seed 1 also at 0.6 and 0.66). A robot driving from a smooth floor onto rough ground
meets the same block. A rising level reads rougher, never smoother; the dangerous fault, a gain
that falls, is first seen at the end of a block as a drop.
"""

import numpy as np
import pytest

import control
import roadgen
from control.sensor_checks import SensorLimits, level_jump, signal_fault


@pytest.fixture(scope="module")
def road_block() -> np.ndarray:
    return np.random.default_rng(3).standard_normal(125) * 4.0


def test_a_quiet_start_then_rough_ground_is_no_fault(road_block):
    rising = road_block.copy()
    rising[1:38] *= 1e-3  # flat ground, its first sample already a little rough
    assert level_jump(rising)[0] < 10
    assert signal_fault(rising, SensorLimits()) == ""


@pytest.mark.parametrize(
    ("where", "start"), [(slice(70, None), 70), (slice(40, 100), 40), (slice(90, None), 90)]
)
def test_a_level_that_drops_is_still_a_fault(road_block, where, start):
    dropped = road_block.copy()
    dropped[where] *= 1e-3  # a gain that fell (and may come back within the block)
    ratio, (first, _) = level_jump(dropped)
    assert ratio > 1e4 and first == start
    assert "signal level jumps" in signal_fault(dropped, SensorLimits())


@pytest.mark.parametrize("gd", [250.0, 500.0])
def test_a_slow_safe_speed_does_not_latch_on_the_tracks_lead_in(gd):
    track = roadgen.track([(6.0, gd)], seed=1)
    result = control.run_closed_loop(
        track, control.shipped_emulator("A"), seed=1, simplex=control.Simplex(v_safe=0.6)
    )
    assert not np.isfinite(result.metrics.latched_at_s)
    assert "sensor_fault" not in set(result.status)
