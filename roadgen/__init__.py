"""ISO 8608 road profiles: synthesis, tracks, wheel enveloping, PSD estimate, road class.

>>> import roadgen
>>> p = roadgen.iso8608_profile(150.0, gd=450, seed=0)       # 6 mm grid, content up to 83 cycles/m
>>> round(roadgen.estimate_gd(p))
450
>>> roadgen.road_class(450)
'C'
>>> t = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=0)   # the paper's test track
>>> float(t.gd_at(75.0))
500.0
"""

from roadgen.envelope import wheel_envelope
from roadgen.errors import RoadgenError
from roadgen.iso8608 import GD_SCALE, N0, gd_spectrum, road_class
from roadgen.plotting import plot_profile_psd
from roadgen.profile import Profile, ProfileSettings, iso8608_profile
from roadgen.psd import FIT_BAND, estimate_gd, profile_psd, psd_slope
from roadgen.road import Road
from roadgen.track import Track, track

__all__ = [
    "FIT_BAND",
    "GD_SCALE",
    "N0",
    "Profile",
    "ProfileSettings",
    "Road",
    "RoadgenError",
    "Track",
    "estimate_gd",
    "gd_spectrum",
    "iso8608_profile",
    "plot_profile_psd",
    "profile_psd",
    "psd_slope",
    "road_class",
    "track",
    "wheel_envelope",
]
