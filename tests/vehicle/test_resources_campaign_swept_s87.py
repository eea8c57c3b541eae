"""A long-running process that saves campaigns into ever new folders holds a bounded record.

`vehicle.campaign` remembers each folder it has swept of stale temporaries, so that a cache
folder is listed once a process, not at every run's save. The record kept every folder for
good: saving a campaign into a new folder per job grew it by ~90 B a save (2,000 saves, 2,003
names held). It now holds `_SWEPT_FOLDERS` names at most and starts afresh past that.
"""

import numpy as np

from vehicle import campaign


def test_campaign_saves_into_many_new_folders_keep_a_bounded_record(tmp_path, monkeypatch):
    monkeypatch.setattr(campaign, "_SWEPT", set())
    monkeypatch.setattr(campaign, "_SWEPT_FOLDERS", 16, raising=False)
    sizes = []
    for k in range(200):
        folder = tmp_path / f"job-{k}"
        folder.mkdir()
        campaign._save_npz(folder / "c.npz", {"f": np.arange(3.0)})
        sizes.append(len(campaign._SWEPT))
    assert max(sizes) <= 16  # before: 200 names, one a folder
    with np.load(tmp_path / "job-199" / "c.npz") as z:
        assert z["f"].tolist() == [0.0, 1.0, 2.0]
