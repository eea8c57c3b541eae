"""Bad input to the generators and to the Road classes raises RoadgenError naming the argument."""

import numpy as np
import pytest

import roadgen


def test_roadgen_error_is_a_value_error():
    assert issubclass(roadgen.RoadgenError, ValueError)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"length_m": 0.0}, r"length_m=0.0 is out of range: allowed \(0, inf\)"),
        ({"length_m": -3.0}, "length_m=-3.0"),
        ({"length_m": np.nan}, "length_m=nan must be finite"),
        ({"length_m": np.inf}, "length_m=inf must be finite"),
        ({"gd": 0.0}, r"gd=0.0 is out of range: allowed \[1e-12, inf\)"),
        ({"gd": -1.0}, "gd=-1.0"),
        ({"gd": np.nan}, "gd=nan"),
        ({"gd": "rough"}, "gd='rough' must be a real number"),
        ({"dx_m": 0.0}, "dx_m=0.0"),
        ({"dx_m": -0.006}, "dx_m=-0.006"),
        ({"dx_m": np.inf}, "dx_m=inf"),
        (
            {"dx_m": 20.0},
            r"dx_m=20.0 is out of range for length_m=21.0: allowed \(0, length_m / 1.5\]",
        ),
        ({"waviness": 0.0}, "waviness=0.0"),
        ({"waviness": np.nan}, "waviness=nan"),
        ({"waviness": 1000.0}, r"^waviness=1000.0 is out of range: allowed \(0, 5\]"),
        ({"amplitudes": "gaussian"}, "amplitudes='gaussian'.*deterministic"),
        ({"band": (0.0, 10.0)}, r"band=\(0.0, 10.0\) is out of range: need 0 < n_min"),
        ({"band": (1.0, 90.0)}, r"band=\(1.0, 90.0\).*<= 83.33"),
        ({"band": (5.0, 1.0)}, "band="),
        ({"band": (np.nan, 1.0)}, "band="),
        ({"band": (1.0, np.inf)}, "band="),
        ({"band": (1.0,)}, "must be a pair"),
        ({"band": (0.01, 1.0)}, r"length_m=21 is too short for band=\(0.01, 1.0\).*>= 99.99"),
        ({"band": (0.101, 0.102)}, "holds no harmonic"),
        ({"lead_in_m": -1.0}, r"lead_in_m=-1.0 is out of range: allowed \[0, inf\)"),
        ({"lead_in_m": 30.0}, r"lead_in_m=30.0 is out of range: allowed \[0, 21\] m"),
    ],
)
def test_bad_profile_input_raises(kwargs, match):
    args = {"length_m": 21.0, "gd": 300.0, "seed": 0} | kwargs
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.iso8608_profile(**args)


def test_road_classes_validate_their_arrays():
    road = roadgen.iso8608_profile(1.0, 300.0, seed=0)
    fields = {"dx_m": road.dx_m, "gd": 300.0, "settings": road.settings}
    with pytest.raises(roadgen.RoadgenError, match="same length"):
        roadgen.Profile(x=road.x, z=road.z[:-1], **fields)
    with pytest.raises(roadgen.RoadgenError, match="finite"):
        roadgen.Profile(x=road.x, z=np.where(road.x > 0.5, np.nan, road.z), **fields)
    with pytest.raises(roadgen.RoadgenError, match="uniform grid"):
        roadgen.Profile(x=road.x**2, z=road.z, **fields)
    with pytest.raises(roadgen.RoadgenError, match="dx_m=0"):
        roadgen.Profile(x=road.x, z=road.z, dx_m=0, gd=300.0, settings=road.settings)


def test_waviness_is_bounded_and_gd_spectrum_refuses_an_overflow():
    road = roadgen.iso8608_profile(21.0, 300.0, seed=0, waviness=5.0)  # the largest allowed
    assert roadgen.estimate_gd(road) == pytest.approx(300.0, rel=0.01)
    with pytest.raises(roadgen.RoadgenError, match=r"^waviness=5.5 is out of range"):
        roadgen.estimate_gd(road, waviness=5.5)
    with pytest.raises(roadgen.RoadgenError, match=r"^waviness=6 is out of range"):
        roadgen.gd_spectrum([1.0], 300.0, 6)
    assert np.isfinite(roadgen.gd_spectrum([1e-150], 450.0))
    with pytest.raises(roadgen.RoadgenError, match=r"^n contains 1e-200: Gd\(n\) overflows.*"
                       r"above about 1.58e-157 cycles/m"):  # fmt: skip
        roadgen.gd_spectrum([1.0, 1e-200], 450.0)
