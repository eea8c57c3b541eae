"""Review of session 65's changes: what a user's saved objects and files meet afterwards."""

import pickle

import numpy as np
import pytest
from _calib_cases import road_emulator
from _study_cases import emulator, observations

import gpmsa


def test_a_calibrator_pickled_before_its_prepared_refinement_still_updates():
    # a Calibrator (or a BCR holding one, docs/robot.md "A saved BCR") pickled before session 65
    # has no prepared refinement: every update was an AttributeError ('_refined')
    emu = road_emulator()
    cal = gpmsa.Calibrator(emu, seed=0)
    state = dict(cal.__dict__)
    del state["_refined"]  # as such a pickle holds it
    restored = gpmsa.Calibrator.__new__(gpmsa.Calibrator)
    setstate = getattr(restored, "__setstate__", None)
    if setstate is None:  # pickle's own way for a class without one
        restored.__dict__.update(state)
    else:
        setstate(state)
    assert restored._refined is not None
    np.testing.assert_array_equal(restored._refined[0], cal._refined[0])
    post, want = restored.update([[1.25]], [[12.1]]), cal.update([[1.25]], [[12.1]])
    assert post.mean("GD") == want.mean("GD") and post.sd("GD") == want.sd("GD")
    again = pickle.loads(pickle.dumps(restored))  # and pickles on as a new one
    assert again.update([[1.25]], [[12.1]]).mean("GD") == want.mean("GD")


def test_a_hostile_held_theta_name_is_named_short():
    # a study file's settings["held_theta"] keyed by a 5,000-character name: the error quoted it
    # whole (file records name what is wrong in at most ~60 characters, studies.record._short)
    x, y = observations(0.4, 3, 0.03, np.random.default_rng(0))
    emu = emulator(None)
    held = {"theta": {"t": 0.4}}
    study = gpmsa.calibrate_study([emu, emu], [x, x], [y, y], shared=["t"], n_samples=20,
                                  n_burn=5, seed=1, tune=False, fixed=held)  # fmt: skip
    args = ("calibration", study.members, study.layout, study.hyper, study.draws)
    for edited, match in (({"x" * 5000: 0.4}, "is no study element"),
                          ({"t": "y" * 5000}, "must be a number")):  # fmt: skip
        with pytest.raises(gpmsa.GPMSAError, match=match) as got:
            gpmsa.Study(*args, {**study.settings, "held_theta": edited})
        assert len(str(got.value)) < 300
