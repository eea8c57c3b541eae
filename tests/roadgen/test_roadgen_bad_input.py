"""Bad types and shapes (bools, strings, complex numbers, ragged or non-numeric arrays) raise
RoadgenError naming the argument; numpy integers, floats and 0-d arrays are numbers."""

import json

import numpy as np
import pytest

import roadgen

ROAD = roadgen.iso8608_profile(5.0, 300.0, seed=0, lead_in_m=0.5)
PLAIN = roadgen.Road(x=np.arange(64) * 0.1, z=0.01 * np.sin(np.arange(64.0)), dx_m=0.1)


class Heights:
    """A road-like object (z, dx_m) that is not a roadgen Road."""

    def __init__(self, z, dx_m):
        self.z, self.dx_m = z, dx_m


def profile(**kw):
    return roadgen.iso8608_profile(**({"length_m": 5.0, "gd": 300.0, "seed": 0} | kw))


@pytest.mark.parametrize("name", ["length_m", "gd", "dx_m", "waviness", "lead_in_m"])
@pytest.mark.parametrize(
    ("value", "kind"), [(True, "bool"), ("1", "str"), (1 + 0j, "complex"), ([2.0], "list")]
)
def test_profile_scalars_must_be_real_numbers(name, value, kind):
    match = rf"^{name}=.* must be a real number \(got {kind}\)"
    with pytest.raises(roadgen.RoadgenError, match=match):
        profile(**{name: value})


def test_numpy_numbers_and_0d_arrays_are_numbers():
    ref = profile(length_m=5.0, gd=300.0, dx_m=0.006, lead_in_m=0.5)
    got = profile(length_m=np.int64(5), gd=np.float32(300.0), dx_m=np.array(0.006),
                  lead_in_m=np.float64(0.5))  # fmt: skip
    np.testing.assert_array_equal(got.z, ref.z)
    assert type(got.gd) is float and type(got.dx_m) is float
    json.dumps({"gd": got.gd, "dx_m": got.dx_m})


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: profile(band=(True, 2.0)), r"^band\[0\]=True must be a real number \(got bool\)"),
        (lambda: profile(band=("1", "2")), r"^band\[0\]='1' must be a real number \(got str\)"),
        (lambda: profile(band=(1.0, 2j)), r"^band\[1\]=2j must be a real number"),
        (lambda: profile(band="12"), r"^band='12' must be a pair"),
        (lambda: profile(amplitudes=np.array(["rayleigh", "x"])), r"^amplitudes=.*not allowed"),
        (lambda: profile(amplitudes=None), r"^amplitudes=None is not allowed"),
        (lambda: profile(seed=1.5), r"^seed=1.5 must be"),
        (lambda: roadgen.track([(True, 300)]), r"^segments\[0\] length_m=True must be a real"),
        (lambda: roadgen.track([(5.0, "300")]), r"^segments\[0\] gd='300' must be a real"),
        (lambda: roadgen.track([(5.0, 300)], blend_m="1"), r"^blend_m='1' must be a real"),
        (lambda: roadgen.track([(5.0, 300)], lead_in_m=1j), r"^lead_in_m=1j must be a real"),
    ],
)  # fmt: skip
def test_generator_arguments_of_the_wrong_type_raise(make, match):
    with pytest.raises(roadgen.RoadgenError, match=match):
        make()


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("1", r"^s must be an array of real numbers, got dtype <U1"),
        (True, r"^s must be an array of real numbers, got dtype bool"),
        (["1", "2"], r"^s must be an array of real numbers, got dtype <U1"),
        ([[1.0], [1.0, 2.0]], r"^s must be an array of real numbers: .*inhomogeneous"),
        ([1j], r"^s must be an array of real numbers, got dtype complex128"),
        ([True, False], r"^s must be an array of real numbers, got dtype bool"),
        (None, r"^s must be an array of real numbers, got dtype object"),
    ],
)
def test_positions_must_be_real_arrays(value, match):
    for query in (ROAD.height_at, ROAD.gd_at):
        with pytest.raises(roadgen.RoadgenError, match=match):
            query(value)
    assert ROAD.height_at(np.int64(1)) == ROAD.height_at(1.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"x": [[0.0, 1.0], [2.0]]}, r"^x must be an array of real numbers: "),
        ({"x": [0j, 1j]}, r"^x must be an array of real numbers, got dtype complex"),
        ({"z": ["0", "0"]}, r"^z must be an array of real numbers, got dtype <U1"),
        ({"z": [True, False]}, r"^z must be an array of real numbers, got dtype bool"),
        ({"z": [object(), object()]}, r"^z must be an array of real numbers, got dtype object"),
        ({"dx_m": True}, r"^dx_m=True must be a real number \(got bool\)"),
    ],
)
def test_road_arrays_must_be_real(kwargs, match):
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.Road(**({"x": [0.0, 1.0], "z": [0.0, 0.0], "dx_m": 1.0} | kwargs))


def test_profile_and_track_records_check_their_fields():
    fields = {"x": ROAD.x, "z": ROAD.z, "dx_m": ROAD.dx_m, "settings": ROAD.settings}
    for gd, match in (
        ("a", r"^gd='a' must be a real number"),
        (-1.0, r"^gd=-1.0 is out of range"),
        (np.nan, r"^gd=nan must be finite"),
        (True, r"^gd=True must be a real"),
    ):
        with pytest.raises(roadgen.RoadgenError, match=match):
            roadgen.Profile(**fields, gd=gd)
    trk = roadgen.track([(3, 300), (3, 500)], seed=0, lead_in_m=0.5)
    base = {name: getattr(trk, name) for name in trk.__dataclass_fields__}
    for change, match in (
        ({"segments": ((3.0, 300.0), (3.0, "500"))}, r"^segments\[1\] gd='500'"),
        ({"boundaries_m": (0.0,)}, r"^boundaries_m=\(0.0,\) must hold one"),
        ({"boundaries_m": ("0", "3")}, r"^boundaries_m must be an array of real numbers"),
        ({"blend_m": True}, r"^blend_m=True must be a real"),
        ({"lead_in_m": -1.0}, r"^lead_in_m=-1.0 is out of range"),
    ):
        with pytest.raises(roadgen.RoadgenError, match=match):
            roadgen.Track(**(base | change))


PSD = roadgen.profile_psd


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: roadgen.wheel_envelope(None, 0.1), r"^road=NoneType is not allowed"),
        (lambda: roadgen.wheel_envelope(Heights(ROAD.z, 0.006), 0.1), r"^road=Heights is not"),
        (lambda: roadgen.wheel_envelope(ROAD, True), r"^radius_m=True must be a real number"),
        (lambda: PSD(None), r"^road=NoneType must have heights z"),
        (lambda: PSD([0.0, 1.0]), r"^road=list must have heights z"),
        (lambda: PSD(Heights(["0"] * 9, 0.1)), r"^road.z must be an array of real numbers"),
        (lambda: PSD(Heights(np.zeros((3, 3)), 0.1)), r"^road.z has shape \(3, 3\)"),
        (lambda: PSD(Heights([0.0, np.nan], 0.1)), r"^road.z contains NaN"),
        (lambda: PSD(Heights(np.zeros(9), "0.1")), r"^road.dx_m='0.1' must be a real number"),
        (lambda: PSD(ROAD, "welch", 8.7), r"^nperseg=8.7 must be an integer >= 8 \(got float\)"),
        (lambda: PSD(ROAD, "welch", "10"), r"^nperseg='10' must be an integer"),
        (lambda: PSD(ROAD, "welch", True), r"^nperseg=True must be an integer"),
        (lambda: PSD(ROAD, "welch", np.nan), r"^nperseg=nan must be an integer"),
        (lambda: PSD(ROAD, "welch", 4), r"^nperseg=4 is out of range: allowed integers >= 8"),
        (lambda: PSD(ROAD, end_match="no"), r"^end_match='no' must be True or False \(got str\)"),
        (lambda: PSD(ROAD, end_match=0), r"^end_match=0 must be True or False"),
        (lambda: PSD(ROAD, np.array(["welch", "x"])), r"^method=.*is not allowed"),
        (lambda: roadgen.estimate_gd(None), r"^road=NoneType must have heights z"),
        (lambda: roadgen.estimate_gd(ROAD, waviness="2"), r"^waviness='2' must be a real"),
        (lambda: roadgen.estimate_gd(ROAD, band=("0.1", "1")), r"^band\[0\]='0.1' must be a"),
        (lambda: roadgen.psd_slope(None), r"^road=NoneType must have heights z"),
        (lambda: roadgen.road_class(True), r"^gd=True must be a real number \(got bool\)"),
        (lambda: roadgen.road_class("C"), r"^gd='C' must be a real number \(got str\)"),
        (lambda: roadgen.plot_profile_psd(None), r"^road=NoneType is not allowed"),
    ],
)
def test_psd_and_envelope_arguments_of_the_wrong_type_raise(call, match):
    with pytest.raises(roadgen.RoadgenError, match=match):
        call()


def test_numpy_integers_and_numpy_bools_are_accepted_by_the_psd():
    a = roadgen.profile_psd(ROAD, "welch", nperseg=16)
    b = roadgen.profile_psd(ROAD, "welch", nperseg=np.int64(16))
    np.testing.assert_array_equal(a[1], b[1])
    c = roadgen.profile_psd(ROAD, end_match=np.bool_(True))
    np.testing.assert_array_equal(c[1], roadgen.profile_psd(ROAD, end_match=True)[1])
    assert roadgen.road_class(np.int64(450)) == roadgen.road_class(np.array(450.0)) == "C"


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (([[1.0], [1.0, 2.0]], 300.0), r"^n must be an array of real numbers: "),
        ((["1", "2"], 300.0), r"^n must be an array of real numbers, got dtype <U1"),
        (([1j], 300.0), r"^n must be an array of real numbers, got dtype complex"),
        (([True], 300.0), r"^n must be an array of real numbers, got dtype bool"),
        (([1.0, 0.0], 300.0), r"^n contains 0.0: allowed frequencies in \(0, inf\)"),
        (([-1.0], 300.0), r"^n contains -1.0"),
        (([np.nan], 300.0), r"^n contains nan"),
        (([1.0], "a"), r"^gd='a' must be a real number"),
        (([1.0], -1.0), r"^gd=-1.0 is out of range"),
        (([1.0], None), r"^gd=None must be a real number"),
        (([1.0], 300.0, None), r"^waviness=None must be a real number"),
        (([1.0], 300.0, np.nan), r"^waviness=nan must be finite"),
    ],
)
def test_gd_spectrum_checks_its_arguments(args, match):
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.gd_spectrum(*args)


def test_a_plain_road_is_plotted_without_a_prescribed_line():
    fig = roadgen.plot_profile_psd(PLAIN)
    labels = [line.get_label() for line in fig.axes[1].get_lines()]
    assert not any(label.startswith("prescribed") for label in labels)


@pytest.mark.parametrize(
    "call",
    [
        lambda road: roadgen.estimate_gd(road),
        lambda road: roadgen.estimate_gd(road, method="welch"),
        lambda road: roadgen.estimate_gd(road, method="periodogram"),
        lambda road: roadgen.profile_psd(road),
        lambda road: roadgen.psd_slope(road),
    ],
)
def test_heights_whose_psd_overflows_are_refused_not_read_as_inf(call):
    road = roadgen.iso8608_profile(length_m=200.0, gd=300.0, seed=1)
    huge = Heights(road.z * 1e200, road.dx_m)
    with pytest.raises(roadgen.RoadgenError, match=r"heights up to .* overflows float64"):
        call(huge)
    assert np.isfinite(call(Heights(road.z * 1e150, road.dx_m))).all()  # large, still finite
