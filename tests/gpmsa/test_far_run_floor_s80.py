"""``far_run``'s floor on the other runs' range is that of the scale the fit divides y by: one
scale over all outputs (its largest robust range, not the median over points, which is ~0 where
most points are flat) or, with ``y_scale="columnwise"``, each element's own."""

import numpy as np

import gpmsa
from gpmsa.model.far_values import far_run

S = np.linspace(0.0, 1.0, 50)


def _design(seed: int, m: int = 40):
    rng = np.random.default_rng(seed)
    return rng.uniform(size=(m, 1)), rng.uniform(size=(m, 1))


def test_steep_steps_and_moving_pulses_are_no_outliers():
    # a steep step whose flat ends hold every run within 1e-7 (0.9999988 was named, 30.7 times
    # the others' range below them), and a pulse reaching each point in a run or two
    x, t = _design(2)
    step = 1.0 / (1.0 + np.exp(-(S - (0.3 + 0.4 * x)) / 0.005))
    assert far_run(gpmsa.SimData(x=x, t=t, y=step, index=S), S) is None
    for seed in (4, 5):
        x, t = _design(seed)
        pulse = np.exp(-(((S - (0.2 + 0.6 * x)) / 0.02) ** 2)) * (1.0 + t)
        assert far_run(gpmsa.SimData(x=x, t=t, y=pulse, index=S), S) is None
        pulse[7, 30] = -999.0  # a missing-value code among them still is
        found = far_run(gpmsa.SimData(x=x, t=t, y=pulse, index=S), S)
        assert found is not None and (found.run, found.value) == (7, -999.0)


def test_a_failed_run_beside_another_code_is_still_named():
    x, t = _design(0)
    y = x * np.sin(3 * S) + t * S**2
    y[3] = -999.0  # a failed run, and another run's -999 at one point: neither sets the floor
    y[9, 30] = -999.0
    found = far_run(gpmsa.SimData(x=x, t=t, y=y, index=S), S)
    assert found is not None and found.run == 3 and found.n_points == 49
    assert "whose range reaches 1.18 elsewhere" in found.text()


def test_columnwise_outputs_of_other_scales_are_judged_each_on_its_own():
    x, t = _design(0)
    y = np.column_stack([300 + 10 * x + 5 * t, 1e-6 * (1 + x * t), 1e5 * (1 + 0.1 * x), t**2])
    names = ["T", "strain", "p", "q"]
    assert far_run(gpmsa.SimData(x=x, t=t, y=y, y_scale="columnwise", y_names=names), S) is None
    y[4, 1] *= 1e6  # a strain in microstrain among strains (was unnamed: 2 typical ranges)
    found = far_run(gpmsa.SimData(x=x, t=t, y=y, y_scale="columnwise", y_names=names), S)
    assert found is not None and (found.run, found.point) == (4, "output 'strain'")
    assert found.text().startswith("simulation run 4 (y[4]) holds 1.31849 at output 'strain', ")
