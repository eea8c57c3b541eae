"""A saved emulator's metadata comes back in the order the user wrote it: the file's manifest was
written with its keys sorted, so ``{"zeta": 1, "alpha": {"z": 2, "b": 3}}`` loaded as
``{"alpha": {"b": 3, "z": 2}, "zeta": 1}``. The content hash stays canonical (sorted keys), so
a file's ``content_sha256`` does not depend on the order, and files written sorted still load."""

import json
import warnings
import zipfile

import numpy as np

import gpmsa
from gpmsa.io.container import read_raw


def _fit(metadata: dict) -> gpmsa.Emulator:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        return gpmsa.fit(gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t), n_iter=10, tune=False,
                         seed=1, progress=False, metadata=metadata)  # fmt: skip


def test_metadata_keys_come_back_in_the_users_order(tmp_path):
    meta = {"zeta": 1, "alpha": {"z": 2, "b": 3}, "mid": [{"y": 1, "x": 2}]}
    _fit(meta).save(tmp_path / "e.gpmsa")
    loaded = gpmsa.load(tmp_path / "e.gpmsa")
    assert json.dumps(loaded.metadata) == json.dumps(meta)  # order too (sorted before)


def test_the_content_hash_does_not_depend_on_the_order_and_a_sorted_file_loads(tmp_path):
    emu = _fit({"zeta": 1, "alpha": 2})
    path = emu.save(tmp_path / "e.gpmsa")
    manifest, _ = read_raw(path)
    # the same file with its manifest written sorted, as before: same hash, loads, same record
    with zipfile.ZipFile(path) as zf:
        members = {i.filename: zf.read(i) for i in zf.infolist()}
    members["manifest.json"] = json.dumps(manifest, indent=1, sort_keys=True).encode()
    sorted_path = tmp_path / "sorted.gpmsa"
    with zipfile.ZipFile(sorted_path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    again = gpmsa.load(sorted_path, sha256=manifest["content_sha256"])
    assert again.metadata == {"alpha": 2, "zeta": 1} and list(again.metadata) == ["alpha", "zeta"]
    assert again.model_sha256 == emu.model_sha256
