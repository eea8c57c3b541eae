"""ProfileSettings' band (session 82): given as a list or an array it was kept as given, so
that the frozen settings were unhashable (a list, an array) and ``==`` between two of them
raised "truth value of an array is ambiguous"; it is stored as a tuple of two floats."""

import copy
import pickle

import numpy as np

import roadgen
from roadgen import ProfileSettings


def test_a_band_given_as_a_list_or_an_array_is_stored_as_a_tuple_of_floats():
    made = [ProfileSettings(band, "rayleigh", 2.0, 1, 0.5)
            for band in ((0.5, 20.0), [0.5, 20.0], np.array([0.5, 20.0]),
                         (np.float64(0.5), np.int64(20)))]  # fmt: skip
    for s in made:
        assert s.band == (0.5, 20.0) and all(type(v) is float for v in s.band)
        assert s == made[0] and hash(s) == hash(made[0])
    assert len(set(made)) == 1


def test_a_profile_and_its_settings_copy_and_pickle_as_they_were():
    p = roadgen.iso8608_profile(5.0, 300.0, seed=2, band=np.array([0.5, 20.0]))
    for twin in (copy.copy(p), copy.deepcopy(p), pickle.loads(pickle.dumps(p, 2)),
                 pickle.loads(pickle.dumps(p, pickle.HIGHEST_PROTOCOL))):  # fmt: skip
        assert twin.settings == p.settings and hash(twin.settings) == hash(p.settings)
        np.testing.assert_array_equal(twin.z, p.z)
