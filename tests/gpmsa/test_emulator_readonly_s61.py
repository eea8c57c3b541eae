"""An Emulator's arrays are read-only after construction, so that its cached ``model_sha256``
(which posteriors and Calibrator records compare) always describes what it predicts with.
Before: ``emu.w[0] = 5``, ``emu.params["lamUz"][0] = 2`` or ``emu.K *= 2`` changed the
predictions and left the digest of the emulator as constructed."""

from __future__ import annotations

import copy
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest

import gpmsa

sys.path.insert(0, str(Path(__file__).parent))
from _study_cases import PARAMS, sim_data  # noqa: E402

READ_ONLY = "read-only"

IN_PLACE = {
    "w": lambda e: e.w.__setitem__((0, 0), 5.0),
    "K": lambda e: np.multiply(e.K, 2.0, out=e.K),
    "y": lambda e: e.y.__setitem__(Ellipsis, 0.0),
    "x_unit": lambda e: e.x_unit.__setitem__((0, 0), 0.3),
    "t_unit": lambda e: e.t_unit.__setitem__((0, 0), 0.3),
    "lam_sim": lambda e: e.lam_sim.__setitem__(0, 1.0),
    "log_post": lambda e: e.log_post.__setitem__(0, 1.0),
    "params": lambda e: e.params["lamUz"].__setitem__(0, 2.0),
    "draws": lambda e: e.draws["betaU"].__setitem__(0, 1.0),
    "calibration": lambda e: e.calibration["theta"].__setitem__(0, 0.5),
    "standardizer": lambda e: e.standardizer.y_mean.__setitem__(0, 1.0),
    "grid": lambda e: e.standardizer.grid.__setitem__(0, 1.0),
}


@pytest.fixture(scope="module")
def fitted() -> gpmsa.Emulator:
    """A joint sim+obs fit: draws, log_post and calibration draws."""
    x = np.linspace(0.1, 0.9, 4)[:, None]
    obs = gpmsa.ObsData(x=x, y=np.sin(3 * x) + 0.5)
    return gpmsa.fit(sim_data(), obs=obs, n_iter=40, seed=0, tune=False, progress=False)


@pytest.mark.parametrize("what", sorted(IN_PLACE))
def test_in_place_changes_are_refused_and_the_digest_holds(fitted, what):
    sha = fitted.model_sha256
    mean = fitted.predict([[0.5]], [[0.5]])[0]
    with pytest.raises(ValueError, match=READ_ONLY):
        IN_PLACE[what](fitted)
    fitted.__dict__.pop("model_sha256")  # recomputed from the arrays: unchanged
    assert fitted.model_sha256 == sha
    np.testing.assert_array_equal(fitted.predict([[0.5]], [[0.5]])[0], mean)


@pytest.mark.parametrize("name", ["params", "draws", "calibration"])
def test_its_parameter_mappings_take_no_new_keys_or_values(fitted, name):
    mapping = getattr(fitted, name)
    key = next(iter(mapping))
    with pytest.raises(TypeError, match="does not support item assignment"):
        mapping[key] = np.zeros_like(mapping[key])
    with pytest.raises(AttributeError):
        mapping.pop(key)


def test_the_callers_arrays_are_copied_not_frozen():
    sim = sim_data()
    params = {k: np.array(v) for k, v in PARAMS.items()}
    emu = gpmsa.Emulator.from_params(sim, params)
    before = emu.predict([[0.5]], [[0.5]])[0]
    sim.y[...] += 1.0  # still writable, and no longer the emulator's
    params["lamUz"][0] = 7.0
    assert emu.params["lamUz"][0] == 1.0
    np.testing.assert_array_equal(emu.y, sim_data().y)  # before: emu.y was sim.y
    np.testing.assert_array_equal(emu.predict([[0.5]], [[0.5]])[0], before)
    again = gpmsa.Emulator.from_params(sim_data(), emu.params)  # its params as a dict
    assert again.model_sha256 == emu.model_sha256


@pytest.mark.parametrize("how", ["pickle", "copy", "deepcopy"])
def test_pickled_and_copied_emulators_are_read_only_with_the_same_digest(fitted, how):
    clone = {
        "pickle": lambda e: pickle.loads(pickle.dumps(e)),
        "copy": copy.copy,
        "deepcopy": copy.deepcopy,
    }[how](fitted)
    clone.__dict__.pop("model_sha256", None)
    assert clone.model_sha256 == fitted.model_sha256
    with pytest.raises(ValueError, match=READ_ONLY):
        clone.w[0, 0] = 5.0
    with pytest.raises(TypeError, match="does not support item assignment"):
        clone.draws["lamUz"] = clone.draws["lamUz"] * 2


def test_a_saved_and_loaded_emulator_is_read_only(fitted, tmp_path):
    loaded = gpmsa.load(fitted.save(tmp_path / "e.gpmsa"))
    assert loaded.model_sha256 == fitted.model_sha256
    with pytest.raises(ValueError, match=READ_ONLY):
        loaded.params["betaU"][0, 0] = 2.0


REPLACED = {
    "w": lambda e: np.zeros_like(e.w),
    "params": lambda e: dict(e.params, lamUz=np.asarray(e.params["lamUz"]) * 1e3),
    "priors": lambda e: gpmsa.Priors(theta_sd=0.1),
    "draws": lambda e: {},
    "t_names": lambda e: ("other",),
    "standardizer": lambda e: e.standardizer,
    "settings": lambda e: {},
}


@pytest.mark.parametrize("name", sorted(REPLACED))
def test_replacing_an_attribute_is_refused_and_the_digest_holds(fitted, name):
    """Before session 62, ``emu.priors = other`` or ``emu.w = other`` replaced the attribute and
    kept the cached ``model_sha256`` (and the cached factors) of the emulator as constructed."""
    sha = fitted.model_sha256
    with pytest.raises(AttributeError, match=rf"Emulator\.{name} cannot be replaced.*from_params"):
        setattr(fitted, name, REPLACED[name](fitted))
    with pytest.raises(AttributeError, match=rf"Emulator\.{name} cannot be deleted"):
        delattr(fitted, name)
    fitted.__dict__.pop("model_sha256")
    assert fitted.model_sha256 == sha


@pytest.mark.parametrize("how", ["pickle", "copy", "load", "with_calibration_priors"])
def test_every_way_to_another_emulator_keeps_it_sealed_and_metadata_free(fitted, how, tmp_path):
    other = {
        "pickle": lambda: pickle.loads(pickle.dumps(fitted)),
        "copy": lambda: copy.deepcopy(fitted),
        "load": lambda: gpmsa.load(fitted.save(tmp_path / "e.gpmsa")),
        "with_calibration_priors": lambda: fitted.with_calibration_priors(theta_sd=0.3),
    }[how]()
    with pytest.raises(AttributeError, match="cannot be replaced"):
        other.K = np.ones_like(other.K)
    other.metadata = {"robot": "jackal-2"}  # the user's dict, not part of the model
    assert gpmsa.load(other.save(tmp_path / "m.gpmsa")).metadata["robot"] == "jackal-2"
