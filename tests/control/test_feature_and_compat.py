"""Window feature, emulator-compatibility checks and plotting helpers (no simulation)."""

from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from control_doubles import plotted_run_and_track  # noqa: E402
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from scipy import stats  # noqa: E402

import vehicle  # noqa: E402
from control import (  # noqa: E402
    PAPER_WINDOW,
    BCRSettings,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    FeatureSpec,
    SensorLimits,
    Simplex,
    bcr_settings_for,
    block_features,
    check_emulator,
    emulator_vehicle,
    window_feature,
)
from control.feature import _quantiles  # noqa: E402
from control.plotting import plot_design, plot_gd_trace, plot_posterior_grid, plot_speed  # noqa: E402


def fake_emulator(**meta):
    return SimpleNamespace(
        domain={"v": (0.5, 2.0), "GD": (200.0, 600.0)}, x_names=["v"], t_names=["GD"], metadata=meta
    )


def test_feature_is_the_papers_variance_normalised_by_t():
    a = np.array([1.0, -1.0, 3.0, -3.0])
    assert window_feature(a, "var") == pytest.approx(5.0)  # sum of squares / T, not T - 1
    assert window_feature(a, "log_var") == pytest.approx(np.log(5.0))
    assert np.isnan(window_feature(np.ones(10), "log_var"))
    with pytest.raises(ControlError, match="feature must be one of"):
        window_feature(a, "rms")
    with pytest.raises(ControlError, match="accel must be 1-D"):
        window_feature(np.ones((2, 2)))


def test_bcr_settings_follow_the_emulators_feature():
    emu = fake_emulator(feature={"name": "var", "window_samples": 600, "rate_hz": 100.0})
    s = bcr_settings_for(emu, method="window")
    assert (s.feature.name, s.feature.block_samples, s.rate_hz, s.method) == (
        "var",
        600,
        100.0,
        "window",
    )
    assert bcr_settings_for(emu).method == "filter"  # a window feature: the window filter
    band = fake_emulator(feature=FeatureSpec().to_dict())
    assert bcr_settings_for(band) == BCRSettings()  # the block feature: the change-point BCR
    # the sensor checks know the training noise (the noise-floor check); none if noise-free
    noisy = fake_emulator(feature=FeatureSpec().to_dict(), noise_std=0.7)
    assert bcr_settings_for(noisy).sensor == SensorLimits(noise_sd_mps2=0.7)
    for value in (0.0, "loud", float("nan")):
        bare = fake_emulator(feature=FeatureSpec().to_dict(), noise_std=value)
        assert bcr_settings_for(bare).sensor.noise_sd_mps2 is None
    mine = SensorLimits(max_repeats=3)
    assert bcr_settings_for(noisy, sensor=mine).sensor == mine
    with pytest.raises(EmulatorMismatchError, match="has no 'feature'"):
        bcr_settings_for(fake_emulator())


def test_check_emulator_errors_and_warnings():
    jackal = vehicle.Jackal()
    emu = fake_emulator(
        vehicle=jackal.describe(),
        noise_std=0.0,
        feature={"name": "log_var", "window_samples": 1000, "rate_hz": 120.0},
    )
    window = BCRSettings(feature=PAPER_WINDOW, method="window")
    check_emulator(emu, model=jackal, noise_std=0.0, bcr=window)  # all agree: silent
    with pytest.raises(EmulatorMismatchError, match=r"another vehicle \(.*model: model \"HalfCar"):
        check_emulator(emu, model=vehicle.HalfCar())
    var = BCRSettings(feature=FeatureSpec("var", 1000), method="window")
    with pytest.raises(EmulatorMismatchError, match="name: BCR 'var' vs emulator 'log_var'"):
        check_emulator(emu, bcr=var)
    fast = BCRSettings(feature=FeatureSpec("log_var", 1000, rate_hz=100.0), method="window")
    with pytest.raises(EmulatorMismatchError, match="rate_hz: BCR 100.0 vs emulator 120.0"):
        check_emulator(emu, bcr=fast)
    with pytest.warns(ControlWarning, match="no 'vehicle'"):
        check_emulator(fake_emulator(), model=jackal)
    with pytest.warns(ControlWarning, match="noise_std = 0.5"):
        check_emulator(emu, noise_std=0.5)
    track = SimpleNamespace(segments=((10.0, 150.0), (10.0, 300.0)))
    with pytest.raises(EmulatorMismatchError, match=r"track GD \[150.0\]"):
        check_emulator(emu, track=track)


def test_check_emulator_refuses_a_simplex_driving_outside_the_speed_domain():
    emu = fake_emulator()
    check_emulator(emu, simplex=Simplex())  # the paper's 1.0 and 2.0 m/s in [0.5, 2.0]
    check_emulator(emu, simplex=Simplex(v_safe=0.5, v_max=0.5))  # the domain's edge is inside
    slow = SimpleNamespace(**{**vars(emu), "domain": {"v": (0.5, 1.5), "GD": (200.0, 600.0)}})
    with pytest.raises(EmulatorMismatchError, match=r"v_max = 2 m/s lies outside .* \[0.5, 1.5\]"):
        check_emulator(slow, simplex=Simplex())
    check_emulator(slow, simplex=Simplex(v_max=1.5))
    fast = SimpleNamespace(**{**vars(emu), "domain": {"v": (1.2, 2.0), "GD": (200.0, 600.0)}})
    with pytest.raises(EmulatorMismatchError, match=r"v_safe = 1 m/s lies outside .*--speed-range"):
        check_emulator(fast, simplex=Simplex())
    narrow = SimpleNamespace(**{**vars(emu), "domain": {"v": (1.2, 1.8), "GD": (200.0, 600.0)}})
    with pytest.raises(EmulatorMismatchError, match="v_safe = 1 m/s and v_max = 2 m/s lie outside"):
        check_emulator(narrow, simplex=Simplex())


def test_check_emulator_refuses_a_gd_max_that_no_estimate_can_exceed():
    emu = fake_emulator()  # GD domain [200, 600]
    check_emulator(emu, simplex=Simplex(gd_min=400, gd_max=590))
    for gd_max in (600, 650):
        with pytest.raises(EmulatorMismatchError, match=rf"gd_max = {gd_max} is not below .* 600"):
            check_emulator(emu, simplex=Simplex(gd_min=400, gd_max=gd_max))


def test_check_emulator_refuses_a_gd_max_that_every_estimate_exceeds():
    emu = fake_emulator()  # GD domain [200, 600]: gd_max 150 would hold safety mode for good
    check_emulator(emu, simplex=Simplex(gd_min=100, gd_max=210))
    for gd_max in (200, 150):
        with pytest.raises(EmulatorMismatchError, match=rf"gd_max = {gd_max} is not above .* 200"):
            check_emulator(emu, simplex=Simplex(gd_min=50, gd_max=gd_max))


def test_feature_spec_checks_and_round_trips():
    spec = FeatureSpec()
    assert spec.dim == 10 and len(spec.names()) == 10 and spec.block_s == pytest.approx(125 / 120)
    assert spec.quantiles == (0.9, 0.98)
    assert spec.names()[-2:] == ["q90_minus_mean", "q98_minus_mean"]
    assert spec.units()[-3:] == ["log((m/s^2)^2)", "g", "g"]
    assert FeatureSpec.from_dict(spec.to_dict()) == spec
    bands = FeatureSpec(quantiles=())
    assert bands.dim == 8 and FeatureSpec.from_dict(bands.to_dict()) == bands
    old = {k: v for k, v in spec.to_dict().items() if k != "quantiles"}  # written before them
    assert FeatureSpec.from_dict(old) == bands and spec.same_as(bands) == ["quantiles"]
    assert FeatureSpec(name="log_var", block_samples=1000).quantiles == ()
    assert spec.same_as(FeatureSpec(taper_nw=3.0, n_tapers=5)) == ["taper_nw", "n_tapers"]
    with pytest.raises(ControlError, match="holds no frequency bin"):
        FeatureSpec(block_samples=16, bands_hz=(1.0, 2.0, 60.0))
    with pytest.raises(ControlError, match="above the Nyquist frequency"):
        FeatureSpec(bands_hz=(1.0, 70.0))
    with pytest.raises(ControlError, match="n_tapers must lie in"):
        FeatureSpec(n_tapers=4)
    with pytest.raises(ControlError, match="feature name must be one of"):
        FeatureSpec(name="rms")
    with pytest.raises(ControlError, match=r"block_samples must lie in \[16, 4096\]"):
        FeatureSpec(block_samples=10**9)  # refused before any table of that size is made
    for kwargs, match in (
        ({"rate_hz": "120"}, "FeatureSpec.rate_hz must be a real number"),
        ({"n_tapers": 2.5}, "FeatureSpec.n_tapers must be an integer"),
        ({"block_samples": 125.0}, "FeatureSpec.block_samples must be an integer"),
        ({"bands_hz": None}, "bands_hz must be an array of real numbers"),
        ({"bands_hz": 5.0}, "bands_hz must be a sequence of finite edges"),
        ({"bands_hz": (1.0, "a")}, "bands_hz must be an array of real numbers"),
        ({"quantiles": (0.9, 1.0)}, r"quantiles must be a sequence of levels in \(0, 1\)"),
        ({"quantiles": (0.98, 0.9)}, "quantiles must be increasing"),
        ({"quantiles": (0.5, 0.5)}, "quantiles must be increasing"),
        ({"quantiles": ((0.5, 0.9),)}, "quantiles must be a sequence of levels"),
        ({"quantiles": "0.9"}, "quantiles must be a sequence of levels"),
        ({"quantiles": (True,)}, "quantiles must be an array of real numbers"),
        ({"quantiles": (0.9, np.nan)}, "quantiles must be a sequence of levels"),
        ({"name": "log_var", "quantiles": (0.9,)}, "quantiles go with the log_band_power"),
    ):
        with pytest.raises(ControlError, match=match):
            FeatureSpec(**kwargs)


def test_band_powers_add_up_to_the_variance_of_white_noise():
    """The bands tile (1.5, 60) Hz: for white noise their powers sum to that share of the
    variance (the multitaper estimate is unbiased for a flat spectrum)."""
    rng = np.random.default_rng(3)
    a = rng.standard_normal((4000, 125)) * 2.0
    power = np.exp(block_features(a, FeatureSpec())[:, :8]).sum(axis=1).mean()
    assert power == pytest.approx(4.0 * (60 - 1.5) / 60, rel=0.03)
    with pytest.raises(ControlError, match=r"accel must have shape \(n, 125\)"):
        block_features(np.ones((2, 100)), FeatureSpec())


def test_the_quantiles_are_the_blocks_upper_tail_less_its_mean_in_g():
    """For Gaussian noise of sd 2 m/s^2 the 90% and 98% sample quantiles of 125 samples less
    the mean are, in expectation, 2 m/s^2 times the interpolated normal order statistics (Blom's
    approximation; 1.27 and 2.05 sd at the population quantiles, the 98% one of 125 samples
    lies ~4% lower); an offset of the sensor changes nothing, and the band powers come first,
    those of the band vector alone."""
    rng = np.random.default_rng(4)
    a = rng.standard_normal((4000, 125)) * 2.0
    spec = FeatureSpec()
    y = block_features(a, spec)
    direct = np.quantile(a - a.mean(axis=1, keepdims=True), [0.9, 0.98], axis=1).T
    assert np.array_equal(y[:, 8:], direct / 9.80665)
    position = 124 * np.array([0.9, 0.98])  # np.quantile's linear interpolation, 0-based
    k, frac = np.floor(position), position % 1
    order = stats.norm.ppf((np.stack([k, k + 1]) + 1 - 0.375) / (125 + 0.25))  # Blom
    expected = 2.0 * ((1 - frac) * order[0] + frac * order[1]) / 9.80665
    assert y[:, 8:].mean(axis=0) == pytest.approx(expected, rel=0.02)
    assert np.array_equal(y[:, :8], block_features(a, FeatureSpec(quantiles=())))
    assert np.allclose(block_features(a + 3.7, spec), y)  # an offset of 3.7 m/s^2


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(2, 300),
    levels=st.lists(st.floats(0.001, 0.999), min_size=1, max_size=5, unique=True),
    seed=st.integers(0, 2**16),
)
def test_the_quantiles_are_numpys_linear_quantiles(n, levels, seed):
    x = np.random.default_rng(seed).standard_normal((3, n)) * 4.0
    levels = tuple(sorted(levels))
    assert np.array_equal(_quantiles(x, levels), np.quantile(x, levels, axis=1).T)  # bit for bit


def test_plots_return_figures_with_one_line_per_run():
    run, track = plotted_run_and_track()
    pos = run.position
    fig = plot_gd_trace([run, run], track)
    assert isinstance(fig, Figure) and len(fig.axes[0].lines) >= 3  # prescribed + 2 runs
    assert isinstance(plot_speed([run], track), Figure)
    edged = SimpleNamespace(**vars(run), domain_edge=np.where(pos > 90, "upper", ""))
    fig = plot_gd_trace([run, edged], track)
    (marks,) = [ln for ln in fig.axes[0].lines if ln.get_marker() == "^"]
    assert marks.get_label() == "run 2: upper edge of the GD domain"
    np.testing.assert_array_equal(marks.get_xdata(), pos[pos > 90])
    assert isinstance(plot_design(np.array([1.0, 2.0]), np.array([300.0, 400.0])), Figure)
    cells = [(v, gd, np.full(10, gd)) for v in (1.0, 2.0) for gd in (300.0, 500.0)]
    assert len(plot_posterior_grid(cells).axes) == 4


def test_training_and_the_bcr_map_a_variance_to_the_same_observation():
    from control.feature import feature_of_variance, window_feature

    accel = np.random.default_rng(4).standard_normal(1000) * 3.0
    f = np.var(accel)
    for feature in ("var", "log_var"):
        assert feature_of_variance(f, feature) == window_feature(accel, feature)
    ys = feature_of_variance(np.array([4.0, 0.0, 9.0]), "log_var")
    np.testing.assert_allclose(ys, [np.log(4.0), np.nan, np.log(9.0)])


def test_a_malformed_quantiles_record_is_refused_and_an_old_one_reads_as_bands_alone():
    from control.compat import emulator_feature

    record = FeatureSpec().to_dict()
    for bad in (None, "0.9", [0.9, "x"], [1.5]):
        with pytest.raises(EmulatorMismatchError, match="feature is malformed: .*quantiles"):
            emulator_feature(fake_emulator(feature={**record, "quantiles": bad}))
    old = {k: v for k, v in record.items() if k != "quantiles"}
    assert emulator_feature(fake_emulator(feature=old)).quantiles == ()


def test_the_emulators_vehicle_is_rebuilt_from_its_record():
    mine = vehicle.Jackal(mass_kg=21.5)
    assert emulator_vehicle(fake_emulator(vehicle=mine.describe())) == mine
    with pytest.raises(EmulatorMismatchError, match="has no 'vehicle'"):
        emulator_vehicle(fake_emulator())
    with pytest.raises(EmulatorMismatchError, match="vehicle record is malformed: .*no parameter"):
        emulator_vehicle(fake_emulator(vehicle={"model": "Jackal", "wings": 2}))


@pytest.mark.parametrize(
    "record, match",
    [
        ({}, "no 'name'"),  # read as the default band feature, without its quantiles
        ({"name": "log_var", "rate_hz": 120.0}, "no 'block_samples'"),  # read as 125 samples
        ({"name": "log_var", "window_samples": 1000}, "no 'rate_hz'"),  # read as 120 Hz
        (None, "must be a mapping"),  # TypeError: 'NoneType' object is not iterable
        ("log_var", "must be a mapping"),  # ValueError from dict(): "dictionary update sequence"
        ([], "must be a mapping"),  # read as the default band feature
    ],
)
def test_a_feature_record_without_its_name_length_or_rate_is_refused(record, match):
    """A record missing the name, the block length or the rate was read with the defaults in
    their place (an empty one as the band feature), and one that was not a mapping failed with
    numpy- or dict()-level messages."""
    from control.compat import emulator_feature

    with pytest.raises(ControlError, match=match):
        FeatureSpec.from_dict(record)
    with pytest.raises(EmulatorMismatchError, match=f"feature is malformed: .*{match}"):
        emulator_feature(fake_emulator(feature=record))
    old = {"name": "log_var", "window_samples": 1000, "rate_hz": 120.0, "span": "ignored"}
    assert FeatureSpec.from_dict(old) == PAPER_WINDOW  # the first form still reads


def test_same_as_names_an_argument_that_is_not_a_feature():
    with pytest.raises(ControlError, match="other must be a control.FeatureSpec, got 'log_var'"):
        FeatureSpec().same_as("log_var")  # AttributeError: 'str' object has no attribute 'name'


@pytest.mark.parametrize(
    "value", [True, "0.7", 10**400, [0.7]], ids=["bool", "str", "huge", "list"]
)
def test_a_training_noise_record_that_is_not_a_number_is_no_noise_sd(value):
    """A bool or a string was read as a noise sd by emulator_noise_std (True as 1 m/s^2) while
    check_emulator said there was none; an integer beyond a float's range raised
    OverflowError in both."""
    from control.compat import emulator_noise_std

    emu = fake_emulator(feature=FeatureSpec().to_dict(), noise_std=value)
    assert emulator_noise_std(emu) is None
    assert bcr_settings_for(emu).sensor.noise_sd_mps2 is None
    with pytest.warns(ControlWarning, match="no 'noise_std'"):
        check_emulator(emu, noise_std=0.7)
    assert emulator_noise_std(fake_emulator(noise_std=np.float32(0.5))) == 0.5
