"""Findings of the s63 file fuzz (/tmp/fuzz63/fuzz.py) of the session's new file contents: a
given emulator basis (settings.basis), held single elements (settings.fixed {"elements",
"values"}), betaV's own rho prior (priors.rhoV_a, rhoV_b) and the recorded step widths a
continuation runs on. Each hostile file is rewritten as an attacker would (any manifest, the
content hash recomputed) and must load valid or raise EmulatorFileError naming the field;
``gpmsa info`` refuses it in one line."""

import contextlib
import io
import warnings
from functools import cache

import numpy as np
import pytest
from test_discrepancy_groups_s61 import BASIS, GROUPS, _data

import gpmsa
from gpmsa import Priors
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa._study_cases import emulator as study_emulator
from tests.gpmsa._study_cases import observations
from tests.gpmsa.test_file_hostile import read_members, write_members

HELD = {"lamVz": {1: 1e6}, "betaU": {(1, 0): 0.7}}
PER_GROUP = Priors(rhoV_a=[1.0, 100.0], rhoV_b=[0.1, 1.0])


def _quiet(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the toys' short chains are not converged
        return fn(*args, **kw)


@cache
def _held_fit() -> gpmsa.Emulator:
    """A joint fit with held elements, per-group rhoV priors and two discrepancy groups."""
    data, obs = _data()
    return _quiet(gpmsa.fit, data, obs, n_iter=30, seed=0, n_chains=2, tune=False, n_jobs=1,
                  discrepancy=BASIS, discrepancy_groups=GROUPS, priors=PER_GROUP,
                  fixed={**HELD, "lamWOs": 1e4})  # fmt: skip


def _p0_data():
    """Runs without known inputs (p = 0) and three experiments of a 10-value output."""
    grid = np.linspace(0.0, 1.0, 10)
    t = np.random.default_rng(0).uniform(size=(16, 1))
    sim = gpmsa.SimData(t=t, y=np.sin(3 * grid) + t * (1 + grid), t_names=["t"], index=grid)
    y = np.sin(3 * grid) + 0.4 * (1 + grid) + 0.2 + np.zeros((3, 1))
    return sim, gpmsa.ObsData(y=y + 0.01 * np.arange(3)[:, None], index=grid)


def _edited(tmp_path, edit, emu=None):
    """The held fit's file after ``edit(manifest)``, as an attacker rewrites it."""
    manifest, arrays = read_members((emu or _held_fit()).save(tmp_path / "e.gpmsa"))
    edit(manifest)
    return write_members(tmp_path / "edit.gpmsa", manifest, arrays)


def _info(path) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        rc = main(["info", str(path)])
    return rc, err.getvalue()


def _refused(path, field: str) -> None:
    """gpmsa.load raises EmulatorFileError naming ``field``; gpmsa info refuses in one line."""
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load(path)
    rc, err = _info(path)
    assert rc == 2 and err.count("\n") == 1 and "unexpected" not in err, err


# --- numbers beyond float64 ----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("where", "field"),
    [(("rhoV_a", 1), r"rhoV_a\[1\]"), (("theta_sd",), "theta_sd"), (("lamOs", "a"), "lamOs.a")],
)
def test_a_prior_number_beyond_float64_is_refused(tmp_path, where, field):
    """A JSON integer 10**400 (no float64) as a prior's number raised OverflowError in
    ``gpmsa.load`` (float() of it), and ``gpmsa info`` answered "unexpected OverflowError"."""

    def edit(m):
        *head, last = where
        obj = m["priors"]
        for key in head:
            obj = obj[key]
        obj[last] = 10**400

    _refused(_edited(tmp_path, edit), f"priors.{field}: 1000.* is beyond float64")


# --- the record of held elements against the draws ----------------------------------------------
def _fixed(name, record):
    return lambda m: m["settings"]["fixed"].update({name: record})


def _held(name, elements, values):
    return _fixed(name, {"elements": elements, "values": values})


@pytest.mark.parametrize(
    ("edit", "field"),
    [  # each loaded, gpmsa info printing the record as the file's held elements
        (_held("lamVz", [[1]], [5.0]), r"lamVz\[1\] at 5.0, but its draws"),
        (_held("lamVz", [[0]], [1e6]), "lamVz.*draws are not held"),
        (_held("betaU", [[1, 0], [0, 2]], [0.7, 0.3]), r"betaU\[0,2\] at 0.3"),
        (_fixed("lamWOs", [2e4]), r"settings.fixed\['lamWOs'\]: holds lamWOs at \[20000.0\]"),
        (_fixed("lamUz", [1.0, 1.0]), r"settings.fixed\['lamUz'\]"),
        (_held("lamVz", [[2]], [1e6]), r"elements\[0\]: \[2\] is not"),
        (_held("lamVz", [[-1]], [1e6]), r"elements\[0\]"),
        (_held("lamVz", [[1], [1]], [1e6, 1e6]), "named twice"),
        (_held("betaU", [[1]], [0.7]), r"\['betaU'\].elements\[0\]"),
        (_held("betaU", [[1, True]], [0.7]), r"elements\[0\]"),
        (_held("lamVz", [[1]], ["1e6"]), r"\['lamVz'\].values"),
        (_held("lamVz", [[1]], [None]), r"\['lamVz'\].values"),
        (_held("lamVz", [[1]], [1e6, 1.0]), "one value per element"),
        (_held("lamVz", [[1]], [[1e6]]), "one number per element"),
        (_fixed("lamVz", {"elements": [[1]]}), r"settings.fixed\['lamVz'\]: held elements"),
        (_held("lamVz", [], []), r"settings.fixed\['lamVz'\]"),
        (_fixed("lamWOs", "1e4"), r"settings.fixed\['lamWOs'\]"),
        (_fixed("lamWOs", [10**400]), r"settings.fixed\['lamWOs'\]"),
        (_fixed("lamWOs", 1e4), "need its shape"),
        (_fixed("zz", [1.0]), r"settings.fixed\['zz'\]: names no parameter"),
        (lambda m: m["settings"].update(fixed=[1.0]), "settings.fixed: must be an object"),
    ],
)
def test_a_fixed_record_unlike_the_draws_or_malformed_is_refused(tmp_path, edit, field):
    _refused(_edited(tmp_path, edit), field)


def test_a_record_of_held_elements_loads_back_and_records_without_it_load(tmp_path):
    emu = _held_fit()
    back = gpmsa.load(emu.save(tmp_path / "e.gpmsa"))
    assert back.settings["fixed"]["lamVz"] == {"elements": [[1]], "values": [1e6]}
    assert back.settings["fixed"] == emu.settings["fixed"]
    for edit in (lambda m: m["settings"].pop("fixed"), lambda m: m["settings"].update(fixed={})):
        assert gpmsa.load(_edited(tmp_path, edit)).settings.get("fixed") in (None, {})


@pytest.mark.parametrize("basis", [5, None, "PCA", ["given"], "given\u202e"])
def test_a_basis_record_that_no_fit_writes_is_refused(tmp_path, basis):
    """settings.basis = 5 loaded and gpmsa info called the basis "PCA of the runs"."""
    path = _edited(tmp_path, lambda m: m["settings"].update(basis=basis))
    _refused(path, "settings.basis: must be one of")
    older = _edited(tmp_path, lambda m: m["settings"].pop("basis"))  # before s63: the PCA
    assert "basis" not in gpmsa.load(older).settings


# --- a continuation of a fit without known inputs ------------------------------------------------
@pytest.mark.parametrize("saved", [False, True])
def test_a_joint_fit_without_known_inputs_continues_with_its_widths(tmp_path, saved):
    """betaV of a p = 0 discrepancy has shape (0, G); its recorded widths are [] per chain
    (no shape), which ``continued_widths`` refused as a damaged record: every continuation of
    such a fit raised GPMSAError (pass step_widths= or tune=True)."""
    sim, obs = _p0_data()
    kw = {"discrepancy": BASIS, "discrepancy_groups": GROUPS, "n_chains": 2, "n_jobs": 1}
    first = _quiet(gpmsa.fit, sim, obs, n_iter=30, seed=0, tune_rounds=2, **kw)
    assert first.settings["step_widths"]["betaV"] == [[], []]
    if saved:
        first = gpmsa.load(first.save(tmp_path / "p0.gpmsa"))
    more = _quiet(gpmsa.fit, sim, obs, n_iter=10, seed=1, init=first, **kw)
    assert more.settings["tune"] is False
    np.testing.assert_array_equal(more.settings["step_widths"]["lamVz"],
                                  first.settings["step_widths"]["lamVz"])  # fmt: skip


# --- a study's uniform hyperprior without its bound ---------------------------------------------
def _hierarchical_study_file(tmp_path):
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    study = _quiet(gpmsa.calibrate_study, [study_emulator(None)] * 2, [d[0] for d in data],
                   [d[1] for d in data], labels=["a", "b"], hierarchical=["t"], n_samples=30,
                   n_burn=10, seed=5, tune=False)  # fmt: skip
    return study.save(tmp_path / "run.gpmsa")


def test_a_uniform_hyperprior_without_sd_max_is_refused_and_an_old_gamma_one_loads(tmp_path):
    """priors.hyper without sd_max loaded with HyperPriors' default 1.0 whatever its sd_prior
    (files before sd_prior, SEPIA's Gamma, have none); ``gpmsa info`` of a uniform one then
    raised KeyError ('sd_max'), answered as "unexpected KeyError"."""
    path = _hierarchical_study_file(tmp_path)
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    assert manifest["priors"]["hyper"]["sd_prior"] == "uniform"
    del manifest["priors"]["hyper"]["sd_max"]
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    with pytest.raises(gpmsa.EmulatorFileError, match="priors.hyper.sd_max: must be a finite"):
        gpmsa.load_study(path)
    rc, err = _info(path)
    assert rc == 2 and err.count("\n") == 1 and "priors.hyper.sd_max" in err, err
    del manifest["priors"]["hyper"]["sd_prior"]  # a file from before both: SEPIA's Gamma
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    assert gpmsa.load_study(path).hyper.sd_prior == "gamma"
    assert _info(path)[0] == 0


# --- gpmsa info of records it only prints ---------------------------------------------------------
def _set_record(m, record: str, value):
    if record == "rhat":
        m["convergence"]["max_rhat"][1] = value
    else:
        m["diagnostics"]["theta"]["mean"][0] = value


@pytest.mark.parametrize("record", ["rhat", "theta mean"])
def test_info_prints_a_record_number_beyond_float64(tmp_path, record):
    """convergence.max_rhat = [element, 10**400] or a theta mean 10**400 in diagnostics (records
    the file keeps for display) loaded, but ``gpmsa info`` raised OverflowError formatting it
    as a float ("unexpected OverflowError")."""
    path = _edited(tmp_path, lambda m: _set_record(m, record, 10**400))
    gpmsa.load(path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()) as err:
        assert main(["info", str(path)]) == 0, err.getvalue()
    assert "1" + "0" * 40 in out.getvalue()
