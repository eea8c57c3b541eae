"""Every check of a study file's hot copies (gpmsa.studies.hot) meets a damaged file (session 85).

Branch coverage showed most of ``check_hot_record``'s refusals and the continuation's
(``continued_copies``) never run. Each is reached here with a hostile record and must name the
field. Found on the way: quoted numbers ("0.5") and bools (true: 1.0) of the right shape were
read as numbers and the file loaded; an integer beyond float64 escaped as a bare OverflowError
(from numpy, not an EmulatorFileError); a whole value null read as "has shape []"; widths
naming another element failed in the continuation as "('t')" (a KeyError's text).
"""

import copy
import warnings

import numpy as np
import pytest
from _study_cases import emulator, observations
from test_studyhot_s76 import _source, _study

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from gpmsa.studies import hot

C, K1 = 2, 3  # the source's chains and hot copies (ladder of 4)
BIG = 10**400  # a JSON integer no float64 holds


@pytest.fixture(scope="module")
def source():
    return _source()


@pytest.fixture(scope="module")
def saved(source, tmp_path_factory):
    """The source's file as (manifest without its envelope, arrays, its folder: the models'
    files lie beside it)."""
    folder = tmp_path_factory.mktemp("study")
    manifest, arrays = read_raw(source.save(folder / "s.gpmsastudy"), formats=(STUDY_FORMAT,))
    return {k: v for k, v in manifest.items() if k not in ENVELOPE}, arrays, folder


def _load(tmp_path, saved, edit):
    manifest, arrays, folder = copy.deepcopy(saved[0]), saved[1], saved[2]
    edit(manifest["settings"])
    path = folder / f"{tmp_path.name}.gpmsastudy"  # beside the models' files
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    return gpmsa.load_study(path)


def _put(*keys, value):
    def edit(settings):
        d = settings
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value

    return edit


def _pop(key):
    return lambda settings: settings.pop(key)


LAM_OS = [[[1.0]] * K1] * C  # a valid lamOs record (C, K - 1, 1)

CASES = {
    "no-ladder": (_pop("temperatures"), r"hot_states: needs settings.temperatures, a ladder of 2 "
                                        r"or more \(got None\)"),
    "one-rung": (_put("temperatures", value=[1.0]), r"hot_states: needs settings.temperatures.*"
                                                     r"got \[1.0\]"),
    "longer-ladder": (_put("temperatures", value=[1.0, 2.0, 4.0, 8.0, 16.0]),
                      r"hot_states.theta: has shape \[2, 3, 1\], expected \[2, 4, 1\] \(chains, "
                      r"hot copies: one per rung of settings.temperatures above T = 1"),
    "states-list": (_put("hot_states", value=[1.0]), r"hot_states: must be an object, got \[1.0\]"),
    "widths-text": (_put("hot_step_widths", value="wide"), "hot_step_widths: must be an object"),
    "extra-part": (_put("hot_states", "nu", value=[]),
                   r"hot_states: must hold exactly \['theta', 'mu', 'lam', 'members'\], got "
                   r"\['lam', 'members', 'mu', 'nu', 'theta'\]"),
    "missing-part": (lambda s: s["hot_states"].pop("mu"),
                     r"hot_states: must hold exactly .*got \['lam', 'members', 'theta'\]"),
    "mu-shape": (_put("hot_states", "mu", value=[[[0.5]] * K1] * C),
                 r"hot_states.mu: has shape \[2, 3, 1\], expected \[2, 3, 0\]"),
    "theta-nan": (_put("hot_states", "theta", value=[[[0.5]] * K1, [[0.5], [0.5], [None]]]),
                  r"hot_states.theta: must be finite numbers, got \[nan\]"),
    "theta-null": (_put("hot_states", "theta", value=None),
                   r"hot_states.theta must be a numeric array, got None \(a damaged record"),
    "theta-quoted": (_put("hot_states", "theta", value=[[["0.5"]] * K1] * C),
                     r"hot_states.theta must be a numeric array, got str '0.5' \(a damaged"),
    "theta-bool": (_put("hot_states", "theta", value=[[[True]] * K1] * C),
                   r"hot_states.theta must be a numeric array, got bool True"),
    "theta-huge": (_put("hot_states", "theta", value=[[[BIG]] * K1] * C),
                   r"hot_states.theta holds a number too large for float64"),
    "theta-ragged": (_put("hot_states", "theta", value=[[[0.5]] * K1, [[0.5]] * 2]),
                     r"hot_states.theta must be a numeric array, got a ragged list"),
    "theta-object": (_put("hot_states", "theta", value={"c0": 0.5}),
                     r"hot_states.theta must be a numeric array, got dict"),
    "members-list": (_put("hot_states", "members", value=[]),
                     r"hot_states.members: must be an object naming the models \['a', 'b'\]"),
    "member-list": (_put("hot_states", "members", "a", value=[1.0]),
                    r"hot_states.members.a: must be an object name -> values"),
    "member-huge": (_put("hot_states", "members", "b", value={"lamOs": [[[BIG]] * K1] * C}),
                    r"hot_states.members.b.lamOs holds a number too large for float64"),
    "member-quoted": (_put("hot_states", "members", "a", value={"lamOs": [[["1"]] * K1] * C}),
                      r"hot_states.members.a.lamOs must be a numeric array, got str '1'"),
    "member-zero": (_put("hot_states", "members", "a", value={"lamOs": [[[0.0]] * K1] * C}),
                    r"hot_states.members.a.lamOs: must be finite numbers > 0, got \[0.0, 0.0"),
    "widths-names": (_put("hot_step_widths", "u", value=[[0.1] * K1] * C),
                     r"hot_step_widths: must name the sweep's elements \(those of "
                     r"settings.accept_rate\)"),
    "widths-quoted": (_put("hot_step_widths", "t", value=[["0.1"] * K1] * C),
                      r"hot_step_widths\['t'\] must be a numeric array, got str '0.1'"),
    "widths-huge": (_put("hot_step_widths", "t", value=[[BIG] * K1] * C),
                    r"hot_step_widths\['t'\] holds a number too large for float64"),
    "widths-shape": (_put("hot_step_widths", "t", value=[[0.1] * K1]),
                         r"hot_step_widths\['t'\]: has shape \[1, 3\], expected \[2, 3\]"),
}  # fmt: skip


@pytest.mark.parametrize(("edit", "message"), CASES.values(), ids=CASES.keys())
def test_each_check_of_the_files_hot_record_names_the_field(tmp_path, saved, edit, message):
    with pytest.raises(gpmsa.EmulatorFileError, match=r"\.gpmsastudy: settings\." + message):
        _load(tmp_path, saved, edit)


def test_a_study_without_the_record_is_not_checked(source):
    """Untempered studies, and files written before the record, hold neither field."""
    assert hot.check_hot_record({"temperatures": "not read"}, source) is None


def test_a_record_the_file_check_passes_loads_with_each_models_own_parameters(tmp_path, saved):
    """A record naming a parameter each model has, of its shape, is taken: lamOs here (held
    in this study: the continuation refuses it, below)."""
    both = {"a": {"lamOs": LAM_OS}, "b": {"lamOs": LAM_OS}}
    back = _load(tmp_path, saved, _put("hot_states", "members", value=both))
    assert back.settings["hot_states"]["members"] == both


@pytest.mark.parametrize(
    ("part", "keys", "value", "message"),
    [("hot_states", ("theta",), [[[0.5]] * K1], r"theta has shape \(1, 3, 1\), expected "
                                                r"\(2, 3, 1\)"),
     ("hot_states", ("theta",), [[["x"]] * K1] * C, r"theta must be a numeric array, got str"),
     ("hot_states", ("members", "a"), {"lamOs": LAM_OS},
      r"model 'a': parameters \['lamOs'\], this study samples \[\]"),
     ("hot_step_widths", ("t",), [[0.1, -1.0, 0.1]] * C, "widths must be finite numbers > 0"),
     ("hot_step_widths", ("t",), [[BIG] * K1] * C, "widths of 't' holds a number too large"),
     ("hot_step_widths", ("u",), [[0.1] * K1] * C,
      r"widths name \['t', 'u'\], this study sweeps \['t'\]")],
    ids=["theta-shape", "theta-text", "member-held", "widths-negative", "widths-huge",
         "widths-names"],
)  # fmt: skip
def test_the_continuation_names_a_record_edited_in_memory(source, monkeypatch, part, keys,
                                                          value, message):  # fmt: skip
    """A Study's settings edited after loading reach ``continued_copies`` unchecked by the
    file: each misfit is named, never a bare numpy error or a KeyError's text."""
    record = copy.deepcopy(source.settings[part])
    target = record
    for k in keys[:-1]:
        target = target[k]
    target[keys[-1]] = value
    monkeypatch.setitem(source.settings, part, record)
    with pytest.raises(GPMSAError, match=r"init=study: its recorded hot copies .* do not fit "
                                         rf"this study \({message}"):  # fmt: skip
        _study(n_samples=5, n_chains=2, seed=5, init=source)


def test_a_models_discrepancy_parameters_are_checked_at_their_shapes(tmp_path):
    """A model with a discrepancy samples betaV (p, G) and lamVz (G,): its hot copies record
    them, and a record of another shape is refused naming the model's discrepancy shape."""
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains; observations off the emulator
        study = gpmsa.calibrate_study(
            [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
            discrepancy=["constant", None], temperatures=[1, 4], n_chains=2, n_samples=10,
            n_burn=0, seed=3, tune=False, n_jobs=1,
        )  # fmt: skip
    members = study.settings["hot_states"]["members"]
    assert {"betaV", "lamVz"} <= set(members["a"]) and "betaV" not in members["b"]
    assert np.shape(members["a"]["betaV"]) == (2, 1, 1, 1)
    path = study.save(tmp_path / "d.gpmsastudy")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["settings"]["hot_states"]["members"]["a"]["betaV"] = [[[1.0, 1.0]]] * 2
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"members\.a\.betaV: has shape \[2, 1, 2\], "
                                                      r"expected \[2, 1, 1, 1\].*betaV's shape "
                                                      r"\[1, 1\] in model 'a'"):  # fmt: skip
        gpmsa.load_study(path)
