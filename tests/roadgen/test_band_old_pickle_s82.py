"""A ProfileSettings pickled with its band as given (a list or an array, before the band was
stored as a tuple) loads with the tuple of two floats: it kept the list, so that it did not
hash and did not compare equal to the same settings made anew."""

import pickle

import numpy as np

import roadgen
from roadgen import ProfileSettings


def _as_pickled_before(band) -> bytes:
    """The pickle of settings whose band was kept as given (what the library stored before)."""
    settings = ProfileSettings((0.5, 20.0), "rayleigh", 2.0, 1, 0.5)
    object.__setattr__(settings, "band", band)
    return pickle.dumps(settings, pickle.HIGHEST_PROTOCOL)


def test_settings_pickled_with_a_list_or_array_band_load_with_a_tuple():
    fresh = ProfileSettings([0.5, 20.0], "rayleigh", 2.0, 1, 0.5)
    for band in ([0.5, 20.0], np.array([0.5, 20.0])):
        back = pickle.loads(_as_pickled_before(band))
        assert back.band == (0.5, 20.0) and all(type(v) is float for v in back.band)
        assert back == fresh and hash(back) == hash(fresh)


def test_a_profiles_settings_pickle_as_they_were():
    p = roadgen.iso8608_profile(5.0, 300.0, seed=2)
    back = pickle.loads(pickle.dumps(p, pickle.HIGHEST_PROTOCOL))
    assert back.settings == p.settings and type(back.settings.band) is tuple
    np.testing.assert_array_equal(back.z, p.z)
