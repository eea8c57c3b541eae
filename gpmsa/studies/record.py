"""Checks of a study file's record (manifest + arrays); each failure an EmulatorFileError naming
the field ("study.models[1].sha256", "arrays/theta", ...). docs/models.md describes the layout."""

from __future__ import annotations

import re

import numpy as np

from gpmsa.errors import EmulatorFileError, numbers_text
from gpmsa.fitting.validation import DISCREPANCY_KINDS, check_rate, check_sweeps, group_count
from gpmsa.studies.hot import check_hot_record
from gpmsa.studies.layout import LABEL_RE, NUMBERS, SD_PRIORS, Layout, finite, sd_max_usable

KINDS = ("calibration", "fit")
"""How a study's draws were made: calibration with the emulators fixed, or a joint fit."""
ARRAYS = ("theta", "mu", "lam", "lamOs", "log_post")
"""The arrays of a study file: (C, N, G), (C, N, H), (C, N, H), (C, N, M), (C, N)."""
DISCREPANCIES = "discrepancy_by_model"
"""The settings key of a calibrated study's record of each model's discrepancy: label ->
{"discrepancy": "constant", "linear", "given" (an array) or "list" (per-experiment arrays),
"discrepancy_sha256": the basis
digest (``gpmsa.model.discrepancy.record``), and with several precision groups
"discrepancy_groups"}; absent for a study without one (and in files written before it)."""
FILE_RE = re.compile(r"\A[A-Za-z0-9_-][A-Za-z0-9_.-]{0,150}\.gpmsa\Z")
"""A model's file name: beside the study file, no folder, no leading dot."""
SHA_RE = re.compile(r"\A[0-9a-f]{64}\Z")
"""A sha256 digest: 64 lowercase hex digits, nothing after (``$`` would take a final newline)."""


def discrepancy_arrays(j: int) -> tuple[str, str]:
    """The study file's arrays of model j's discrepancy draws: betaV (C, N, p, G), lamVz
    (C, N, G) (array names allow no label: a label may hold '-')."""
    return f"betaV_{j}", f"lamVz_{j}"


def _fail(field: str, problem: str) -> EmulatorFileError:
    return EmulatorFileError(f"{field}: {problem}")


def _short(value, n: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= n else text[: n - 3] + "..."


def _names(value, field: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise _fail(field, f"must be a list of strings, got {_short(value)}")
    return value


def check_study_manifest(manifest: dict) -> None:
    """The study fields of a manifest (before any array is decompressed)."""
    study = manifest.get("study")
    if not isinstance(study, dict):
        raise _fail("study", f"must be an object, got {_short(study)}")
    if study.get("kind") not in KINDS:
        raise _fail("study.kind", f"must be one of {KINDS}, got {_short(study.get('kind'))}")
    _names(study.get("shared"), "study.shared")
    _names(study.get("hierarchical"), "study.hierarchical")
    models = study.get("models")
    if not isinstance(models, list) or not models:
        raise _fail("study.models", f"must be a non-empty list, got {_short(models)}")
    labels, files = [], []
    for j, mod in enumerate(models):
        where = f"study.models[{j}]"
        if not isinstance(mod, dict):
            raise _fail(where, f"must be an object, got {_short(mod)}")
        lab, file, sha = mod.get("label"), mod.get("file"), mod.get("sha256")
        if not isinstance(lab, str) or not LABEL_RE.match(lab):
            raise _fail(f"{where}.label", f"must be 1-48 letters, digits, _ or -: {_short(lab)}")
        if not isinstance(file, str) or not FILE_RE.match(file):
            raise _fail(f"{where}.file", f"must be a .gpmsa file name beside the study file (no "
                                         f"folder), got {_short(file)}")  # fmt: skip
        if not isinstance(sha, str) or not SHA_RE.match(sha):
            raise _fail(f"{where}.sha256", f"must be 64 lowercase hex digits, got {_short(sha)}")
        labels.append(lab)
        files.append(file)
    if len(set(labels)) != len(labels):
        raise _fail("study.models", f"labels repeat: {labels}")
    if len(set(files)) != len(files):
        raise _fail("study.models", f"files repeat: {files}")
    hyper = manifest["priors"].get("hyper")
    if not isinstance(hyper, dict):
        raise _fail("priors.hyper", f"must be an object, got {_short(hyper)}")
    unknown = set(hyper) - {"sd_prior", *NUMBERS}
    if unknown:
        raise _fail("priors.hyper", f"unknown keys {_short(sorted(unknown))}")
    if hyper.get("sd_prior", "gamma") not in SD_PRIORS:  # files before the key had SEPIA's
        raise _fail("priors.hyper.sd_prior", f"must be one of {SD_PRIORS}, got "
                                             f"{_short(hyper.get('sd_prior'))}")  # fmt: skip
    for key in NUMBERS:
        if key == "sd_max" and key not in hyper and hyper.get("sd_prior", "gamma") == "gamma":
            continue  # files before sd_prior (SEPIA's Gamma) have no sd_max; a uniform one does
        val = hyper.get(key)
        ok = isinstance(val, (int, float)) and not isinstance(val, bool) and finite(val)
        if not ok or (key != "mu_mean" and not val > 0):
            need = "a finite number" if key == "mu_mean" else "a finite number > 0"
            raise _fail(f"priors.hyper.{key}", f"must be {need}, got {_short(val)}")
        if key == "sd_max" and not sd_max_usable(val):  # as HyperPriors checks it
            raise _fail(f"priors.hyper.{key}", f"{_short(val)}: its square and 4/sd_max^2 are "
                                               "not finite, non-zero float64s")  # fmt: skip
    n_groups = _check_discrepancies(manifest, study["kind"], labels)
    specs = manifest["arrays"]
    want = [*ARRAYS, *(a for j in n_groups for a in discrepancy_arrays(j))]
    if set(specs) != set(want):
        raise _fail("arrays", f"this study holds exactly {want}, got {sorted(specs)[:10]}")
    for name, spec in specs.items():
        if spec["dtype"] != "<f8":
            raise _fail(f"arrays/{name}", f"dtype {spec['dtype']}: must be <f8 (float64)")
    shape = {k: tuple(specs[k]["shape"]) for k in ARRAYS}
    if len(shape["log_post"]) != 2:
        raise _fail("arrays/log_post", f"must be (chains, draws), got {shape['log_post']}")
    cn = shape["log_post"]
    for what, size in zip(("chain", "draw"), cn, strict=True):
        if size < 1:
            raise _fail("arrays/log_post", f"needs >= 1 {what}, got shape {cn}")
    for k in ("theta", "mu", "lam", "lamOs"):
        if len(shape[k]) != 3 or shape[k][:2] != cn:
            raise _fail(f"arrays/{k}", f"must be (chains, draws, k) with (chains, draws) = {cn}, "
                                       f"got {shape[k]}")  # fmt: skip
    if shape["lamOs"][2] != len(models):
        raise _fail("arrays/lamOs", f"has {shape['lamOs'][2]} columns for {len(models)} models")
    n_h = len(study["hierarchical"])
    if shape["mu"] != shape["lam"] or shape["mu"][2] != n_h:
        raise _fail("arrays/mu", f"mu {shape['mu']} and lam {shape['lam']} need one column per "
                                 f"hierarchical parameter ({n_h})")  # fmt: skip
    for j, g in n_groups.items():
        beta, lam = discrepancy_arrays(j)
        for name, ndim in ((beta, 4), (lam, 3)):
            got = tuple(specs[name]["shape"])
            if len(got) != ndim or got[:2] != cn or got[-1] != g:
                what = "(chains, draws, p, G)" if ndim == 4 else "(chains, draws, G)"
                raise _fail(f"arrays/{name}", f"must be {what} with (chains, draws) = {cn} and "
                                              f"G = {g} precision group(s) (model "
                                              f"{labels[j]}), got {got}")  # fmt: skip


def _check_discrepancies(manifest: dict, kind: str, labels: list[str]) -> dict[int, int]:
    """The settings' record of the models' discrepancies (``DISCREPANCIES``): model index ->
    its number of precision groups."""
    record = manifest["settings"].get(DISCREPANCIES)  # settings: an object (the container's)
    field = f"settings.{DISCREPANCIES}"
    if record is None:
        return {}
    if kind != "calibration":
        raise _fail(field, f"belongs to a calibration; a {kind!r} study keeps its discrepancy "
                           "draws in its members' files")  # fmt: skip
    if not isinstance(record, dict) or not record:
        raise _fail(field, f"must be a non-empty object, got {_short(record)}")
    out = {}
    for lab, rec in record.items():
        where = f"{field}.{lab}"
        if lab not in labels:
            raise _fail(field, f"names the model {_short(lab)}, not one of {labels}")
        keys = {"discrepancy", "discrepancy_sha256", "discrepancy_groups"}
        if not isinstance(rec, dict) or set(rec) - keys:
            raise _fail(
                where,
                "must be an object of discrepancy, discrepancy_sha256 and (several groups) "
                f"discrepancy_groups, got {_short(rec)}",
            )
        if rec.get("discrepancy") not in DISCREPANCY_KINDS:
            raise _fail(f"{where}.discrepancy", f"must be one of {DISCREPANCY_KINDS}, got "
                                                f"{_short(rec.get('discrepancy'))}")  # fmt: skip
        sha = rec.get("discrepancy_sha256")
        if not isinstance(sha, str) or not SHA_RE.match(sha):
            raise _fail(f"{where}.discrepancy_sha256", f"must be 64 lowercase hex digits, got "
                                                       f"{_short(sha)}")  # fmt: skip
        groups = rec.get("discrepancy_groups")
        out[labels.index(lab)] = group_count(rec["discrepancy"], groups,
                                             f"{where}.discrepancy_groups")  # fmt: skip
    return out


def check_study_arrays(
    manifest: dict,
    arrays: dict[str, np.ndarray],
    layout: Layout,
    inputs: tuple[int, ...],
    levels: list | None = None,
) -> None:
    """The arrays against the models' layout and their numbers of known inputs ``inputs`` (a
    model's discrepancy betaV has one row per input): shapes, finiteness and ranges (``levels``:
    per study element its unit-scale levels where it is categorical, its draws one of them,
    else None; None: every element continuous)."""
    names = manifest.get("names", {}).get("elements")
    want = [el.name for el in layout.elements]
    if names != want:
        raise _fail("names.elements", f"{_short(names, 200)} differ from the models' study "
                                      f"elements {want}")  # fmt: skip
    if arrays["theta"].shape[2] != layout.n_elements:
        raise _fail("arrays/theta", f"has {arrays['theta'].shape[2]} columns for "
                                    f"{layout.n_elements} study elements")  # fmt: skip
    for j, p in enumerate(inputs):
        beta = discrepancy_arrays(j)[0]
        if beta in arrays and arrays[beta].shape[2] != p:
            raise _fail(f"arrays/{beta}", f"has {arrays[beta].shape[2]} rows of betaV for model "
                                          f"{layout.labels[j]}'s {p} known input(s)")  # fmt: skip
    for name in arrays:
        if not np.all(np.isfinite(arrays[name])):
            raise _fail(f"arrays/{name}", "holds NaN or inf")
    levels = levels or [None] * layout.n_elements
    for e, lv in enumerate(levels):  # a categorical element's draws: its levels (0 and 1 too)
        col = arrays["theta"][:, :, e]
        if lv is not None and not np.all(np.isin(col, lv)):
            bad = numbers_text(col[~np.isin(col, lv)].flat[0], *lv)[0]  # not read as a level
            raise _fail("arrays/theta", f"column {e} ({layout.elements[e].name}, categorical) "
                                        f"must hold its unit-scale levels {list(lv)}, got "
                                        f"{bad}")  # fmt: skip
    cont = [e for e, lv in enumerate(levels) if lv is None]
    for name, a in (("theta", arrays["theta"][:, :, cont]), ("mu", arrays["mu"])):
        if a.size and not (a.min() > 0.0 and a.max() < 1.0):  # 1 + 1e-9 not read as 1
            low, high = numbers_text(a.min(), a.max(), 0.0, 1.0)[:2]
            raise _fail(f"arrays/{name}", f"must lie in (0, 1) (unit scale), got {low}..{high}")
    for name in ("lam", "lamOs", *(k for k in arrays if k not in ARRAYS)):
        a = arrays[name]
        if a.size and not a.min() > 0.0:
            what = "correlation parameters" if name.startswith("betaV") else "precisions"
            raise _fail(f"arrays/{name}", f"{what} must be > 0, got min {a.min():.6g}")


def check_study_claims(manifest: dict, study) -> None:
    """The manifest's descriptions against the study built from the file's models and draws:
    the models' labels, t_names and units, the kind (a "fit" study's models are its fitted
    members, their theta draws the study's) and the settings' chain and draw counts. The
    diagnostics and convergence record are not compared: a loaded Study computes its own from
    the draws, and a comparison would refuse a genuine file whenever ArviZ's estimators (or
    the convergence limits) change."""
    labels = list(study.labels)
    want = {
        "names.models": (manifest["names"].get("models"), labels),
        "names.t": (manifest["names"].get("t"),
                    {lab: list(e.t_names) for lab, e in zip(labels, study.members, strict=True)}),
        "units": (manifest.get("units"),
                  {lab: list(e.t_units) for lab, e in zip(labels, study.members, strict=True)}),
    }  # fmt: skip
    for field, (saved, expected) in want.items():
        if saved != expected:
            raise _fail(field, f"{_short(saved, 200)} differ from the models' {expected}")
    _check_kind(study)
    _check_counts(manifest["settings"], study.draws["log_post"].shape)
    check_hot_record(manifest["settings"], study)


def _check_kind(study) -> None:
    """kind "fit" if and only if every model file is this study's fitted member: it names the
    study's label, and its calibration theta draws are the study's draws of its elements (a
    calibration's models are fitted elsewhere)."""
    fitted = [_is_member_fit(study, i) for i in range(len(study.members))]
    if study.kind == "fit" and not all(fitted):
        lab = study.labels[fitted.index(False)]
        raise _fail("study.kind", f"'fit', but model {lab!r}'s file is not this study's fitted "
                                  "member (its study label or theta draws differ)")  # fmt: skip
    if study.kind == "calibration" and all(fitted):
        raise _fail("study.kind", "'calibration', but every model file is this study's fitted "
                                  "member: the draws are a joint fit's")  # fmt: skip


def _is_member_fit(study, i: int) -> bool:
    """Whether model i's emulator was fitted in this study (``fit_study``'s member): its study
    tag names the label, and its calibration theta draws are the study's. The tag's shared and
    hierarchical names are not compared: files written before they were recorded from the
    layout may hold the caller's spelling of them."""
    layout, emu = study.layout, study.members[i]
    tag = emu.settings.get("study")
    mine = study.draws["theta"][:, :, list(layout.index[i])].reshape(-1, len(layout.index[i]))
    cal = getattr(emu, "calibration", None) or {}
    return (
        isinstance(tag, dict)
        and tag.get("label") == study.labels[i]
        and np.array_equal(cal.get("theta", ()), mine)
    )


def _check_counts(settings: dict, shape: tuple[int, int]) -> None:
    """settings' n_chains and the draws a chain kept (n_iter, n_burn, thin; an appended study's
    "appended_after" draws of its source first) against the draws' (chains, draws) ``shape``."""
    got = {k: settings.get(k, 1 if k == "thin" else None)
           for k in ("n_chains", "n_iter", "n_burn", "thin")}  # fmt: skip
    for k, v in got.items():
        low = 0 if k == "n_burn" else 1
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise _fail(f"settings.{k}", f"must be an integer >= {low}, got {_short(v)}")
    n_samples = settings.get("n_samples", got["n_iter"])  # calibrate_study's name of n_iter
    if isinstance(n_samples, bool) or not isinstance(n_samples, int):
        raise _fail("settings.n_samples", f"must be an integer, got {_short(n_samples)}")
    if n_samples != got["n_iter"]:
        raise _fail("settings.n_samples", f"{_short(n_samples)} differs from n_iter "
                                          f"{got['n_iter']}")  # fmt: skip
    if got["n_chains"] != shape[0]:
        raise _fail("settings.n_chains", f"{got['n_chains']}, but the draws have {shape[0]} "
                                         "chains")  # fmt: skip
    # len(range(n_burn, n_iter, thin)) without its OverflowError: a JSON integer has any size
    kept = max(0, -(-(got["n_iter"] - got["n_burn"]) // got["thin"]))
    before, what = 0, ""
    if "appended_to" in settings:  # the source's draws, then sweeps thin - 1, 2 thin - 1, ...
        before = settings.get("appended_after")
        if isinstance(before, bool) or not isinstance(before, int) or before < 1:
            raise _fail("settings.appended_after", f"must be an integer >= 1, got "
                                                   f"{_short(before)}")  # fmt: skip
        kept = max(0, (got["n_iter"] - got["n_burn"]) // got["thin"])
        what = f" after appended_after={before}"
    if before + kept != shape[1]:
        raise _fail("settings", f"n_iter={got['n_iter']}, n_burn={got['n_burn']}, thin="
                                f"{got['thin']} keep {kept} draws a chain{what}, but the draws "
                                f"have {shape[1]}")  # fmt: skip
    check_sweeps(settings, shape[0] * shape[1], unsaved=True)  # as an appended fit's
    _check_rates(settings.get("accept_rate"))


def _check_rates(rates) -> None:
    """settings.accept_rate (absent in files written before it): null or sweep element name ->
    its acceptance rate (null or in [0, 1]), which an appended study pools."""
    if rates is None:
        return
    if not isinstance(rates, dict):
        raise _fail("settings.accept_rate", f"must be an object element -> rate, got "
                                            f"{_short(rates)}")  # fmt: skip
    for name, v in rates.items():
        check_rate(v, f"settings.accept_rate[{_short(name, 40)}]")
