"""Bad-input audit (session 75): a numpy array (or anything not a string) given for a choice
field or argument is a ControlError naming it; ``array not in CHOICES`` raised numpy's bare
"The truth value of an empty array is ambiguous" ValueError, naming nothing."""

import numpy as np
import pytest

import control
from control import ControlError

CHOICE_FIELDS = [
    (control.BCRSettings, "method"),
    (control.BCRSettings, "interval_kind"),
    (control.ChangePointSettings, "prior"),
    (control.TrackerSettings, "prior"),
    (control.FeatureSpec, "name"),
    (control.Simplex, "law"),
    (control.Simplex, "after_fault"),
    (control.ReplaySettings, "imu_axis"),
    (control.ReplaySettings, "time_base"),
    (control.ReplaySettings, "position"),
    (control.ReplaySettings, "gravity"),
    (control.ReplaySettings, "resample"),
    (control.ReplaySettings, "storage"),
]


@pytest.mark.parametrize(("cls", "field"), CHOICE_FIELDS)
@pytest.mark.parametrize("value", [np.array([]), np.array(["a", "b"])])
def test_settings_choice_field_refuses_an_array_naming_it(cls, field, value):
    with pytest.raises(ControlError, match=field):
        cls(**{field: value})


@pytest.mark.parametrize("value", [np.array([]), np.array(["nan", "drop"])])
def test_sensor_fault_kind_and_estimate_status_refuse_an_array(value):
    with pytest.raises(ControlError, match="kind"):
        control.SensorFault(1.0, 1.0, kind=value)
    with pytest.raises(ControlError, match="status"):
        control.Estimate(time=0.0, position=0.0, status=value)


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda v: control.shipped_emulator_path(case=v), "case"),
        (lambda v: control.shipped_emulator_path(kind=v), "kind"),
        (lambda v: control.window_feature(np.ones(100), feature=v), "feature"),
    ],
)
def test_choice_arguments_refuse_an_array_naming_them(call, name):
    with pytest.raises(ControlError, match=name):
        call(np.array([]))


def test_numpy_strings_and_callables_are_still_choices():
    assert control.BCRSettings(method=np.str_("changepoint")).method == "changepoint"
    assert callable(control.ChangePointSettings(prior=lambda g: np.ones_like(g)).prior)
    assert control.shipped_emulator_path(np.str_("B")).name == "jackal_B.gpmsa"


def _metrics_on_two_parts():
    errors = (control.GDError(300.0, 4.0, 1), control.GDError(500.0, 100.0, 1))
    nan = float("nan")
    return control.LoopMetrics(errors, (), 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, nan, nan)


@pytest.mark.parametrize("gd", [np.inf, -np.inf, np.nan])
def test_loop_metrics_rmse_refuses_a_gd_that_is_not_finite(gd):
    # inf lay within the relative tolerance (1e-6 x inf) of every part: 300's RMSE came back
    metrics = _metrics_on_two_parts()
    assert metrics.rmse(500.0) == 10.0
    with pytest.raises(ControlError, match="gd must be finite"):
        metrics.rmse(gd)


@pytest.mark.parametrize(
    ("name", "value"), [("gd_max", -1.0), ("gd_max", 0.0), ("v_safe", -1.0), ("tol", -0.5)]
)
def test_fast_on_rough_m_refuses_bounds_out_of_their_domain(name, value):
    import roadgen

    track = roadgen.track([(3, 300), (3, 500)], seed=0)
    position, speed = np.linspace(0.0, 6.0, 61), np.full(61, 2.0)
    args = {"gd_max": 350.0, "v_safe": 1.0, "tol": 0.02}
    assert control.fast_on_rough_m(track, position, speed, **args) == pytest.approx(3.0, abs=0.1)
    with pytest.raises(ControlError, match=name):
        control.fast_on_rough_m(track, position, speed, **{**args, name: value})
