"""theta_init (and fit's fixed['theta']) as a dict by the calibration parameters' names, as a
pandas Series by its labels already was: a dict was refused ('must be a numeric array, got
dict'), found in a SEPIA-user walkthrough."""

import numpy as np
import pytest
from _calib_cases import two_param_emulator

import gpmsa
from gpmsa.errors import GPMSAError


def test_a_dict_theta_init_is_read_by_name():
    emu = two_param_emulator()
    x, y = [[0.3], [0.6]], [[0.9], [1.1]]
    kw = {"n_samples": 30, "n_burn": 0, "tune": False, "seed": 2}
    by_list = gpmsa.calibrate(emu, x, y, theta_init=[0.3, 0.7], **kw)
    by_dict = gpmsa.calibrate(emu, x, y, theta_init={"b": 0.7, "a": 0.3}, **kw)
    for name in ("a", "b"):
        np.testing.assert_array_equal(by_list.samples[name], by_dict.samples[name])
    with pytest.raises(GPMSAError, match=r"theta_init has the keys \['a'\]; expected \['a', 'b'\]"):
        gpmsa.calibrate(emu, x, y, theta_init={"a": 0.3}, **kw)
