"""Round-trip fidelity of emulator files: ``load(save(emu))`` holds every field a user reaches
(the JSON records as ``jsonable`` writes them: tuples as lists, non-finite floats as None; the
diagnostics and convergence record with their NaN and inf, since session 89), a
re-save keeps every member of the file (only ``created_utc`` and the hash that covers it
change), and the loaded emulator predicts and continues its chains bit for bit as the one in
memory. A sweep of session 86 (fit varieties x these checks) found no loss; this keeps it so."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.io.container import jsonable, read_raw

ARRAYS = ("x_unit", "t_unit", "y", "K", "w", "lam_sim", "index", "log_post")
RECORDS = ("settings", "metadata")
NUMERIC_RECORDS = ("diagnostics", "convergence")  # read back with their NaN and inf
PLAIN = ("x_names", "t_names", "y_names", "x_units", "t_units", "y_units", "index_names",
         "index_units", "levels", "priors", "domain", "given_ranges", "model_sha256")  # fmt: skip


def _data(seed: int = 1) -> gpmsa.SimData:
    rng = np.random.default_rng(seed)
    x, t = rng.random((16, 1)), rng.random((16, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2, x_names=["vélo"], t_names=["θ"],
                         x_units=["m/s²"], t_units=["µm"])  # fmt: skip


OBS = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[np.sin(0.6) + 0.16], [np.sin(2.1) + 0.16]])
CASES = {
    "joint": (OBS, {}),
    "tempered": (OBS, {"temperatures": 2}),
    "fixed": (None, {"fixed": {"lamWOs": 1e5 - 1, "betaU": {(0, 0): 0.5}}}),
    "mean_basis": (None, {"mean_basis": "linear", "metadata": {"π": [1, (2, 3)], "n": None}}),
}


def _fit(name: str, **kw) -> gpmsa.Emulator:
    obs, options = CASES[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        return gpmsa.fit(_data(), obs, **{"n_iter": 20, "tune": False, "seed": 0, **options,
                                          **kw})  # fmt: skip


def _same_array(a, b) -> bool:
    if a is None or b is None:
        return a is b
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


def _same_numbers(a, b) -> bool:
    """Equal records, NaN equal to NaN (a float's type kept: no None for NaN)."""
    if isinstance(a, dict):
        return (
            isinstance(b, dict)
            and a.keys() == b.keys()
            and all(_same_numbers(a[k], b[k]) for k in a)
        )
    if isinstance(a, (list, tuple)):
        return isinstance(b, list) and len(a) == len(b) and all(map(_same_numbers, a, b))
    if isinstance(a, float):
        return isinstance(b, float) and (a == b or (np.isnan(a) and np.isnan(b)))
    return a == b


def _assert_same(a: gpmsa.Emulator, b: gpmsa.Emulator) -> None:
    for name in ARRAYS:
        assert _same_array(getattr(a, name), getattr(b, name)), name
    for name in ("params", "draws", "calibration"):
        x, y = getattr(a, name) or {}, getattr(b, name) or {}
        assert set(x) == set(y) and all(_same_array(x[k], y[k]) for k in x), name
    for name in RECORDS:
        assert jsonable(getattr(a, name)) == getattr(b, name), name
    for name in NUMERIC_RECORDS:
        assert _same_numbers(getattr(a, name), getattr(b, name)), name
    for name in PLAIN:
        assert getattr(a, name) == getattr(b, name), name
    std_a, std_b = a.standardizer, b.standardizer
    for name in ("x_min", "x_max", "t_min", "t_max", "y_mean", "grid"):
        assert _same_array(getattr(std_a, name), getattr(std_b, name)), name
    assert std_a.y_sd == std_b.y_sd


def _members(path) -> tuple[dict, dict]:
    manifest, arrays = read_raw(path)
    for key in ("created_utc", "content_sha256"):  # documented to change on every save
        manifest.pop(key)
    return manifest, arrays


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_saved_emulator_reads_back_whole_and_a_resave_keeps_every_member(name, tmp_path):
    emu = _fit(name)
    emu.save(tmp_path / "a.gpmsa")
    once = gpmsa.load(tmp_path / "a.gpmsa")
    _assert_same(emu, once)
    once.save(tmp_path / "b.gpmsa")
    _assert_same(once, gpmsa.load(tmp_path / "b.gpmsa"))
    (ma, aa), (mb, ab) = _members(tmp_path / "a.gpmsa"), _members(tmp_path / "b.gpmsa")
    assert ma == mb
    assert set(aa) == set(ab) and all(_same_array(aa[k], ab[k]) for k in aa)
    x, t = [[0.3], [0.6]], [[0.4], [0.5]]
    for a, b in zip(emu.predict(x, t), once.predict(x, t), strict=True):
        assert _same_array(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("name", ["joint", "tempered", "fixed"])
@pytest.mark.parametrize("append", [False, True])
def test_a_loaded_emulator_continues_as_the_one_in_memory(name, append, tmp_path):
    emu = _fit(name)
    emu.save(tmp_path / "a.gpmsa")
    loaded = gpmsa.load(tmp_path / "a.gpmsa")
    mine, theirs = (_fit(name, init=src, n_iter=10, seed=3, append=append)
                    for src in (emu, loaded))  # fmt: skip
    assert set(mine.draws) == set(theirs.draws)
    for k in mine.draws:
        assert _same_array(mine.draws[k], theirs.draws[k]), k
    assert jsonable(mine.settings["step_widths"]) == jsonable(theirs.settings["step_widths"])
    if name == "tempered":
        assert jsonable(mine.settings["hot_states"]) == jsonable(theirs.settings["hot_states"])
