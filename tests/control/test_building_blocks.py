"""From a probe of control's building blocks: metrics that read their input once or the wrong
GD, spikes counted over a fault's whole span, feature functions and helpers that name what
they cannot take."""

from types import SimpleNamespace

import numpy as np
import pytest

import control
from control import ControlError, SensorFault, fast_on_rough_m, gd_errors
from control.faults import FaultInjector
from control.feature import FeatureSpec, block_features, window_feature
from control.observation_model import BlockScatter

TRACK = SimpleNamespace(
    segments=((50.0, 300.0), (50.0, 500.0), (50.0, 300.0)),
    boundaries_m=(0.0, 50.0, 100.0),
    length_m=150.0,
)


def test_pooled_rmse_reads_any_iterable_and_names_a_gd_no_run_has():
    runs = [gd_errors(TRACK, np.array([10.0, 60.0]), np.array([320.0, 450.0])),
            gd_errors(TRACK, np.array([20.0]), np.array([290.0]))]  # fmt: skip
    expected = np.sqrt((400 + 100) / 2)
    assert control.pooled_rmse(runs, 300) == pytest.approx(expected)
    assert control.pooled_rmse((run for run in runs), 300) == pytest.approx(expected)  # was NaN
    for gd in (301, 300.0000001):
        with pytest.raises(ControlError, match=r"no run has a part at GD .*at GD 300, 500"):
            control.pooled_rmse(runs, gd)
    for gd in ("300", None, True):
        with pytest.raises(ControlError, match="gd must be a real number"):
            control.pooled_rmse(runs, gd)
    with pytest.raises(ControlError, match=r"errors\[0\] holds 1, not a GDError"):
        control.pooled_rmse([[1, 2]], 300)


def test_fast_on_rough_m_checks_its_numbers():
    pos, speed = np.linspace(0, 150, 301), np.full(301, 2.0)
    assert fast_on_rough_m(TRACK, pos, speed, 350, 1.0) == pytest.approx(50.0)
    for kw in ({"gd_max": np.nan}, {"v_safe": np.nan}, {"tol": np.nan}, {"gd_max": True},
               {"gd_max": "350"}):  # fmt: skip
        args = {"gd_max": 350, "v_safe": 1.0, "tol": 0.02} | kw
        with pytest.raises(ControlError, match=f"{next(iter(kw))} must be a finite real number"):
            fast_on_rough_m(TRACK, pos, speed, **args)
    with pytest.raises(ControlError, match="speed must hold finite samples"):
        fast_on_rough_m(TRACK, pos, np.full(301, np.nan), 350, 1.0)


def test_spikes_keep_their_spacing_and_sign_across_batches():
    """The spacing restarted in every batch: one spike asked for in 600 samples came 16 times."""
    t, a = np.arange(720) / 120.0, np.zeros(720)
    for spacing in (1000.0, 10.0, 2.9):
        fault = [SensorFault(1.0, 5.0, "spike", spacing)]
        whole = FaultInjector(fault, np.random.default_rng(0))(t, t, a, np.ones(720))[2]
        inject = FaultInjector(fault, np.random.default_rng(0))
        parts = [inject(t[k : k + 42], t[k : k + 42], a[k : k + 42], np.ones(t[k : k + 42].size))[2]
                 for k in range(0, 720, 42)]  # fmt: skip
        np.testing.assert_array_equal(np.concatenate(parts), whole)
    spikes = np.flatnonzero(whole)
    assert spikes.size == 200 and set(np.sign(whole[spikes[:4]])) == {-1.0, 1.0}
    with pytest.raises(ControlError, match="must have one length, got 10, 5, 10 and 10"):
        inject(t[:10], t[:5], a[:10], np.ones(10))
    with pytest.raises(ControlError, match=r"t must be an array of real numbers, got dtype object"):
        inject(None, None, None, None)
    text = r"accel must be an array of real numbers, got dtype <U1"
    with pytest.raises(ControlError, match=text):
        inject(t[:2], t[:2], ["a", "b"], np.ones(2))
    with pytest.raises(ControlError, match=r"t must be 1-D, got shape \(2, 1\)"):
        inject(t[:2, None], t[:2], a[:2], np.ones(2))


def test_feature_functions_take_finite_real_samples_only():
    spec = FeatureSpec()
    good = np.random.default_rng(0).normal(size=spec.block_samples)
    assert np.all(np.isfinite(block_features(good, spec)))
    for bad, match in (
        (good.astype(str), "accel"), (good > 0, "accel"), (good + 1j, "accel"),
        (np.ma.masked_array(good, good > 1), "masked array"),
        (np.where(good > 1, np.nan, good), "NaN or inf"),
    ):  # fmt: skip
        with pytest.raises(ControlError, match=match):
            block_features(bad, spec)
        with pytest.raises(ControlError, match=match):
            window_feature(bad)
    with pytest.raises(ControlError, match="spec must be a control.FeatureSpec"):
        block_features(good, None)


def test_a_block_scatter_must_be_symmetric_and_helpers_name_wrong_types(emulator_a):
    c = np.stack([np.eye(3), np.eye(3)])
    assert BlockScatter([0.5, 2.0], c).cov.shape == (2, 3, 3)
    with pytest.raises(ControlError, match="symmetric"):
        BlockScatter([0.5, 2.0], c + 5 * np.triu(np.ones((3, 3)), 1))
    with pytest.raises(control.EmulatorMismatchError, match="block_scatter is malformed"):
        BlockScatter.from_dict(None)
    for bad in ("A", None):
        with pytest.raises(ControlError, match="emulator must be a gpmsa.Emulator"):
            control.ObservationModel(bad)
    with pytest.raises(ControlError, match="scatter must be a control BlockScatter"):
        control.ObservationModel(emulator_a, scatter="x")
    with pytest.raises(ControlError, match="MAX_TABLE_NODES"):
        control.ObservationModel(emulator_a, n_grid=10**9)
    for kw, match in (({"model": "Jackal"}, "model must be a vehicle model"),
                      ({"bcr": "x"}, "bcr must be a control.BCRSettings"),
                      ({"track": "x"}, "track must be a roadgen Track"),
                      ({"simplex": "x"}, "simplex must be a control.Simplex"),
                      ({"noise_std": "x"}, "noise_std must be a finite real"),
                      ({"noise_std": np.nan}, "noise_std must be a finite real"),
                      ({"noise_std": True}, "noise_std must be a finite real")):  # fmt: skip
        with pytest.raises(ControlError, match=match):
            control.check_emulator(emulator_a, **kw)


def test_run_closed_loop_names_a_record_or_flag_of_the_wrong_type(emulator_a):
    import roadgen

    track = roadgen.track([(10.0, 300.0)], seed=0)
    record = r"record must be the path \(a str or os.PathLike\) of the \.mcap"
    for kw, match in (({"record": 5}, record),
                      ({"check": "no"}, "check must be True or False"),
                      ({"progress": "yes"}, "progress must be True or False")):  # fmt: skip
        with pytest.raises(ControlError, match=match):
            control.run_closed_loop(track, emulator_a, **kw)


def test_fault_injector_at_the_edges_of_its_magnitudes_and_its_arguments():
    """A spike spacing beyond int64 crashed in numpy (OverflowError), a quantisation step so
    fine that a reading divided by it overflows turned the readings into inf, and one fault
    passed without a list was a TypeError."""
    t, a = np.arange(240) / 120.0, np.random.default_rng(0).normal(size=240)
    hit = (t >= 0.5) & (t < 1.5)

    def inject(kind, magnitude):
        fault = SensorFault(0.5, 1.0, kind, magnitude)
        with np.errstate(over="raise", invalid="raise"):  # no overflow on the way
            return FaultInjector([fault], np.random.default_rng(0))(t, t, a, np.ones(240))[2]

    for spacing in (1e19, 1e300, np.finfo(float).max):  # one spike, at the fault's start
        spiked = inject("spike", spacing)
        assert np.flatnonzero(spiked != a).tolist() == [60] and spiked[60] == -1e6
    for step in (5e-324, 1e-310):  # far below the readings' resolution: unchanged
        np.testing.assert_array_equal(inject("quantize", step), a)
    assert np.all(inject("quantize", 1e300)[hit] == 0.0)
    for faults, match in ((SensorFault(0.5, 1.0), "pass \\[fault\\]"), (None, "got None"),
                          ("nan", "got 'nan'"), (5, "got 5")):  # fmt: skip
        with pytest.raises(
            ControlError, match=f"faults must be a sequence of SensorFault.*{match}"
        ):
            FaultInjector(faults, np.random.default_rng(0))
