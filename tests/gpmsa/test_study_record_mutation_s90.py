"""Exact checks of a study file's record (``gpmsa.studies.record``), from mutation testing of the
module (session 90): hand-built manifests, arrays and studies, each refusal named exactly, each
limit at its edge, and a tiny saved study read back field by field."""

from __future__ import annotations

import copy
from types import SimpleNamespace

import numpy as np
import pytest

from gpmsa.errors import EmulatorFileError
from gpmsa.studies.layout import Element, Layout
from gpmsa.studies.record import (
    _check_counts,
    _check_discrepancies,
    _check_kind,
    _check_rates,
    _is_member_fit,
    check_study_arrays,
    check_study_claims,
    check_study_manifest,
    discrepancy_arrays,
)

SHA = "0123456789abcdef" * 4
"""A well-formed sha256 (64 lowercase hex digits)."""
OTHER = "fedcba9876543210" * 4


def _spec(*shape: int, dtype: str = "<f8") -> dict:
    return {"shape": list(shape), "dtype": dtype}


def _manifest() -> dict:
    """A valid record of a calibration of models a and b (hierarchical t), 2 chains x 3 draws."""
    return {
        "names": {
            "models": ["a", "b"],
            "elements": ["t[a]", "t[b]"],
            "t": {"a": ["t"], "b": ["t"]},
        },
        "units": {"a": [""], "b": ["m"]},
        "priors": {
            "hyper": {
                "sd_prior": "uniform",
                "mu_mean": 0.5,
                "mu_sd": 10.0,
                "sd_max": 1.0,
                "lam_a": 1.0,
                "lam_b": 0.001,
                "lam_start": 5.0,
            }
        },
        "settings": {"n_iter": 4, "n_burn": 1, "n_chains": 2},
        "metadata": {},
        "study": {
            "kind": "calibration",
            "shared": [],
            "hierarchical": ["t"],
            "models": [
                {"label": "a", "file": "run.a.gpmsa", "sha256": SHA},
                {"label": "b", "file": "run.b.gpmsa", "sha256": OTHER},
            ],
        },
        "arrays": {
            "theta": _spec(2, 3, 2),
            "mu": _spec(2, 3, 1),
            "lam": _spec(2, 3, 1),
            "lamOs": _spec(2, 3, 2),
            "log_post": _spec(2, 3),
        },
    }


def _refused(call, message: str) -> None:
    with pytest.raises(EmulatorFileError) as info:
        call()
    assert str(info.value) == message


def _edited(edit) -> dict:
    m = _manifest()
    edit(m)
    return m


def _set(path: str, value):
    """An edit setting manifest[path] ("study.models.1.file": keys, list indices as digits)."""

    def edit(m: dict) -> None:
        *head, last = path.split(".")
        node = m
        for k in head:
            node = node[int(k)] if isinstance(node, list) else node[k]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value

    return edit


def _drop(path: str):
    def edit(m: dict) -> None:
        *head, last = path.split(".")
        node = m
        for k in head:
            node = node[k]
        del node[last]

    return edit


def test_discrepancy_array_names():
    assert discrepancy_arrays(0) == ("betaV_0", "lamVz_0")
    assert discrepancy_arrays(12) == ("betaV_12", "lamVz_12")


# --- check_study_manifest: a valid record, then each refusal ---------------------------------


def test_a_valid_record_passes_and_is_left_as_it_was():
    m = _manifest()
    check_study_manifest(m)
    assert m == _manifest()


@pytest.mark.parametrize(
    "edit",
    [
        _set("study.kind", "fit"),
        _set("study.shared", ["t"]),
        _set("study.models.1.label", "x" * 48),  # the longest label
        _set("study.models.1.label", "B-_9"),
        _set("study.models.1.file", "a" * 151 + ".gpmsa"),  # the longest file name
        _set("study.models.1.file", "-b.x.gpmsa"),
        _set("study.models.1.file", "b.gpmsa"),
        _set("priors.hyper.mu_mean", -3),  # any finite number, an int too
        _set("priors.hyper.mu_mean", 0.0),
        _set("priors.hyper.mu_sd", 5e-324),  # the smallest number > 0
        _set("priors.hyper.lam_b", 7),
        _set("priors.hyper.sd_max", 1e-150),  # its square 1e-300: non-zero
        _set("priors.hyper.sd_max", 1e154),  # its square 1e308: finite
        _drop("priors.hyper.sd_prior"),  # files before sd_prior: SEPIA's gamma, no sd_max
        _set(
            "priors.hyper",
            {
                "sd_prior": "gamma",
                "mu_mean": 0.5,
                "mu_sd": 10.0,
                "lam_a": 1.0,
                "lam_b": 0.001,
                "lam_start": 5.0,
            },
        ),
        _set(
            "priors.hyper",
            {"mu_mean": 0.5, "mu_sd": 10.0, "lam_a": 1.0, "lam_b": 0.001, "lam_start": 5.0},
        ),
    ],
)
def test_valid_variants_pass(edit):
    check_study_manifest(_edited(edit))


def _one_model(m: dict) -> None:
    m["study"]["models"] = m["study"]["models"][:1]
    m["arrays"]["lamOs"] = _spec(2, 3, 1)


def test_a_one_model_record_passes():
    check_study_manifest(_edited(_one_model))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_drop("study"), "study: must be an object, got None"),
        (_set("study", ["calibration"]), "study: must be an object, got ['calibration']"),
        (_set("study.kind", "Fit"), "study.kind: must be one of ('calibration', 'fit'), got 'Fit'"),
        (_drop("study.kind"), "study.kind: must be one of ('calibration', 'fit'), got None"),
        (
            _set("study.kind", "k" * 58),
            f"study.kind: must be one of ('calibration', 'fit'), got '{'k' * 58}'",
        ),
        (
            _set("study.kind", "k" * 59),
            f"study.kind: must be one of ('calibration', 'fit'), got '{'k' * 56}...",
        ),
        (_set("study.shared", "t"), "study.shared: must be a list of strings, got 't'"),
        (_set("study.shared", ["t", 1]), "study.shared: must be a list of strings, got ['t', 1]"),
        (_drop("study.shared"), "study.shared: must be a list of strings, got None"),
        (
            _set("study.hierarchical", ("t",)),
            "study.hierarchical: must be a list of strings, got ('t',)",
        ),
        (
            _set("study.hierarchical", [None]),
            "study.hierarchical: must be a list of strings, got [None]",
        ),
        (_set("study.models", []), "study.models: must be a non-empty list, got []"),
        (_set("study.models", {"a": 1}), "study.models: must be a non-empty list, got {'a': 1}"),
        (
            _set("study.models.1", "run.b.gpmsa"),
            "study.models[1]: must be an object, got 'run.b.gpmsa'",
        ),
        (
            _set("study.models.1.label", "a b"),
            "study.models[1].label: must be 1-48 letters, digits, _ or -: 'a b'",
        ),
        (
            _set("study.models.1.label", "x" * 49),
            f"study.models[1].label: must be 1-48 letters, digits, _ or -: '{'x' * 49}'",
        ),
        (
            _set("study.models.1.label", ""),
            "study.models[1].label: must be 1-48 letters, digits, _ or -: ''",
        ),
        (
            _set("study.models.1.label", 7),
            "study.models[1].label: must be 1-48 letters, digits, _ or -: 7",
        ),
        (
            _set("study.models.1.file", "sub/run.b.gpmsa"),
            "study.models[1].file: must be a .gpmsa file name beside the study file (no folder), "
            "got 'sub/run.b.gpmsa'",
        ),
        (
            _set("study.models.1.file", ".b.gpmsa"),
            "study.models[1].file: must be a .gpmsa file name beside the study file (no folder), "
            "got '.b.gpmsa'",
        ),
        (
            _set("study.models.1.file", "b.gpmsa\n"),
            "study.models[1].file: must be a .gpmsa file name beside the study file (no folder), "
            "got 'b.gpmsa\\n'",
        ),
        (
            _set("study.models.1.file", "a" * 152 + ".gpmsa"),
            "study.models[1].file: must be a .gpmsa file name beside the study file (no folder), "
            f"got '{'a' * 56}...",
        ),
        (
            _set("study.models.1.file", None),
            "study.models[1].file: must be a .gpmsa file name beside the study file (no folder), "
            "got None",
        ),
        (
            _set("study.models.1.sha256", SHA.upper()),
            f"study.models[1].sha256: must be 64 lowercase hex digits, got '{SHA.upper()[:56]}...",
        ),
        (
            _set("study.models.1.sha256", SHA[:63]),
            f"study.models[1].sha256: must be 64 lowercase hex digits, got '{SHA[:56]}...",
        ),
        (
            _set("study.models.1.sha256", 5),
            "study.models[1].sha256: must be 64 lowercase hex digits, got 5",
        ),
        (_set("study.models.1.label", "a"), "study.models: labels repeat: ['a', 'a']"),
        (
            _set("study.models.1.file", "run.a.gpmsa"),
            "study.models: files repeat: ['run.a.gpmsa', 'run.a.gpmsa']",
        ),
        (_set("priors.hyper", None), "priors.hyper: must be an object, got None"),
        (_set("priors.hyper", [1.0]), "priors.hyper: must be an object, got [1.0]"),
        (_set("priors.hyper.zeta", 1.0), "priors.hyper: unknown keys ['zeta']"),
        (
            _set("priors.hyper.sd_prior", "cauchy"),
            "priors.hyper.sd_prior: must be one of ('uniform', 'gamma'), got 'cauchy'",
        ),
        (
            _set("priors.hyper.sd_prior", None),
            "priors.hyper.sd_prior: must be one of ('uniform', 'gamma'), got None",
        ),
        (
            _set("priors.hyper.mu_mean", "0.5"),
            "priors.hyper.mu_mean: must be a finite number, got '0.5'",
        ),
        (
            _set("priors.hyper.mu_mean", True),
            "priors.hyper.mu_mean: must be a finite number, got True",
        ),
        (
            _set("priors.hyper.mu_mean", float("inf")),
            "priors.hyper.mu_mean: must be a finite number, got inf",
        ),
        (
            _set("priors.hyper.mu_mean", 10**400),
            f"priors.hyper.mu_mean: must be a finite number, got {str(10**400)[:57]}...",
        ),
        (_drop("priors.hyper.mu_mean"), "priors.hyper.mu_mean: must be a finite number, got None"),
        (_set("priors.hyper.mu_sd", 0), "priors.hyper.mu_sd: must be a finite number > 0, got 0"),
        (
            _set("priors.hyper.mu_sd", -1e-300),
            "priors.hyper.mu_sd: must be a finite number > 0, got -1e-300",
        ),
        (
            _set("priors.hyper.lam_a", float("nan")),
            "priors.hyper.lam_a: must be a finite number > 0, got nan",
        ),
        (
            _set("priors.hyper.lam_start", False),
            "priors.hyper.lam_start: must be a finite number > 0, got False",
        ),
        (
            _drop("priors.hyper.sd_max"),
            "priors.hyper.sd_max: must be a finite number > 0, got None",
        ),
        (
            _set("priors.hyper.sd_max", 0.0),
            "priors.hyper.sd_max: must be a finite number > 0, got 0.0",
        ),
        (
            _set("priors.hyper.sd_max", 1e-170),
            "priors.hyper.sd_max: 1e-170: its square and 4/sd_max^2 are not finite, non-zero "
            "float64s",
        ),
        (
            _set("priors.hyper.sd_max", 1e160),
            "priors.hyper.sd_max: 1e+160: its square and 4/sd_max^2 are not finite, non-zero "
            "float64s",
        ),
        (  # its square 1e-308 is finite and non-zero, but 4/sd_max^2 overflows (session 92)
            _set("priors.hyper.sd_max", 1e-154),
            "priors.hyper.sd_max: 1e-154: its square and 4/sd_max^2 are not finite, non-zero "
            "float64s",
        ),
        (
            _set("priors.hyper.sd_max", 10**200),
            f"priors.hyper.sd_max: {str(10**200)[:57]}...: its square and 4/sd_max^2 are not "
            "finite, non-zero float64s",
        ),
    ],
)
def test_a_damaged_study_field_is_refused_by_name(edit, message):
    _refused(lambda: check_study_manifest(_edited(edit)), message)


def test_a_gamma_record_with_sd_max_has_it_checked():
    def edit(m: dict) -> None:
        m["priors"]["hyper"].update(sd_prior="gamma", sd_max=-1.0)

    _refused(
        lambda: check_study_manifest(_edited(edit)),
        "priors.hyper.sd_max: must be a finite number > 0, got -1.0",
    )


def test_a_gamma_record_without_sd_max_has_its_other_numbers_checked():
    def edit(m: dict) -> None:
        del m["priors"]["hyper"]["sd_max"]
        m["priors"]["hyper"].update(sd_prior="gamma", lam_start=0)

    _refused(
        lambda: check_study_manifest(_edited(edit)),
        "priors.hyper.lam_start: must be a finite number > 0, got 0",
    )


def test_the_first_bad_model_is_named():
    def edit(m: dict) -> None:
        m["study"]["models"][0]["sha256"] = "x"
        m["study"]["models"][1]["sha256"] = "y"

    _refused(
        lambda: check_study_manifest(_edited(edit)),
        "study.models[0].sha256: must be 64 lowercase hex digits, got 'x'",
    )


def test_a_digest_with_a_final_newline_is_refused():
    """``$`` matches before a final newline: the digests are matched to their end (``\\Z``)."""
    bad = SHA + "\n"
    _refused(
        lambda: check_study_manifest(_edited(_set("study.models.1.sha256", bad))),
        f"study.models[1].sha256: must be 64 lowercase hex digits, got '{SHA[:56]}...",
    )
    rec = {"b": {"discrepancy": "constant", "discrepancy_sha256": bad}}
    _refused(
        lambda: _check_discrepancies(
            {"settings": {"discrepancy_by_model": rec}}, "calibration", ["a", "b"]
        ),
        "settings.discrepancy_by_model.b.discrepancy_sha256: must be 64 lowercase hex "
        f"digits, got '{SHA[:56]}...",
    )


# --- arrays in the manifest ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            _drop("arrays.mu"),
            "arrays: this study holds exactly ['theta', 'mu', 'lam', 'lamOs', 'log_post'], got "
            "['lam', 'lamOs', 'log_post', 'theta']",
        ),
        (
            _set("arrays.betaV_0", _spec(2, 3, 1, 1)),
            "arrays: this study holds exactly ['theta', 'mu', 'lam', 'lamOs', 'log_post'], got "
            "['betaV_0', 'lam', 'lamOs', 'log_post', 'mu', 'theta']",
        ),
        (
            _set("arrays.mu", _spec(2, 3, 1, dtype="<f4")),
            "arrays/mu: dtype <f4: must be <f8 (float64)",
        ),
        (
            _set("arrays.log_post", _spec(2, 3, dtype=">f8")),
            "arrays/log_post: dtype >f8: must be <f8 (float64)",
        ),
        (_set("arrays.log_post", _spec(6)), "arrays/log_post: must be (chains, draws), got (6,)"),
        (
            _set("arrays.log_post", _spec(2, 3, 1)),
            "arrays/log_post: must be (chains, draws), got (2, 3, 1)",
        ),
        (
            _set("arrays.log_post", _spec(0, 3)),
            "arrays/log_post: needs >= 1 chain, got shape (0, 3)",
        ),
        (
            _set("arrays.log_post", _spec(2, 0)),
            "arrays/log_post: needs >= 1 draw, got shape (2, 0)",
        ),
        (
            _set("arrays.theta", _spec(2, 3)),
            "arrays/theta: must be (chains, draws, k) with (chains, draws) = (2, 3), got (2, 3)",
        ),
        (
            _set("arrays.theta", _spec(2, 3, 2, 1)),
            "arrays/theta: must be (chains, draws, k) with (chains, draws) = (2, 3), "
            "got (2, 3, 2, 1)",
        ),
        (
            _set("arrays.theta", _spec(2, 4, 2)),
            "arrays/theta: must be (chains, draws, k) with (chains, draws) = (2, 3), got (2, 4, 2)",
        ),
        (
            _set("arrays.lam", _spec(3, 3, 1)),
            "arrays/lam: must be (chains, draws, k) with (chains, draws) = (2, 3), got (3, 3, 1)",
        ),
        (_set("arrays.lamOs", _spec(2, 3, 3)), "arrays/lamOs: has 3 columns for 2 models"),
        (_set("arrays.lamOs", _spec(2, 3, 1)), "arrays/lamOs: has 1 columns for 2 models"),
        (
            _set("arrays.mu", _spec(2, 3, 2)),
            "arrays/mu: mu (2, 3, 2) and lam (2, 3, 1) need one column per "
            "hierarchical parameter (1)",
        ),
        (
            _set("study.hierarchical", ["t", "u"]),
            "arrays/mu: mu (2, 3, 1) and lam (2, 3, 1) need one column per "
            "hierarchical parameter (2)",
        ),
        (
            _set("study.hierarchical", []),
            "arrays/mu: mu (2, 3, 1) and lam (2, 3, 1) need one column per "
            "hierarchical parameter (0)",
        ),
    ],
)
def test_a_damaged_array_spec_is_refused_by_name(edit, message):
    _refused(lambda: check_study_manifest(_edited(edit)), message)


def test_a_record_without_a_hierarchical_parameter_passes():
    def edit(m: dict) -> None:
        m["study"]["hierarchical"] = []
        m["arrays"]["mu"] = m["arrays"]["lam"] = _spec(2, 3, 0)

    check_study_manifest(_edited(edit))


def test_one_chain_of_one_draw_passes():
    def edit(m: dict) -> None:
        for spec in m["arrays"].values():
            spec["shape"] = [1, 1, *spec["shape"][2:]]

    check_study_manifest(_edited(edit))


# --- the discrepancy record ------------------------------------------------------------------


def _with_discrepancy(record, kind: str = "calibration"):
    """A manifest with the settings' discrepancy record ``record`` and its arrays (model b: p = 1
    known input; G from the record)."""

    def edit(m: dict) -> None:
        m["study"]["kind"] = kind
        m["settings"]["discrepancy_by_model"] = record
        if isinstance(record, dict):
            for lab, rec in record.items():
                j = ["a", "b"].index(lab) if lab in ("a", "b") else 9
                g = len(set(rec.get("discrepancy_groups") or [0])) if isinstance(rec, dict) else 1
                beta, lam = discrepancy_arrays(j)
                m["arrays"][beta] = _spec(2, 3, 1, g)
                m["arrays"][lam] = _spec(2, 3, g)

    return edit


def test_the_discrepancy_record_gives_each_models_groups():
    rec = {
        "b": {"discrepancy": "linear", "discrepancy_sha256": SHA, "discrepancy_groups": [1, 0]},
        "a": {"discrepancy": "constant", "discrepancy_sha256": OTHER},
    }
    m = _edited(_with_discrepancy(rec))
    assert _check_discrepancies(m, "calibration", ["a", "b"]) == {1: 2, 0: 1}
    check_study_manifest(m)
    assert _check_discrepancies(_manifest(), "calibration", ["a", "b"]) == {}
    assert _check_discrepancies(_manifest(), "fit", ["a", "b"]) == {}
    one = {"b": {"discrepancy": "given", "discrepancy_sha256": SHA}}
    assert _check_discrepancies(_edited(_with_discrepancy(one)), "calibration", ["a", "b"]) == {
        1: 1
    }


def test_the_discrepancy_arrays_are_required_exactly():
    rec = {"b": {"discrepancy": "constant", "discrepancy_sha256": SHA}}
    m = _edited(_with_discrepancy(rec))
    del m["arrays"]["lamVz_1"]
    _refused(
        lambda: check_study_manifest(m),
        "arrays: this study holds exactly ['theta', 'mu', 'lam', 'lamOs', 'log_post', "
        "'betaV_1', 'lamVz_1'], got ['betaV_1', 'lam', 'lamOs', 'log_post', 'mu', "
        "'theta']",
    )


@pytest.mark.parametrize(
    ("name", "shape", "message"),
    [
        (
            "betaV_1",
            (2, 3, 1),
            "arrays/betaV_1: must be (chains, draws, p, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (2, 3, 1)",
        ),
        (
            "betaV_1",
            (2, 3, 1, 1),
            "arrays/betaV_1: must be (chains, draws, p, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (2, 3, 1, 1)",
        ),
        (
            "betaV_1",
            (2, 4, 1, 2),
            "arrays/betaV_1: must be (chains, draws, p, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (2, 4, 1, 2)",
        ),
        (
            "betaV_1",
            (1, 3, 1, 2),
            "arrays/betaV_1: must be (chains, draws, p, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (1, 3, 1, 2)",
        ),
        (
            "lamVz_1",
            (2, 3, 3),
            "arrays/lamVz_1: must be (chains, draws, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (2, 3, 3)",
        ),
        (
            "lamVz_1",
            (2, 3, 1, 2),
            "arrays/lamVz_1: must be (chains, draws, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (2, 3, 1, 2)",
        ),
        (
            "lamVz_1",
            (2, 2, 2),
            "arrays/lamVz_1: must be (chains, draws, G) with (chains, "
            "draws) = (2, 3) and G = 2 precision group(s) (model b), got (2, 2, 2)",
        ),
    ],
)
def test_a_damaged_discrepancy_array_is_refused_by_name(name, shape, message):
    rec = {"b": {"discrepancy": "linear", "discrepancy_sha256": SHA, "discrepancy_groups": [0, 1]}}
    m = _edited(_with_discrepancy(rec))
    check_study_manifest(copy.deepcopy(m))
    m["arrays"][name] = _spec(*shape)
    _refused(lambda: check_study_manifest(m), message)


F = "settings.discrepancy_by_model"


@pytest.mark.parametrize(
    ("record", "kind", "message"),
    [
        (
            {"a": {"discrepancy": "constant", "discrepancy_sha256": SHA}},
            "fit",
            f"{F}: belongs to a calibration; a 'fit' study keeps its discrepancy draws in its "
            "members' files",
        ),
        ({}, "calibration", f"{F}: must be a non-empty object, got {{}}"),
        ([], "calibration", f"{F}: must be a non-empty object, got []"),
        ("constant", "calibration", f"{F}: must be a non-empty object, got 'constant'"),
        (
            {"c": {"discrepancy": "constant", "discrepancy_sha256": SHA}},
            "calibration",
            f"{F}: names the model 'c', not one of ['a', 'b']",
        ),
        (
            {"a": "constant"},
            "calibration",
            f"{F}.a: must be an object of discrepancy, discrepancy_sha256 and (several groups) "
            "discrepancy_groups, got 'constant'",
        ),
        (
            {"a": {"discrepancy": "constant", "discrepancy_sha256": SHA, "extra": 1}},
            "calibration",
            f"{F}.a: must be an object of discrepancy, discrepancy_sha256 and (several groups) "
            "discrepancy_groups, got {'discrepancy': 'constant', 'discrepancy_sha256': "
            "'012345...",
        ),
        (
            {"a": {"discrepancy": "quadratic", "discrepancy_sha256": SHA}},
            "calibration",
            f"{F}.a.discrepancy: must be one of ('constant', 'linear', 'given', 'list'), got "
            "'quadratic'",
        ),
        (
            {"a": {"discrepancy_sha256": SHA}},
            "calibration",
            f"{F}.a.discrepancy: must be one of ('constant', 'linear', 'given', 'list'), got None",
        ),
        (
            {"a": {"discrepancy": "constant"}},
            "calibration",
            f"{F}.a.discrepancy_sha256: must be 64 lowercase hex digits, got None",
        ),
        (
            {"a": {"discrepancy": "constant", "discrepancy_sha256": SHA[1:]}},
            "calibration",
            f"{F}.a.discrepancy_sha256: must be 64 lowercase hex digits, got '{SHA[1:57]}...",
        ),
        (
            {
                "a": {
                    "discrepancy": "constant",
                    "discrepancy_sha256": SHA,
                    "discrepancy_groups": [0, 1],
                }
            },
            "calibration",
            f"{F}.a.discrepancy_groups: [0, 1]: one group per basis vector, but a 'constant' "
            "discrepancy has 1",
        ),
    ],
)
def test_a_damaged_discrepancy_record_is_refused_by_name(record, kind, message):
    m = _edited(_with_discrepancy(record, kind))
    _refused(lambda: check_study_manifest(m), message)
    _refused(lambda: _check_discrepancies(m, kind, ["a", "b"]), message)


# --- check_study_arrays: the arrays against a hand-built layout ------------------------------

LAYOUT = Layout(
    labels=("a", "b"),
    elements=(
        Element("t[a]", "t", ((0, 0),), 0, (0.5, 10.0)),
        Element("t[b]", "t", ((1, 0),), 0, (0.5, 10.0)),
    ),
    index=((0,), (1,)),
    groups=("t",),
    bounds=((0.0, 1.0), (0.0, 1.0)),
    shared=(),
)


def _arrays() -> dict[str, np.ndarray]:
    return {
        "theta": np.full((2, 3, 2), 0.5),
        "mu": np.full((2, 3, 1), 0.25),
        "lam": np.full((2, 3, 1), 2.0),
        "lamOs": np.full((2, 3, 2), 3.0),
        "log_post": np.full((2, 3), -1.0),
    }


def _arrays_refused(arrays, message, levels=None, inputs=(1, 1), manifest=None) -> None:
    _refused(
        lambda: check_study_arrays(manifest or _manifest(), arrays, LAYOUT, inputs, levels), message
    )


def test_valid_arrays_pass():
    check_study_arrays(_manifest(), _arrays(), LAYOUT, (1, 1))
    check_study_arrays(_manifest(), _arrays(), LAYOUT, (1, 1), [None, None])
    a = _arrays()
    a["theta"][0, 0] = [np.nextafter(0.0, 1.0), np.nextafter(1.0, 0.0)]  # the edges inside
    a["mu"][1, 2, 0] = np.nextafter(1.0, 0.0)
    a["lam"][0, 0, 0] = a["lamOs"][1, 1, 1] = 5e-324
    check_study_arrays(_manifest(), a, LAYOUT, (1, 1))


def test_the_element_names_are_compared():
    m = _manifest()
    m["names"]["elements"] = ["t[b]", "t[a]"]
    _arrays_refused(
        _arrays(),
        "names.elements: ['t[b]', 't[a]'] differ from the models' study elements ['t[a]', 't[b]']",
        manifest=m,
    )
    del m["names"]
    _arrays_refused(
        _arrays(),
        "names.elements: None differ from the models' study elements ['t[a]', 't[b]']",
        manifest=m,
    )


def test_theta_needs_a_column_per_element():
    a = _arrays()
    a["theta"] = np.full((2, 3, 3), 0.5)
    _arrays_refused(a, "arrays/theta: has 3 columns for 2 study elements")
    a["theta"] = np.full((2, 3, 1), 0.5)
    _arrays_refused(a, "arrays/theta: has 1 columns for 2 study elements")


def test_betav_needs_a_row_per_known_input():
    a = _arrays()
    a["betaV_1"], a["lamVz_1"] = np.full((2, 3, 2, 1), 0.5), np.full((2, 3, 1), 2.0)
    check_study_arrays(_manifest(), a, LAYOUT, (1, 2))
    _arrays_refused(a, "arrays/betaV_1: has 2 rows of betaV for model b's 1 known input(s)")
    _arrays_refused(
        a, "arrays/betaV_1: has 2 rows of betaV for model b's 3 known input(s)", inputs=(2, 3)
    )
    a["betaV_0"], a["lamVz_0"] = np.full((2, 3, 1, 1), 0.5), np.full((2, 3, 1), 2.0)
    _arrays_refused(
        a, "arrays/betaV_0: has 1 rows of betaV for model a's 2 known input(s)", inputs=(2, 2)
    )


@pytest.mark.parametrize("name", ["theta", "mu", "lam", "lamOs", "log_post", "lamVz_0"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_draw_is_refused(name, bad):
    a = _arrays()
    a["betaV_0"], a["lamVz_0"] = np.full((2, 3, 1, 1), 0.5), np.full((2, 3, 1), 2.0)
    a[name].flat[-1] = bad
    _arrays_refused(a, f"arrays/{name}: holds NaN or inf")


@pytest.mark.parametrize(
    ("name", "index", "value", "message"),
    [
        ("theta", (1, 2, 1), 0.0, "arrays/theta: must lie in (0, 1) (unit scale), got 0..0.5"),
        ("theta", (0, 0, 0), 1.0, "arrays/theta: must lie in (0, 1) (unit scale), got 0.5..1"),
        (
            "theta",
            (0, 1, 1),
            -0.25,
            "arrays/theta: must lie in (0, 1) (unit scale), got -0.25..0.5",
        ),
        (
            "theta",
            (0, 1, 1),
            1 + 1e-9,
            "arrays/theta: must lie in (0, 1) (unit scale), got 0.5..1.000000001",
        ),
        ("mu", (1, 1, 0), 0.0, "arrays/mu: must lie in (0, 1) (unit scale), got 0..0.25"),
        ("mu", (1, 1, 0), 1.5, "arrays/mu: must lie in (0, 1) (unit scale), got 0.25..1.5"),
        ("lam", (1, 1, 0), 0.0, "arrays/lam: precisions must be > 0, got min 0"),
        ("lamOs", (0, 2, 1), -2.5, "arrays/lamOs: precisions must be > 0, got min -2.5"),
        ("lamVz_0", (0, 0, 0), 0.0, "arrays/lamVz_0: precisions must be > 0, got min 0"),
        (
            "betaV_0",
            (0, 0, 0, 0),
            -1.0,
            "arrays/betaV_0: correlation parameters must be > 0, got min -1",
        ),
    ],
)
def test_a_draw_out_of_its_range_is_refused(name, index, value, message):
    a = _arrays()
    a["betaV_0"], a["lamVz_0"] = np.full((2, 3, 1, 1), 0.5), np.full((2, 3, 1), 2.0)
    a[name][index] = value
    _arrays_refused(a, message)


def test_log_post_may_take_any_finite_value():
    a = _arrays()
    a["log_post"][:] = [[-1e300, 0.0, 1e300], [5.0, -5.0, 0.0]]
    check_study_arrays(_manifest(), a, LAYOUT, (1, 1))


def test_empty_draws_of_no_hierarchical_parameter_pass():
    a = _arrays()
    a["mu"], a["lam"] = np.zeros((2, 3, 0)), np.zeros((2, 3, 0))
    check_study_arrays(_manifest(), a, LAYOUT, (1, 1))


def test_a_categorical_column_holds_its_levels_and_only_them():
    levels = [None, [0.0, 0.5, 1.0]]
    a = _arrays()
    a["theta"][:, :, 1] = [[0.0, 1.0, 0.5], [1.0, 1.0, 0.0]]  # 0 and 1 are levels here
    check_study_arrays(_manifest(), a, LAYOUT, (1, 1), levels)
    a["theta"][1, 2, 1] = 0.25
    _arrays_refused(
        a,
        "arrays/theta: column 1 (t[b], categorical) must hold its unit-scale "
        "levels [0.0, 0.5, 1.0], got 0.25",
        levels,
    )
    a["theta"][1, 2, 1] = 1 + 1e-9  # not read as the level 1
    _arrays_refused(
        a,
        "arrays/theta: column 1 (t[b], categorical) must hold its unit-scale "
        "levels [0.0, 0.5, 1.0], got 1.000000001",
        levels,
    )
    b = _arrays()
    b["theta"][:, :, 0] = 0.0  # column 0 is continuous: 0 is outside (0, 1)
    b["theta"][:, :, 1] = 0.5
    _arrays_refused(b, "arrays/theta: must lie in (0, 1) (unit scale), got 0..0", levels)
    c = _arrays()
    c["theta"][:, :, 0] = 0.0
    c["theta"][:, :, 1] = 0.75
    _arrays_refused(
        c,
        "arrays/theta: column 1 (t[b], categorical) must hold its unit-scale "
        "levels [0.0, 1.0], got 0.75",
        [[0.0, 1.0], [0.0, 1.0]],
    )


# --- check_study_claims, _check_kind and _is_member_fit: hand-built studies ------------------


def _draws() -> dict[str, np.ndarray]:
    theta = np.arange(12.0).reshape(2, 3, 2) / 20.0 + 0.1  # (2 chains, 3 draws, 2 elements)
    return {"theta": theta, "log_post": np.zeros((2, 3))}


def _member(label, theta_cols, units=("",), tag=True):
    return SimpleNamespace(
        t_names=["t"],
        t_units=list(units),
        settings={"study": {"label": label}} if tag else {},
        calibration=None if theta_cols is None else {"theta": theta_cols},
    )


def _study(kind: str, fitted=(True, True), layout: Layout = LAYOUT) -> SimpleNamespace:
    draws = _draws()
    members = []
    for i, lab in enumerate(("a", "b")):
        cols = draws["theta"][:, :, list(layout.index[i])].reshape(-1, len(layout.index[i]))
        members.append(_member(lab, cols if fitted[i] else cols + 0.01))
    members[1].t_units = ["m"]
    return SimpleNamespace(
        kind=kind, labels=("a", "b"), layout=layout, members=members, draws=draws
    )


def test_a_member_fit_is_recognised_exactly():
    s = _study("fit")
    assert [_is_member_fit(s, i) for i in (0, 1)] == [True, True]
    s.members[0].settings = {"study": {"label": "b"}}  # another model's tag
    s.members[1].settings = {"study": "b"}  # not an object
    assert [_is_member_fit(s, i) for i in (0, 1)] == [False, False]
    s = _study("fit")
    s.members[0].settings = {}
    s.members[1].calibration = None
    assert [_is_member_fit(s, i) for i in (0, 1)] == [False, False]
    s = _study("fit", fitted=(True, False))
    assert [_is_member_fit(s, i) for i in (0, 1)] == [True, False]


def test_a_member_fit_compares_its_own_elements_draws():
    """Model b of a shared-and-own layout uses elements (0, 2): its draws are those columns."""
    layout = Layout(
        labels=("a", "b"),
        elements=(
            Element("s", "s", ((0, 0), (1, 0)), -1, (0.5, 10.0)),
            Element("t[a]", "t", ((0, 1),), -1, (0.5, 10.0)),
            Element("t[b]", "t", ((1, 1),), -1, (0.5, 10.0)),
        ),
        index=((0, 1), (0, 2)),
        groups=(),
        bounds=((0.0, 1.0),) * 3,
        shared=("s",),
    )
    theta = np.arange(18.0).reshape(2, 3, 3) / 30.0 + 0.1
    b = theta[:, :, [0, 2]].reshape(-1, 2)
    s = SimpleNamespace(
        kind="fit",
        labels=("a", "b"),
        layout=layout,
        members=[_member("a", theta[:, :, [0, 1]].reshape(-1, 2)), _member("b", b)],
        draws={"theta": theta},
    )
    assert [_is_member_fit(s, i) for i in (0, 1)] == [True, True]
    s.members[1].calibration = {"theta": theta[:, :, [0, 1]].reshape(-1, 2)}
    assert _is_member_fit(s, 1) is False
    s.members[1].calibration = {"theta": theta[:, :, [2, 0]].reshape(-1, 2)}
    assert _is_member_fit(s, 1) is False


def test_the_kind_matches_the_member_files():
    _check_kind(_study("fit"))
    _check_kind(_study("calibration", fitted=(True, False)))
    _check_kind(_study("calibration", fitted=(False, False)))
    _refused(
        lambda: _check_kind(_study("fit", fitted=(True, False))),
        "study.kind: 'fit', but model 'b''s file is not this study's fitted member (its "
        "study label or theta draws differ)",
    )
    _refused(
        lambda: _check_kind(_study("fit", fitted=(False, True))),
        "study.kind: 'fit', but model 'a''s file is not this study's fitted member (its "
        "study label or theta draws differ)",
    )
    _refused(
        lambda: _check_kind(_study("calibration")),
        "study.kind: 'calibration', but every model file is this study's fitted member: "
        "the draws are a joint fit's",
    )


def _claims_manifest(**settings) -> dict:
    m = _manifest()
    m["settings"] = {"n_iter": 4, "n_burn": 1, "n_chains": 2, **settings}
    return m


def test_the_claims_of_a_valid_record_pass():
    check_study_claims(_claims_manifest(), _study("calibration", fitted=(False, True)))
    check_study_claims(_claims_manifest(), _study("fit"))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            _set("names.models", ["b", "a"]),
            "names.models: ['b', 'a'] differ from the models' ['a', 'b']",
        ),
        (_drop("names.models"), "names.models: None differ from the models' ['a', 'b']"),
        (
            _set("names.t.b", ["u"]),
            "names.t: {'a': ['t'], 'b': ['u']} differ from the models' {'a': ['t'], 'b': ['t']}",
        ),
        (
            _set("units.a", ["m"]),
            "units: {'a': ['m'], 'b': ['m']} differ from the models' {'a': [''], 'b': ['m']}",
        ),
        (_drop("units"), "units: None differ from the models' {'a': [''], 'b': ['m']}"),
        (_set("settings.n_chains", 3), "settings.n_chains: 3, but the draws have 2 chains"),
        (
            _set("settings.accept_rate", {"t[a]": 1.01}),
            "settings.accept_rate['t[a]']: must be null or an acceptance rate in [0, 1], got 1.01",
        ),
        (
            _set("settings.hot_states", {}),
            "settings.hot_step_widths: a tempered study records ['hot_states', 'hot_step_widths'] "
            "together; the file has only ['hot_states']",
        ),
    ],
)
def test_a_false_claim_is_refused_by_name(edit, message):
    m = _claims_manifest()
    edit(m)
    _refused(lambda: check_study_claims(m, _study("calibration", fitted=(False, True))), message)


def test_the_claims_check_the_kind():
    _refused(
        lambda: check_study_claims(_claims_manifest(), _study("calibration")),
        "study.kind: 'calibration', but every model file is this study's fitted member: "
        "the draws are a joint fit's",
    )


# --- _check_counts: the chains and draws the settings keep -----------------------------------


@pytest.mark.parametrize(
    ("settings", "shape"),
    [
        ({"n_chains": 2, "n_iter": 4, "n_burn": 1}, (2, 3)),
        ({"n_chains": 1, "n_iter": 3, "n_burn": 0}, (1, 3)),  # n_burn's edge
        ({"n_chains": 1, "n_iter": 1, "n_burn": 0}, (1, 1)),  # n_iter's edge
        ({"n_chains": 1, "n_iter": 4, "n_burn": 1, "thin": 1}, (1, 3)),
        ({"n_chains": 1, "n_iter": 6, "n_burn": 1, "thin": 2}, (1, 3)),  # sweeps 1, 3, 5
        ({"n_chains": 1, "n_iter": 5, "n_burn": 1, "thin": 2}, (1, 2)),  # sweeps 1, 3
        ({"n_chains": 1, "n_iter": 7, "n_burn": 0, "thin": 3}, (1, 3)),  # sweeps 0, 3, 6
        ({"n_chains": 1, "n_iter": 4, "n_burn": 1, "thin": 5}, (1, 1)),  # sweep 1
        ({"n_chains": 3, "n_iter": 4, "n_burn": 1, "n_samples": 4}, (3, 3)),
        ({"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": None}, (1, 3)),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": {"t": 0, "u": 1.0, "v": None}},
            (1, 3),
        ),
    ],
)
def test_counts_that_keep_the_draws_pass(settings, shape):
    _check_counts(settings, shape)


APPENDED = {"appended_to": SHA, "pooled_sweeps": 9, "sweeps_run": 9}


@pytest.mark.parametrize(
    ("settings", "shape", "message"),
    [
        (
            {"n_chains": True, "n_iter": 4, "n_burn": 1},
            (1, 3),
            "settings.n_chains: must be an integer >= 1, got True",
        ),
        (
            {"n_chains": 0, "n_iter": 4, "n_burn": 1},
            (1, 3),
            "settings.n_chains: must be an integer >= 1, got 0",
        ),
        (
            {"n_chains": 1.0, "n_iter": 4, "n_burn": 1},
            (1, 3),
            "settings.n_chains: must be an integer >= 1, got 1.0",
        ),
        (
            {"n_iter": 4, "n_burn": 1},
            (1, 3),
            "settings.n_chains: must be an integer >= 1, got None",
        ),
        (
            {"n_chains": 1, "n_iter": 0, "n_burn": 0},
            (1, 3),
            "settings.n_iter: must be an integer >= 1, got 0",
        ),
        (
            {"n_chains": 1, "n_burn": 0},
            (1, 3),
            "settings.n_iter: must be an integer >= 1, got None",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": -1},
            (1, 3),
            "settings.n_burn: must be an integer >= 0, got -1",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": False},
            (1, 3),
            "settings.n_burn: must be an integer >= 0, got False",
        ),
        (
            {"n_chains": 1, "n_iter": 4},
            (1, 3),
            "settings.n_burn: must be an integer >= 0, got None",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "thin": 0},
            (1, 3),
            "settings.thin: must be an integer >= 1, got 0",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "thin": None},
            (1, 3),
            "settings.thin: must be an integer >= 1, got None",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "n_samples": 5},
            (1, 3),
            "settings.n_samples: 5 differs from n_iter 4",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "n_samples": None},
            (1, 3),
            "settings.n_samples: must be an integer, got None",
        ),
        (
            {"n_chains": 2, "n_iter": 4, "n_burn": 1},
            (1, 3),
            "settings.n_chains: 2, but the draws have 1 chains",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1},
            (2, 3),
            "settings.n_chains: 1, but the draws have 2 chains",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1},
            (1, 4),
            "settings: n_iter=4, n_burn=1, thin=1 keep 3 draws a chain, but the draws have 4",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1},
            (1, 2),
            "settings: n_iter=4, n_burn=1, thin=1 keep 3 draws a chain, but the draws have 2",
        ),
        (
            {"n_chains": 1, "n_iter": 6, "n_burn": 1, "thin": 2},
            (1, 2),
            "settings: n_iter=6, n_burn=1, thin=2 keep 3 draws a chain, but the draws have 2",
        ),
        (
            {"n_chains": 1, "n_iter": 7, "n_burn": 0, "thin": 3},
            (1, 2),
            "settings: n_iter=7, n_burn=0, thin=3 keep 3 draws a chain, but the draws have 2",
        ),
        (
            {"n_chains": 1, "n_iter": 1, "n_burn": 3},
            (1, 1),
            "settings: n_iter=1, n_burn=3, thin=1 keep 0 draws a chain, but the draws have 1",
        ),
        (
            {"n_chains": 1, "n_iter": 3, "n_burn": 3},
            (1, 1),
            "settings: n_iter=3, n_burn=3, thin=1 keep 0 draws a chain, but the draws have 1",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": [0.5]},
            (1, 3),
            "settings.accept_rate: must be an object element -> rate, got [0.5]",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": {"t": -0.1}},
            (1, 3),
            "settings.accept_rate['t']: must be null or an acceptance rate in [0, 1], got -0.1",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": {"t": 0.5, "u": True}},
            (1, 3),
            "settings.accept_rate['u']: must be null or an acceptance rate in [0, 1], got True",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": {"x" * 39: 2}},
            (1, 3),
            f"settings.accept_rate['{'x' * 36}...]: must be null or an acceptance rate in [0, 1], "
            "got 2",
        ),
        (
            {"n_chains": 1, "n_iter": 4, "n_burn": 1, "accept_rate": {"x" * 38: 2}},
            (1, 3),
            f"settings.accept_rate['{'x' * 38}']: must be null or an acceptance rate in [0, 1], "
            "got 2",
        ),
        (
            {"n_chains": 1, "n_iter": 2**63, "n_burn": 2**63 - 2},
            (1, 2),
            f"settings.n_iter: must be null or an integer in [1, {2**63 - 1}], got {2**63}",
        ),
    ],
)
def test_counts_that_disagree_are_refused_by_name(settings, shape, message):
    _refused(lambda: _check_counts(settings, shape), message)


def test_an_appended_study_keeps_the_source_draws_then_whole_thin_periods():
    """After appended_after source draws, a continuation keeps sweeps thin - 1, 2 thin - 1, ...
    of its (n_iter - n_burn): floor((n_iter - n_burn) / thin) of them."""
    base = {"n_chains": 1, "n_iter": 5, "n_burn": 0, "thin": 2, "appended_after": 2, **APPENDED}
    _check_counts(base, (1, 4))  # 2 + floor(5 / 2)
    _refused(
        lambda: _check_counts(base, (1, 5)),
        "settings: n_iter=5, n_burn=0, thin=2 keep 2 draws a chain after appended_after=2, "
        "but the draws have 5",
    )
    _check_counts({**base, "n_iter": 6, "n_burn": 1}, (1, 4))  # 2 + floor(5 / 2)
    _check_counts({**base, "thin": 1, "appended_after": 1}, (1, 6))  # 1 + 5
    _refused(
        lambda: _check_counts({**base, "n_iter": 1, "n_burn": 3, "thin": 1}, (1, 3)),
        "settings: n_iter=1, n_burn=3, thin=1 keep 0 draws a chain after appended_after=2, "
        "but the draws have 3",
    )
    for after in (0, -1, True, None, 2.0):
        _refused(
            lambda after=after: _check_counts({**base, "appended_after": after}, (1, 4)),
            f"settings.appended_after: must be an integer >= 1, got {after!r}",
        )
    _refused(
        lambda: _check_counts({k: v for k, v in base.items() if k != "appended_after"}, (1, 4)),
        "settings.appended_after: must be an integer >= 1, got None",
    )


@pytest.mark.parametrize("n_samples", [True, 1.0, "1"])
def test_n_samples_other_than_the_integer_n_iter_is_refused(n_samples):
    """calibrate_study records n_samples, the integer n_iter: True and 1.0 equal 1 but are not
    it (a damaged record), and the refusal says so rather than "differs" (session 91)."""
    settings = {"n_chains": 1, "n_iter": 1, "n_burn": 0, "n_samples": n_samples}
    _refused(
        lambda: _check_counts(settings, (1, 1)),
        f"settings.n_samples: must be an integer, got {n_samples!r}",
    )


def test_an_appended_study_is_checked_as_an_unsaved_source_s_continuation():
    """A study's source may never have been saved (appended_to null), and appended_after must
    leave the continuation at least one draw of each chain's (chains x draws) = shape."""
    base = {"n_chains": 1, "n_iter": 5, "n_burn": 0, "thin": 1, "appended_after": 1, **APPENDED}
    _check_counts({**base, "appended_to": None}, (1, 6))
    _refused(
        lambda: _check_counts(
            {**base, "n_iter": 4, "n_burn": 3, "thin": 2, "appended_after": 2}, (1, 2)
        ),
        "settings.appended_after: must be an integer in [1, 1] (the source's draws of each "
        "chain, before the continuation's), got 2",
    )
    _check_counts({**base, "n_chains": 2, "appended_after": 2}, (2, 7))
    _refused(
        lambda: _check_counts(
            {**base, "n_chains": 2, "n_iter": 4, "n_burn": 3, "thin": 2, "appended_after": 3},
            (2, 3),
        ),
        "settings.appended_after: must be an integer in [1, 2] (the source's draws of each "
        "chain, before the continuation's), got 3",
    )


def test_rates_are_checked_exactly():
    _check_rates(None)
    _check_rates({})
    _check_rates({"t": 0, "u": 1, "v": None, "w": 0.5})
    _refused(
        lambda: _check_rates("0.5"),
        "settings.accept_rate: must be an object element -> rate, got '0.5'",
    )
    _refused(
        lambda: _check_rates({"t": 0.5, "u": 1 + 1e-12}),
        "settings.accept_rate['u']: must be null or an acceptance rate in [0, 1], got "
        "1.000000000001",
    )


# --- a tiny saved study, read back field by field --------------------------------------------


def test_a_saved_study_record_reads_back_field_by_field(tmp_path):
    import gpmsa
    from gpmsa.io.container import FORMAT, STUDY_FORMAT, read_raw
    from tests.gpmsa._study_cases import two_model_study

    study = two_model_study(12, 4, 1)
    path = study.save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    digests = [
        read_raw(tmp_path / f"run.{lab}.gpmsa", formats=(FORMAT,))[0]["content_sha256"]
        for lab in "ab"
    ]
    assert manifest["study"] == {
        "kind": "calibration",
        "shared": [],
        "hierarchical": ["t"],
        "models": [
            {"label": "a", "file": "run.a.gpmsa", "sha256": digests[0]},
            {"label": "b", "file": "run.b.gpmsa", "sha256": digests[1]},
        ],
    }
    assert manifest["names"] == {
        "models": ["a", "b"],
        "elements": ["t[a]", "t[b]"],
        "t": {"a": ["t"], "b": ["t"]},
    }
    assert manifest["units"] == {"a": [""], "b": [""]}
    assert manifest["priors"]["hyper"] == {
        "sd_prior": "uniform",
        "mu_mean": 0.5,
        "mu_sd": 10.0,
        "sd_max": 1.0,
        "lam_a": 1.0,
        "lam_b": 0.001,
        "lam_start": 5.0,
    }
    s = manifest["settings"]
    assert (s["n_chains"], s["n_iter"], s["n_burn"], s["n_samples"]) == (1, 12, 4, 12)
    assert {k: (v["shape"], v["dtype"]) for k, v in manifest["arrays"].items()} == {
        "theta": ([1, 8, 2], "<f8"),
        "mu": ([1, 8, 1], "<f8"),
        "lam": ([1, 8, 1], "<f8"),
        "lamOs": ([1, 8, 2], "<f8"),
        "log_post": ([1, 8], "<f8"),
    }
    back = gpmsa.load_study(path)
    assert back.kind == study.kind and back.labels == study.labels
    assert back.layout == study.layout and back.hyper == study.hyper
    assert back.settings == study.settings
    assert sorted(back.draws) == sorted(study.draws) == sorted(arrays)
    for k, v in study.draws.items():
        assert back.draws[k].dtype == np.float64
        assert np.array_equal(back.draws[k], v), k
        assert np.array_equal(arrays[k], v), k
    assert back.sha256 == manifest["content_sha256"] == study.sha256
