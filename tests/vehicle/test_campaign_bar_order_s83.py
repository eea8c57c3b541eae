"""A campaign whose own process pool cannot be made leaves no progress bar open (the bar was made
first, so tqdm kept it in its list and drew every later bar a line lower in a notebook)."""

import numpy as np
import pytest
from tqdm import tqdm

import vehicle
import vehicle.campaign as campaign


def test_a_pool_that_cannot_be_made_leaves_no_bar_open(monkeypatch):
    def refuse(*args, **kwargs):
        raise OSError("no more processes")

    monkeypatch.setattr(campaign, "ProcessPoolExecutor", refuse)
    before = len(tqdm._instances)
    design = np.array([[1.0, 300.0], [1.5, 400.0]])
    with pytest.raises(OSError, match="no more processes") as kept:  # its traceback kept,
        vehicle.run_campaign(design, road_length_m=6.0, window=300, lead_in_m=0.5, progress=True)
    assert kept.tb is not None  # as IPython keeps the last one: it would hold an open bar
    assert len(tqdm._instances) == before
