"""Mutation testing of `control.compat` (session 88): each property an emulator records is
checked on both sides of the line its check draws.

For each recorded property (the feature's name, block length, rate, bands, tapers and
quantiles; the vehicle and each of its parameters; the training noise; the GD and speed
domains; the training roads' grid and band) an emulator that differs in exactly that property
is refused (or warned about) naming it, and one that differs only within the tolerance its
check allows is accepted. `check_likelihood` and the recording checks likewise.
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pytest

import gpmsa
import vehicle
from control import (
    PAPER_WINDOW,
    BCRSettings,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    FeatureSpec,
    Simplex,
    check_emulator,
    check_likelihood,
)
from control.compat import (
    _mean_reach,
    _quantile,
    _risk_above,
    _risk_text,
    _track_road_mismatch,
    _warn_if_out_of_reach,
    check_against,
    check_recorded_feature,
    check_recorded_vehicle,
    emulator_noise_std,
    one_observation_posteriors,
    recorded_vehicle_mismatch,
)

DOMAIN = {"v": (0.5, 2.0), "GD": (200.0, 600.0)}


def emulator(domain=DOMAIN, predict=None, **meta):
    """A stand-in of an emulator's records (no predictions unless ``predict`` is given)."""
    emu = SimpleNamespace(domain=dict(domain), x_names=["v"], t_names=["GD"], metadata=meta)
    if predict is not None:
        emu.predict_mean = predict
    return emu


def silent(fn, *args, **kwargs):
    """``fn(*args, **kwargs)``, failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return fn(*args, **kwargs)


BAND = FeatureSpec()  # the block feature (log_band_power)

# one field of the block feature changed at a time: (field, the BCR's feature)
BAND_CHANGES = [
    ("name", FeatureSpec("log_var", 125)),
    ("block_samples", FeatureSpec(block_samples=126)),
    ("rate_hz", FeatureSpec(rate_hz=121.0)),
    ("bands_hz", FeatureSpec(bands_hz=[*BAND.bands_hz[:-1], BAND.bands_hz[-1] - 1.0])),
    ("bands_hz", FeatureSpec(bands_hz=BAND.bands_hz[:-1])),  # one band fewer
    ("taper_nw", FeatureSpec(taper_nw=2.5)),
    ("n_tapers", FeatureSpec(n_tapers=2)),
    ("quantiles", FeatureSpec(quantiles=())),
]


@pytest.mark.parametrize(("field", "feature"), BAND_CHANGES)
def test_a_feature_differing_in_one_field_is_refused_naming_it(field, feature):
    emu = emulator(feature=BAND.to_dict())
    bcr = BCRSettings(feature=feature, method="changepoint" if field != "name" else "window")
    with pytest.raises(EmulatorMismatchError, match=rf"\({field}: BCR .* vs emulator "):
        check_emulator(emu, bcr=bcr)
    with pytest.raises(EmulatorMismatchError, match=rf"\({field}: BCR "):
        check_recorded_feature(emu, bcr)
    with pytest.raises(EmulatorMismatchError, match=rf"\({field}: BCR "):
        check_against(emu, bcr=bcr)


def test_a_feature_differing_in_two_fields_names_both():
    emu = emulator(feature=BAND.to_dict())
    bcr = BCRSettings(feature=FeatureSpec(block_samples=126, n_tapers=2))
    with pytest.raises(EmulatorMismatchError, match=r"block_samples: BCR 126 vs emulator 125, "):
        check_emulator(emu, bcr=bcr)


def test_a_feature_equal_or_within_rounding_of_the_recorded_one_is_accepted():
    emu = emulator(feature=BAND.to_dict())
    silent(check_emulator, emu, bcr=BCRSettings())
    # a rate read back through a float round trip (within np.isclose) is the same rate
    silent(check_emulator, emu, bcr=BCRSettings(feature=FeatureSpec(rate_hz=120.0 * (1 + 1e-9))))
    window = emulator(feature=PAPER_WINDOW.to_dict())
    silent(check_emulator, window, bcr=BCRSettings(feature=PAPER_WINDOW, method="window"))


def test_a_feature_is_checked_only_where_the_emulator_records_one():
    bare = emulator()
    silent(check_recorded_feature, bare, BCRSettings(feature=PAPER_WINDOW, method="window"))
    with pytest.raises(EmulatorMismatchError, match="has no 'feature'"):
        check_emulator(bare, bcr=BCRSettings())
    silent(check_emulator, bare)  # no bcr: nothing to compare


JACKAL = vehicle.Jackal()


@pytest.mark.parametrize("key", sorted(k for k in JACKAL.describe() if k != "model"))
def test_a_vehicle_differing_in_one_parameter_is_refused_naming_it(key):
    record = JACKAL.describe()
    value = record[key]
    record[key] = (not value) if isinstance(value, bool) else value * 1.5
    emu = emulator(vehicle=record)
    with pytest.raises(EmulatorMismatchError, match=r"another vehicle \(([^,]*)\)") as err:
        check_emulator(emu, model=JACKAL)
    assert str(err.value).count(" vs emulator ") == 1  # that parameter alone
    assert f"({key}: model " in str(err.value)
    why = recorded_vehicle_mismatch(emu, JACKAL)
    assert f"({key}: recording " in why and why.count(" vs emulator ") == 1
    with pytest.raises(EmulatorMismatchError, match=rf"\({key}: recording .*check_vehicle=False"):
        check_recorded_vehicle(emu, JACKAL)


def test_the_same_vehicle_is_accepted_and_the_model_is_named_first():
    emu = emulator(vehicle=JACKAL.describe())
    silent(check_emulator, emu, model=vehicle.Jackal())
    assert recorded_vehicle_mismatch(emu, vehicle.Jackal()) == ""
    silent(check_recorded_vehicle, emu, vehicle.Jackal())
    with pytest.raises(EmulatorMismatchError, match=r"another vehicle \(model: model \"HalfCar\""):
        check_emulator(emu, model=vehicle.HalfCar())
    why = recorded_vehicle_mismatch(emu, vehicle.HalfCar(), "the bag")
    assert why.startswith("the bag was simulated with another vehicle")
    assert '(model: recording "HalfCar" vs emulator "Jackal"' in why


def test_an_emulator_without_a_vehicle_record_is_taken_as_it_is_by_a_recording():
    assert recorded_vehicle_mismatch(emulator(), JACKAL) == ""
    assert recorded_vehicle_mismatch(emulator(vehicle=JACKAL.describe()), None) == ""
    silent(check_recorded_vehicle, emulator(), JACKAL)
    with pytest.warns(ControlWarning, match="no 'vehicle'; cannot check it was made for Jackal"):
        check_emulator(emulator(), model=JACKAL)


@pytest.mark.parametrize("noise", [-0.1, np.inf, np.nan, "0.5"])
def test_a_noise_sd_that_is_not_a_finite_number_at_least_0_is_refused(noise):
    with pytest.raises(ControlError, match=r"noise_std must be a finite real number >= 0"):
        check_emulator(emulator(noise_std=0.5), noise_std=noise)


def test_another_noise_sd_warns_and_the_same_one_within_rounding_does_not():
    emu = emulator(noise_std=0.5)
    silent(check_emulator, emu, noise_std=0.5)
    silent(check_emulator, emu, noise_std=0.5 * (1 + 1e-10))
    silent(check_recorded_vehicle, emu, None, 0.5)
    for other in (0.0, 0.6, 1.0):
        with pytest.warns(
            ControlWarning, match=rf"noise_std = {other:g} m/s\^2 in the data .* 0.5"
        ):
            check_emulator(emu, noise_std=other)
        with pytest.warns(ControlWarning, match=rf"with noise_std = {other:g} m/s\^2 but .* 0.5"):
            check_recorded_vehicle(emu, None, other)
    silent(check_emulator, emulator(noise_std=0.0), noise_std=0.0)
    with pytest.warns(ControlWarning, match="emulator metadata has no 'noise_std'"):
        check_emulator(emulator(), noise_std=0.0)
    silent(check_recorded_vehicle, emulator(), None, 0.5)  # no record: nothing to compare


@pytest.mark.parametrize(("value", "read"), [(0.7, 0.7), (0, None), (0.0, None), (-0.5, None),
                                             (float("inf"), None), (None, None)])  # fmt: skip
def test_the_training_noise_sd_is_a_positive_finite_number_or_none(value, read):
    emu = emulator() if value is None else emulator(noise_std=value)
    assert emulator_noise_std(emu) == read


def test_a_track_gd_inside_the_gd_domain_ends_included_is_accepted_and_one_outside_refused():
    emu = emulator()
    silent(check_emulator, emu, track=SimpleNamespace(segments=((1.0, 200.0), (1.0, 600.0))))
    for gd in (199.9, 600.1):
        track = SimpleNamespace(segments=((1.0, 400.0), (1.0, gd)))
        with pytest.raises(
            EmulatorMismatchError, match=rf"track GD \[{gd}\] outside .*\[200, 600\]"
        ):
            check_emulator(emu, track=track)


ROAD = {"dx_m": 0.006, "band": None}  # the training roads: a 6 mm grid, up to its Nyquist limit


def track(dx_m=0.006, band=(0.01, 0.5 / 0.006)):
    return SimpleNamespace(segments=((1.0, 400.0),), dx_m=dx_m, settings=SimpleNamespace(band=band))


@pytest.mark.parametrize(
    ("dx_m", "band", "named"),
    [
        (0.006 * 1.0009, (0.01, 83.3), ""),  # both within 0.1 %
        (0.006 * 1.0011, (0.01, 0.5 / 0.006), "dx_m = "),
        (0.006 * 0.9989, (0.01, 0.5 / 0.006), "dx_m = "),
        (0.006, (0.01, 0.5 / 0.006 * 1.0011), "band up to "),
        (0.006, (0.01, 0.5 / 0.006 * 0.9989), "band up to "),
        (0.006, (0.01, 0.5 / 0.006 * 0.9991), ""),
    ],
)
def test_a_track_road_is_named_where_its_grid_or_band_differs_by_more_than_a_thousandth(
    dx_m, band, named
):
    why = _track_road_mismatch({"road": ROAD}, track(dx_m, band))
    if named:
        assert why.startswith(named) and ";" not in why
        with pytest.warns(ControlWarning, match=f"the track's road differs .*{named}"):
            check_emulator(emulator(road=ROAD), track=track(dx_m, band))
    else:
        assert why == ""
        silent(check_emulator, emulator(road=ROAD), track=track(dx_m, band))


def test_a_recorded_band_top_is_compared_with_the_tracks():
    road = {"dx_m": 0.006, "band": [0.01, 40.0]}
    assert _track_road_mismatch({"road": road}, track(band=(0.01, 40.0))) == ""
    why = _track_road_mismatch({"road": road}, track(band=(0.01, 0.5 / 0.006)))
    assert why == "band up to 83.3 cycles/m against 40 cycles/m"
    both = _track_road_mismatch({"road": road}, track(dx_m=0.02, band=(0.01, 25.0)))
    assert both == "dx_m = 0.02 m against 0.006 m; band up to 25 cycles/m against 40 cycles/m"


@pytest.mark.parametrize(
    "road", [{"dx_m": 0.0, "band": None}, {"dx_m": 0.006, "band": [0.01, "wide"]}]
)
def test_a_road_record_with_no_band_top_compares_the_grid_alone(road):
    """A grid step of 0 (no Nyquist limit) or a band whose top is not a number: the band is
    not compared (and nothing fails); the grid still is."""
    assert _track_road_mismatch({"road": road}, track(band=(0.01, 10.0))) == ""
    silent(check_emulator, emulator(road=road), track=track(band=(0.01, 10.0)))
    if road["dx_m"]:
        assert _track_road_mismatch({"road": road}, track(dx_m=0.02)).startswith("dx_m = 0.02")


def likelihood_for(emu):
    return SimpleNamespace(emulator=emu)


def predictor(scale=1.0):
    return lambda v, gd: scale * np.stack([np.asarray(v) * 0 + 1.0, np.log(gd)], axis=-1)


def test_a_likelihood_is_accepted_for_its_emulator_or_an_equal_one_and_refused_otherwise():
    emu = emulator(predict=predictor(), feature=BAND.to_dict(), noise_std=0.0)
    check_likelihood(emu, likelihood_for(emu))
    twin = emulator(predict=predictor(), feature=BAND.to_dict(), noise_std=0.0)
    check_likelihood(emu, likelihood_for(twin))  # same records, domain and predictions
    with pytest.raises(EmulatorMismatchError, match=r"metadata differ in \['noise_std'\]"):
        check_likelihood(emu, likelihood_for(emulator(predict=predictor(), feature=BAND.to_dict(),
                                                      noise_std=1.0)))  # fmt: skip
    with pytest.raises(EmulatorMismatchError, match=r"metadata differ in \['feature'\]"):
        check_likelihood(emu, likelihood_for(emulator(predict=predictor(), noise_std=0.0)))
    wider = emulator({"v": (0.5, 2.0), "GD": (200.0, 700.0)}, predictor(), feature=BAND.to_dict(),
                     noise_std=0.0)  # fmt: skip
    with pytest.raises(EmulatorMismatchError, match=r"domains or predictions differ"):
        check_likelihood(emu, likelihood_for(wider))
    off = emulator(predict=predictor(1 + 1e-9), feature=BAND.to_dict(), noise_std=0.0)
    with pytest.raises(EmulatorMismatchError, match=r"domains or predictions differ"):
        check_likelihood(emu, likelihood_for(off))
    with pytest.raises(EmulatorMismatchError, match=r"likelihood must be .* got SimpleNamespace"):
        check_likelihood(emu, SimpleNamespace())


def test_a_likelihood_whose_predictions_differ_at_one_probe_alone_is_refused():
    """The probe reads the domain's four corners and its centre: a change at any one is seen."""
    emu = emulator(predict=predictor())
    corners = [(0.5, 200.0), (0.5, 600.0), (2.0, 200.0), (2.0, 600.0), (1.25, 400.0)]
    for v0, g0 in corners:

        def bumped(v, gd, v0=v0, g0=g0):
            out = predictor()(v, gd)
            at = np.isclose(np.asarray(v), v0) & np.isclose(np.asarray(gd), g0)
            return out + at[:, None] * 1e-3

        with pytest.raises(EmulatorMismatchError, match=r"domains or predictions differ"):
            check_likelihood(emu, likelihood_for(emulator(predict=bumped)))


@pytest.mark.parametrize(
    ("low", "high", "up", "text"),
    [
        (0.0123, 0.5, True, "0.013"),  # low rounded up to 2 digits
        (0.0123, 0.5, False, "0.50"),  # high rounded down
        (0.0121, 0.0129, True, "0.0121"),  # 2 digits leave the range: 3
        (0.0121, 0.0129, False, "0.0129"),
        (0.01231, 0.01239, True, "0.01231"),  # 4
        (0.05, 0.5, True, "0.050"),  # exactly representable at 2 digits
        (0.3, 0.2, True, None),  # an empty range
        (0.0, 0.5, True, None),  # low not in (0, 1)
        (0.1, 1.0, False, None),  # high not in (0, 1)
    ],
)
def test_a_risk_text_is_the_shortest_in_the_range(low, high, up, text):
    assert _risk_text(low, high, up) == text


def test_a_simplex_at_the_gd_domains_ends_is_refused_and_one_just_inside_accepted():
    emu = emulator()  # GD domain [200, 600]; no predictions: the reach is not computed
    silent(check_emulator, emu, simplex=Simplex(gd_min=150, gd_max=200.001))
    silent(check_emulator, emu, simplex=Simplex(gd_min=150, gd_max=599.999))
    for gd_max, end in ((200, "above"), (600, "below")):
        with pytest.raises(EmulatorMismatchError, match=rf"gd_max = {gd_max} is not {end}"):
            check_emulator(emu, simplex=Simplex(gd_min=100, gd_max=gd_max))


class Post:
    """A stand-in of a GridMarginal with a given sd and (1 - risk) quantile."""

    def __init__(self, sd, q, above=0.5):
        self._sd, self._q, self._above = sd, q, above

    def sd(self):
        return self._sd

    def ppf(self, p):
        return self._q

    def cdf(self, x):
        return 1.0 - self._above


def test_the_mean_reach_takes_the_largest_sd_and_the_quantile_its_pick_default_the_largest():
    posts = [Post(5.0, 510.0), Post(20.0, 530.0), Post(10.0, 490.0)]
    assert _mean_reach(posts, 600.0) == (580.0, 20.0)
    assert _quantile(posts, 0.05) == 530.0
    assert _quantile(posts, 0.05, min) == 490.0
    assert _risk_above(
        [Post(1, 1, 0.2), Post(1, 1, 0.05), Post(1, 1, 0.1)], 500.0
    ) == pytest.approx(0.05)


@pytest.mark.parametrize(("gd_max", "warns"), [(530.0, False), (530.5, True)])
def test_a_gd_max_at_the_top_quantile_reach_is_within_reach_and_one_above_is_not(
    monkeypatch, gd_max, warns
):
    """``risk`` = alpha: the warning starts strictly above the smallest top quantile."""
    tops = [Post(1, 540.0, 0.3), Post(1, 530.0, 0.3), Post(1, 535.0, 0.3)]
    monkeypatch.setattr("control.compat.one_observation_posteriors",
                        lambda emu, speeds, ends=("top",): {"top": tops})  # fmt: skip
    emu = emulator(predict=predictor())
    simplex = Simplex(gd_min=300, gd_max=gd_max, risk=0.05)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        _warn_if_out_of_reach(emu, simplex)
    assert [("lies above 530" in str(w.message)) for w in seen] == ([True] if warns else [])


@pytest.mark.parametrize(("gd_max", "warns"), [(420.0, False), (419.5, True)])
def test_a_gd_max_at_the_bottom_quantile_is_accepted_and_one_below_warned_about(
    monkeypatch, gd_max, warns
):
    """Method "window" with ``risk``: the warning starts strictly below the bottom quantile
    at v_safe (the first speed)."""
    bottom = [Post(1, 420.0, 0.01), Post(1, 480.0, 0.01), Post(1, 480.0, 0.01)]
    posts = {"top": [Post(1, 590.0, 0.5)] * 3, "bottom": bottom}
    monkeypatch.setattr("control.compat.one_observation_posteriors",
                        lambda emu, speeds, ends=("top",): posts)  # fmt: skip
    emu = emulator(predict=predictor())
    simplex = Simplex(gd_min=300, gd_max=gd_max, risk=0.05)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        _warn_if_out_of_reach(emu, simplex, one_observation=True)
    assert [("lies below 420.0" in str(w.message)) for w in seen] == ([True] if warns else [])


def test_one_observation_posteriors_of_a_window_emulator_read_each_end_at_each_speed():
    """An emulator without a block_scatter (a window feature): one gpmsa.Calibrator, one
    observation (the emulator's mean) per speed, each of one output."""
    rng = np.random.default_rng(0)
    speed, gd = rng.uniform(0.5, 2.0, 14), rng.uniform(200.0, 600.0, 14)
    data = gpmsa.SimData(x=speed[:, None], t=gd[:, None], y=np.log(0.05 * gd * speed**1.3)[:, None])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        emu = gpmsa.fit(data, n_iter=20, tune=False, seed=0,
                        metadata={"feature": PAPER_WINDOW.to_dict()})  # fmt: skip
    posts = one_observation_posteriors(emu, [0.1, 1.0, 2.0], ("bottom", "top"))
    assert sorted(posts) == ["bottom", "top"]
    assert [len(posts[end]) for end in ("bottom", "top")] == [3, 3]
    lo, hi = emu.domain[emu.t_names[0]]
    for bottom, top in zip(posts["bottom"], posts["top"], strict=True):
        assert lo <= bottom.mean() < top.mean() <= hi
    # the speed below the domain is read at the domain's lowest speed
    assert posts["top"][0].mean() == pytest.approx(
        one_observation_posteriors(emu, [emu.domain[emu.x_names[0]][0]])["top"][0].mean()
    )
