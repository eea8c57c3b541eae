"""Bad-input audit (session 75): ProfileSettings refuses, where it is made, the fields that no
road can have been made with (it took any value; the error came only when a Profile or Track
was built with it, or never for a settings record kept on its own)."""

import math

import pytest

import roadgen
from roadgen import ProfileSettings, RoadgenError

GOOD = dict(band=(0.1, 10.0), amplitudes="deterministic", waviness=2.0, seed=0, lead_in_m=0.0)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("band", "x"),
        ("band", (1.0,)),
        ("band", (math.nan, 1.0)),
        ("band", (2.0, 1.0)),
        ("band", (0.0, 1.0)),
        ("band", (1.0, math.inf)),
        ("amplitudes", "gauss"),
        ("amplitudes", 3),
        ("waviness", math.nan),
        ("waviness", 0.0),
        ("waviness", 9.0),
        ("waviness", "2"),
        ("seed", -1),
        ("seed", "0"),
        ("seed", 1.5),
        ("lead_in_m", -1.0),
        ("lead_in_m", math.inf),
        ("lead_in_m", None),
    ],
)
def test_profile_settings_refuses_a_bad_field_naming_it(field, value):
    with pytest.raises(RoadgenError, match=field):
        ProfileSettings(**{**GOOD, field: value})


def test_profile_settings_made_by_the_generators_still_pass():
    p = roadgen.iso8608_profile(5.0, 300.0, seed=0, band=(0.5, 20.0), lead_in_m=1.0)
    assert p.settings == ProfileSettings((0.5, 20.0), "deterministic", 2.0, 0, 1.0)
    t = roadgen.track([(3, 300), (3, 500)], seed=None)
    assert t.settings.seed is None and t.settings.lead_in_m == 1.0


def test_a_road_still_bounds_its_settings_by_its_grid_and_length():
    p = roadgen.iso8608_profile(5.0, 300.0, seed=0)
    above_nyquist = ProfileSettings((0.5, 100.0), "deterministic", 2.0, 0, 0.0)
    with pytest.raises(RoadgenError, match="settings.band"):
        roadgen.Profile(x=p.x, z=p.z, dx_m=p.dx_m, gd=300.0, settings=above_nyquist)
    too_long = ProfileSettings(p.settings.band, "deterministic", 2.0, 0, 6.0)
    with pytest.raises(RoadgenError, match="settings.lead_in_m"):
        roadgen.Profile(x=p.x, z=p.z, dx_m=p.dx_m, gd=300.0, settings=too_long)
