"""Findings of the s62 file fuzz (/tmp/fuzz62/fuzz.py) of the new file contents: emulator files
of a joint fit with discrepancy precision groups and per-group lamVz priors (a list), and study
files of ``calibrate_study(discrepancy=, discrepancy_groups=)`` (betaV_j, lamVz_j and
settings.discrepancy_by_model). Each hostile file is rewritten as an attacker would (any
manifest, the content hash recomputed) and must load valid or raise EmulatorFileError naming
the field; every file the features write loads back equal."""

import copy
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import GammaPrior, Priors
from gpmsa.io import container
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa.test_file_hostile import read_members, write_zip

GRID = np.linspace(0.0, 1.0, 10)
BASIS = np.column_stack([np.ones(GRID.size), GRID, GRID**2])
GROUPS = [0, 1, 1]
PER_GROUP = Priors(lamVz=[GammaPrior(1.0, 1e-3), GammaPrior(2.0, 1e-2)])


def _simulator(x, t):
    return np.sin(3.0 * GRID[None] * (1.0 + x)) + t * (1.0 + GRID[None])


@cache
def _data(p: int):
    """Runs of a vector-output simulator with p = 1 or 0 known inputs, and its observations."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(24, 1)), rng.uniform(size=(24, 1))
    if p == 0:
        sim = gpmsa.SimData(t=t, y=_simulator(0.5, t), t_names=["t"], index=GRID)
        return sim, gpmsa.ObsData(y=_simulator(0.5, 0.4) + 0.2, index=GRID)
    sim = gpmsa.SimData(x=x, t=t, y=_simulator(x, t), x_names=["x"], t_names=["t"], index=GRID)
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    yo = _simulator(xo, 0.4) + 0.3 * np.sin(2 * xo) + 0.02 * rng.standard_normal((5, 10))
    return sim, gpmsa.ObsData(x=xo, y=yo, index=GRID)


@cache
def _joint_fit(p: int = 1) -> gpmsa.Emulator:
    """A joint fit with two discrepancy precision groups under their own lamVz priors."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(*_data(p), n_iter=40, tune=False, seed=0, discrepancy=BASIS,
                         discrepancy_groups=GROUPS, priors=PER_GROUP, n_pc=2)  # fmt: skip


@cache
def _study() -> gpmsa.Study:
    """Three models: a linear discrepancy in two groups, a given one in two, none."""
    sim, obs = _data(1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, n_iter=60, tune=False, seed=1, n_pc=2)
        return gpmsa.calibrate_study(
            [emu] * 3, [obs] * 3, labels=["m-1", "b_2", "c"], shared=["t"],
            discrepancy=["linear", BASIS, None], discrepancy_groups=[[0, 1], GROUPS, None],
            n_samples=30, n_burn=10, seed=3, tune=False, n_chains=2,
        )  # fmt: skip


def _rewrite(path, manifest, arrays):
    """The file as an attacker writes it: this manifest and arrays, the hash recomputed."""
    manifest = dict(manifest)
    manifest["arrays"] = {k: {"shape": list(v.shape), "dtype": v.dtype.str}
                          for k, v in arrays.items()}  # fmt: skip
    manifest["content_sha256"] = container.content_hash(arrays, manifest)
    return write_zip(path, manifest, arrays)


# --- round trips ---------------------------------------------------------------------------------
def _same_posterior(a: gpmsa.Posterior, b: gpmsa.Posterior) -> None:
    assert a.names == b.names
    for name in a.names:
        np.testing.assert_array_equal(a.samples[name], b.samples[name])
    assert a.info == b.info


@pytest.mark.parametrize("p", [1, 0])
def test_a_joint_fit_with_per_group_priors_loads_back_equal(tmp_path, p):
    emu = _joint_fit(p)
    back = gpmsa.load(emu.save(tmp_path / "e.gpmsa"))
    assert back.model_sha256 == emu.model_sha256 and back.priors == emu.priors
    assert back.priors.lamVz == PER_GROUP.lamVz and back.settings == emu.settings
    assert {k: v.shape for k, v in back.calibration.items()}["betaV"] == (32, p, 2)
    _same_posterior(gpmsa.calibration_posterior(emu), gpmsa.calibration_posterior(back))


def test_a_study_with_discrepancies_in_some_models_loads_back_equal(tmp_path):
    study = _study()
    back = gpmsa.load_study(study.save(tmp_path / "run.gpmsa"))
    assert back.posterior.names == study.posterior.names
    assert {"betaV[0,1][m-1]", "lamVz[1][b_2]", "lamOs[c]"} <= set(back.posterior.names)
    for name in study.posterior.names:
        np.testing.assert_array_equal(back.posterior.samples[name], study.posterior.samples[name])
    assert back.settings == study.settings
    for lab in study.labels:
        _same_posterior(back.member_posterior(lab), study.member_posterior(lab))
        assert back.discrepancy(lab) == study.discrepancy(lab)
    assert back.discrepancy("c") is None
    assert [e.model_sha256 for e in back.members] == [e.model_sha256 for e in study.members]


# --- the joint fit's calibration draws ----------------------------------------------------------
def _cal_edit(name, op):
    return lambda m, a: a.update({name: op(a[name])})


@pytest.mark.parametrize(
    ("edit", "field"),
    [  # each loaded, then calibration_posterior (or a study's member_posterior) raised
        # ValueError (cannot reshape) or IndexError deep in numpy
        (_cal_edit("cal_betaV", lambda v: v[..., :-1]), r"cal_betaV: has shape \[32, 1, 1\]"),
        (_cal_edit("cal_betaV", lambda v: v.reshape(len(v), -1)), "arrays/cal_betaV: has shape"),
        (_cal_edit("cal_betaV", lambda v: np.concatenate([v, v], 1)), "arrays/cal_betaV"),
        (_cal_edit("cal_lamVz", lambda v: v.reshape(-1)[: len(v)]), "arrays/cal_lamVz: shape"),
        (_cal_edit("cal_lamVz", lambda v: v[:, :0]), "arrays/cal_lamVz: shape"),
        (_cal_edit("cal_lamOs", lambda v: v[:, :0]), r"arrays/cal_lamOs: has shape \[32, 0\]"),
        (_cal_edit("cal_lamOs", lambda v: np.hstack([v, v])), "arrays/cal_lamOs: has shape"),
    ],
)
def test_calibration_draws_of_another_shape_are_refused(tmp_path, edit, field):
    manifest, arrays = read_members(_joint_fit().save(tmp_path / "e.gpmsa"))
    edit(manifest, arrays)
    path = _rewrite(tmp_path / "edit.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load(path)


def _settings_edit(key, value):
    return lambda m: m["settings"].update({key: value})


@pytest.mark.parametrize(
    ("edit", "field"),
    [  # each loaded: a record of groups that are not the draws' two (gpmsa info showed it)
        (_settings_edit("discrepancy_groups", [0, 1, 2]), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy_groups", [0, 0, 0]), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy_groups", [0, 2, 2]), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy_groups", "011"), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy_groups", [0, True, 1]), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy_groups", None), "settings.discrepancy_groups"),
        (lambda m: m["settings"].pop("discrepancy_groups"), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy", None), "settings.discrepancy"),
        (_settings_edit("discrepancy", "quadratic"), "settings.discrepancy"),
        (_settings_edit("discrepancy", "constant"), "settings.discrepancy_groups"),
        (_settings_edit("discrepancy", "linear"), "settings.discrepancy_groups"),
    ],
)
def test_a_discrepancy_record_unlike_the_draws_is_refused(tmp_path, edit, field):
    manifest, arrays = read_members(_joint_fit().save(tmp_path / "e.gpmsa"))
    edit(manifest)
    path = _rewrite(tmp_path / "edit.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load(path)


@pytest.mark.parametrize("lengths", [2, True, 0.5, [], [10, 0], [10.0], "10"])
def test_observation_lengths_that_are_no_list_of_lengths_are_refused(tmp_path, lengths):
    """settings.obs_lengths = 2 loaded; full_prediction then raised TypeError ('int' object is
    not iterable) comparing them with its observations'."""
    manifest, arrays = read_members(_joint_fit().save(tmp_path / "e.gpmsa"))
    manifest["settings"]["obs_lengths"] = lengths
    path = _rewrite(tmp_path / "edit.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="settings.obs_lengths"):
        gpmsa.load(path)


def test_another_consistent_grouping_loads(tmp_path):
    """[1, 0, 0] numbers the same two groups: a consistent rewrite, loaded as written."""
    manifest, arrays = read_members(_joint_fit().save(tmp_path / "e.gpmsa"))
    manifest["settings"]["discrepancy_groups"] = [1, 0, 0]
    back = gpmsa.load(_rewrite(tmp_path / "edit.gpmsa", manifest, arrays))
    assert back.settings["discrepancy_groups"] == [1, 0, 0]


def test_a_discrepancy_record_without_its_draws_is_refused(tmp_path):
    manifest, arrays = read_members(_joint_fit().save(tmp_path / "e.gpmsa"))
    arrays = {k: v for k, v in arrays.items() if k not in ("cal_betaV", "cal_lamVz")}
    path = _rewrite(tmp_path / "edit.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="settings.discrepancy"):
        gpmsa.load(path)


# --- the study's discrepancy record ------------------------------------------------------------
@pytest.mark.parametrize(
    ("label", "record", "field"),
    [  # each loaded: groups no basis of that kind has (constant: one vector, linear: two)
        ("m-1", {"discrepancy": "constant"}, r"discrepancy_by_model.m-1.discrepancy_groups"),
        ("m-1", {"discrepancy_groups": [0, 1, 1]}, r"discrepancy_by_model.m-1.discrepancy_groups"),
        ("b_2", {"discrepancy": "linear"}, r"discrepancy_by_model.b_2.discrepancy_groups"),
    ],
)
def test_a_study_record_of_groups_its_basis_cannot_have_is_refused(tmp_path, label, record, field):
    path = _study().save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["settings"]["discrepancy_by_model"][label].update(record)
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load_study(path)


@pytest.mark.parametrize("n_iter", [2**70, 2**64])
def test_a_study_n_iter_beyond_c_integers_is_refused(tmp_path, n_iter):
    """settings.n_iter = 2**70 (n_samples alike) raised OverflowError (len of a range) in
    ``gpmsa.load_study``."""
    path = _study().save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["settings"].update(n_iter=n_iter, n_samples=n_iter)
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    with pytest.raises(gpmsa.EmulatorFileError, match=f"n_iter={n_iter}, n_burn=10, thin=1 keep"):
        gpmsa.load_study(path)


# --- a seeded fuzz of both ----------------------------------------------------------------------
GOOD = {"a": 1.0, "b": 1e-3, "lower": 0.0, "upper": "inf"}
VALUES = [None, True, 0, -1, 2, 2**70, 1e308, 0.5, "", "x", "inf", [], [0], [0, 1], [1, 0],
          [0, 2], [0, 1, 1], [0, 1, 2], [True, False], [0.0, 1.0], {}, {"a": 1}, [GOOD],
          [GOOD, GOOD], [GOOD] * 3, GOOD, [GOOD, {**GOOD, "a": -1.0}], "constant", "linear",
          "given"]  # fmt: skip
ARRAY_OPS = [
    lambda v: v[..., :-1], lambda v: np.concatenate([v, v[..., -1:]], -1), lambda v: v[..., None],
    lambda v: v.reshape(-1), lambda v: v[:, :-1], lambda v: v[:0], lambda v: np.swapaxes(v, -1, -2),
    lambda v: v.astype(np.int64), lambda v: np.zeros_like(v), lambda v: -v, lambda v: v * 2.0,
    lambda v: np.where(v == v.flat[0], np.nan, v),
]  # fmt: skip


def _mutate(rng, manifest, arrays, paths):
    """One to three random edits of the fields and arrays the new features write."""
    manifest, arrays, base = copy.deepcopy(manifest), dict(arrays), arrays
    for _ in range(int(rng.integers(1, 4))):
        if rng.random() < 0.6:
            *head, key = paths[int(rng.integers(len(paths)))]
            obj = manifest
            for k in head:
                obj = obj.get(k) if isinstance(obj, dict) else None
            if isinstance(obj, list if isinstance(key, int) else dict) and (
                not isinstance(key, int) or key < len(obj)
            ):
                obj[key] = VALUES[int(rng.integers(len(VALUES)))]
        else:
            names = sorted(k for k in arrays if k.startswith(("cal_", "betaV", "lamVz", "lamOs")))
            name = names[int(rng.integers(len(names)))]
            op = ARRAY_OPS[int(rng.integers(len(ARRAY_OPS)))]
            arrays[name] = np.ascontiguousarray(op(base[name]))
    return manifest, arrays


def _use_emulator(emu):
    post = gpmsa.calibration_posterior(emu)
    assert all(np.all(np.isfinite(v)) for v in post.samples.values())
    emu.priors.lamvz_priors(emu.calibration["lamVz"].shape[1])


def _use_study(study):
    for lab in study.labels:
        post = study.member_posterior(lab)
        assert all(np.all(np.isfinite(v)) for v in post.samples.values())
        disc = study.discrepancy(lab)
        assert (disc is None) == (f"lamVz[{lab}]" not in study.posterior.names
                                  and f"lamVz[0][{lab}]" not in study.posterior.names)  # fmt: skip


def test_seeded_fuzz_of_the_new_contents_loads_valid_or_names_the_field(tmp_path):
    """800 edits (seeded) of a joint fit's per-group priors, groups and draws and of a study's
    discrepancy record and draws: each loads and works, or raises EmulatorFileError."""
    rng = np.random.default_rng(62)
    emu_manifest, emu_arrays = read_members(_joint_fit().save(tmp_path / "e.gpmsa"))
    study_path = _study().save(tmp_path / "run.gpmsa")
    st_manifest, st_arrays = read_members(study_path)
    emu_paths = [("priors", "lamVz"), ("priors", "lamVz", 0), ("priors", "lamVz", 1),
                 ("settings", "discrepancy_groups"), ("settings", "discrepancy"),
                 ("settings", "obs_lengths")]  # fmt: skip
    key = ("settings", "discrepancy_by_model")
    st_paths = [key, (*key, "m-1"), (*key, "b_2"), (*key, "c"), (*key, "zz"),
                (*key, "m-1", "discrepancy_groups"), (*key, "b_2", "discrepancy_groups"),
                (*key, "m-1", "discrepancy"), (*key, "b_2", "discrepancy")]  # fmt: skip
    loaded, refused = [0, 0], [0, 0]
    for i in range(800):
        study = i % 2
        manifest, arrays = _mutate(rng, *((st_manifest, st_arrays) if study else
                                          (emu_manifest, emu_arrays)),
                                   st_paths if study else emu_paths)  # fmt: skip
        path = _rewrite(study_path if study else tmp_path / "edit.gpmsa", manifest, arrays)
        try:
            back = gpmsa.load_study(path) if study else gpmsa.load(path)
        except gpmsa.EmulatorFileError:
            refused[study] += 1
            continue
        loaded[study] += 1
        _use_study(back) if study else _use_emulator(back)
    assert min(refused) > 300 and min(loaded) > 5, (loaded, refused)
