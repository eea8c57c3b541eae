"""The campaign's up-front road check for a faster robot (session 64)."""

import numpy as np
import pytest

import vehicle


def test_the_window_check_reads_the_road_that_keep_s_lengthens():
    """With ``keep_s`` every road is lengthened to hold it, but the window check read
    ``road_length_m`` alone: a 3 m/s robot was refused (``road_length_m=21.0 is too short``)
    with keep_s = 20 s, whose roads are 64 m long. Here: a 3 m road, a 240-sample window at
    1 m/s (2 m of road after the lead-in), kept 3 s (the road becomes 5.3 m)."""
    kw = dict(road_length_m=3.0, window=240, noise_std=0.0, progress=False, seed=0,
              executor=None)  # fmt: skip
    design = np.array([[1.0, 300.0]])
    with pytest.raises(vehicle.VehicleError, match="road_length_m=3.0 is too short"):
        vehicle.run_campaign(design, **kw)  # nothing kept: the road stays 3 m
    campaign = vehicle.run_campaign(design, keep_s=3.0, **kw)
    assert campaign.ok.all() and campaign.accel.shape == (1, 360)
    assert np.isfinite(campaign.f_window).all()
