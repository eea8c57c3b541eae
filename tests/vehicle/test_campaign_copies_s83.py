"""A Campaign holds copies of the arrays it is built from. Before: ``status`` was the caller's
own array, so that writing into it later changed the campaign's ``ok`` mask and what it saved
(every other column was already copied)."""

from __future__ import annotations

import numpy as np

import vehicle


def test_a_campaign_does_not_follow_later_writes_into_the_callers_arrays(tmp_path):
    names = ("v", "gd", "f_full", "f_window", "f_full_noisy", "f_window_noisy")
    columns = {name: np.array([1.0, 2.0]) for name in names}
    seed, status = np.array([1, 2]), np.array(["ok", "ok"])
    camp = vehicle.Campaign(seed=seed, status=status, settings={}, **columns)
    status[1] = "diverged"
    seed[:] = 9
    for column in columns.values():
        column[:] = 5.0
    assert camp.ok.tolist() == [True, True] and camp.seed.tolist() == [1, 2]
    assert camp.v.tolist() == [1.0, 2.0] and camp.f_full.tolist() == [1.0, 2.0]
    camp.save(tmp_path / "c.npz")
    assert vehicle.load_campaign(tmp_path / "c.npz").status.tolist() == ["ok", "ok"]


def test_a_campaign_accepts_read_only_arrays():
    one = np.ones(2)
    one.flags.writeable = False
    status = np.array(["ok", "ok"])
    status.flags.writeable = False
    camp = vehicle.Campaign(v=one, gd=one, seed=np.broadcast_to(np.int64(3), (2,)), f_full=one,
                            f_window=one, f_full_noisy=one, f_window_noisy=one, status=status,
                            settings={})  # fmt: skip
    assert camp.ok.all() and camp.seed.tolist() == [3, 3]
