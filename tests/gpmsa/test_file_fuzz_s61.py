"""Findings of the s61 file fuzz (/tmp/fileaudit/fuzz.py): hostile files that escaped the
readers as non-library exceptions. Each rewrites a real file as an attacker would (any
manifest, the content hash recomputed) and expects EmulatorFileError naming the field."""

import numpy as np
import pytest

import gpmsa
from gpmsa.io import container
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa._study_cases import two_model_study
from tests.gpmsa.test_file_hostile import read_members, write_zip


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    rng = np.random.default_rng(0)
    x, t = 0.5 + 1.5 * rng.random((16, 1)), 200 + 400 * rng.random((16, 1))
    sim = gpmsa.SimData(x=x, t=t, y=0.02 * t * x**1.6, x_names=["v"], t_names=["GD"])
    emu = gpmsa.fit(sim, n_iter=50, seed=1, tune=False)
    return emu.save(tmp_path_factory.mktemp("fuzz") / "e.gpmsa")


def _write(path, manifest, arrays):
    """A zip with this manifest (its hash recomputed) and these arrays."""
    manifest = dict(manifest, content_sha256=container.content_hash(arrays, manifest))
    return write_zip(path, manifest, arrays)


@pytest.mark.parametrize("dtype", [["<f8"], [["a", "<f8"]], {"descr": "<f8"}])
def test_an_array_dtype_that_is_not_a_string_is_refused(saved, tmp_path, dtype):
    """A JSON list or object as an array's declared dtype (numpy's structured-dtype spelling)
    was looked up in a set: TypeError (unhashable type) escaped ``gpmsa.load``."""
    manifest, arrays = read_members(saved)
    manifest["arrays"]["x_unit"]["dtype"] = dtype
    path = _write(tmp_path / "e.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="array 'x_unit' has dtype"):
        gpmsa.load(path)
    with pytest.raises(gpmsa.EmulatorFileError, match="array 'x_unit' has dtype"):
        read_raw(path)
    assert container.stored_format(path) == container.FORMAT  # the manifest alone reads


def _study_file(tmp_path):
    return two_model_study(n_samples=60, n_burn=20, tune_rounds=3).save(tmp_path / "run.gpmsa")


@pytest.mark.parametrize("sd_max", [1e155, 1e308])
def test_a_study_sd_max_whose_square_overflows_is_refused(tmp_path, sd_max):
    """priors.hyper.sd_max = 1e308 is a finite number > 0, but HyperPriors squares it:
    OverflowError escaped ``gpmsa.load_study``."""
    path = _study_file(tmp_path)
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["priors"]["hyper"]["sd_max"] = sd_max
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    with pytest.raises(gpmsa.EmulatorFileError, match="sd_max"):
        gpmsa.load_study(path)
