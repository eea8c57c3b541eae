"""``gpmsa info FILE --json``: what ``gpmsa info`` prints, as one JSON object for programs.

Its keys are documented in docs/emulator-file.md ("gpmsa info --json"); ``INFO_FORMAT`` names
their version. Numbers are JSON numbers; a value that is not finite (an R-hat of stuck chains,
the ESS of a held parameter) is null, and so is a prior's infinite upper bound, so a strict
parser (RFC 8259: no NaN or Infinity tokens) reads the output; the posterior's "rhat_inf" tells
an infinite R-hat (chains stuck apart) from one not computable. The verified manifest is kept
whole under "manifest".
"""

from __future__ import annotations

import json
import math

from gpmsa.cli.index_text import index_record
from gpmsa.io.container import jsonable

INFO_FORMAT = "gpmsa-info/1"
"""The version of the keys below: a key's meaning changes only with a new version."""


def dumps(record: dict) -> str:
    """``record`` as strict JSON text: non-finite floats as null, every non-ASCII or control
    character escaped (``\\u001b``: a file's names cannot drive the terminal)."""
    return json.dumps(jsonable(record), indent=1, sort_keys=True, ensure_ascii=True,
                      allow_nan=False)  # fmt: skip


def _head(file: str, manifest: dict, kind: str) -> dict:
    """The keys every file's record has: what it is and where it came from."""
    keys = ("format", "schema_version", "library_version", "created_utc", "content_sha256")
    return {"info_format": INFO_FORMAT, "kind": kind, "file": str(file),
            **{k: manifest.get(k) for k in keys}, "manifest": manifest}  # fmt: skip


def _converged(record: object) -> bool | None:
    """The convergence record's verdict; None where none was made (from_params, older files)."""
    if not isinstance(record, dict) or not record:
        return None
    flagged = record.get("flagged")
    return not flagged if flagged is None or isinstance(flagged, dict) else None


def _inputs(manifest: dict, kind: str) -> list[dict]:
    """Known inputs (``kind`` "x") or calibration parameters ("t"): name, unit, native range
    (the unit scale's [0, 1]), whether that range was given (``SimData(x_range=, t_range=)``)
    and a categorical input's training levels."""
    model = manifest.get("model", {})
    given, cat = model.get("input_ranges") or (), model.get("categorical") or {}
    pairs = zip(manifest["names"][kind], manifest["units"][kind], strict=True)
    return [{"name": n, "unit": u, "range": manifest["domain"].get(n), "range_given": n in given,
             "levels": cat.get(n)} for n, u in pairs]  # fmt: skip


def _priors(priors: object) -> object:
    """The manifest's priors with each Gamma's infinite upper bound ("inf") as null."""
    if isinstance(priors, list):
        return [_priors(v) for v in priors]
    if not isinstance(priors, dict):
        return priors
    out = {k: _priors(v) for k, v in priors.items()}
    if {"a", "b", "lower", "upper"} <= set(out) and out["upper"] == "inf":
        out["upper"] = None
    return out


def emulator_info(file: str, manifest: dict, facts: dict) -> dict:
    """An emulator file's record: ``manifest`` verified, ``facts`` what ``gpmsa.cli.info``
    derives from it and the emulator loaded from it (its ``_facts``: model_sha256, the
    separable factors, output scale, output index, basis, posterior, array_values)."""
    model = manifest.get("model", {})
    convergence = manifest.get("convergence")
    return {
        **_head(file, manifest, "emulator"),
        "model": {k: model.get(k) for k in ("m", "p", "q", "l_sim", "p_u")},
        "known_inputs": _inputs(manifest, "x"),
        "parameters": _inputs(manifest, "t"),
        "outputs": {"names": manifest["names"]["y"], "units": manifest["units"]["y"]},
        "mean_basis": model.get("mean_basis"),
        "fixed": manifest["settings"].get("fixed") or {},
        "priors": _priors(manifest["priors"]),
        "settings": manifest["settings"],
        "metadata": manifest["metadata"],
        "convergence": convergence or None,
        "converged": _converged(convergence),
        "arrays": manifest["arrays"],
        **facts,
    }


def _infinite(value: object) -> bool:
    """Whether ``value`` is an infinite number (an R-hat of chains stuck apart), which the
    record writes as null, as it writes NaN (an R-hat not computable)."""
    return isinstance(value, float) and math.isinf(value)


def study_info(file: str, manifest: dict, study) -> dict:
    """A study file's record: ``manifest`` verified, ``study`` loaded from it
    (``gpmsa.load_study``: its posterior summary and convergence computed from the draws)."""
    st = manifest["study"]
    models = []
    for i, (mod, emu) in enumerate(zip(st["models"], study.members, strict=True)):
        params = [{"name": n, "unit": u, "range": list(emu.domain[n])}
                  for n, u in zip(emu.t_names, emu.t_units, strict=True)]  # fmt: skip
        models.append({"label": mod["label"], "file": mod["file"], "sha256": mod["sha256"],
                       "m": emu.m, "p": emu.p, "l_sim": emu.l_sim, "parameters": params,
                       "output_index": index_record(emu),
                       "discrepancy": study.discrepancy(i)})  # fmt: skip
    hyper = manifest["priors"].get("hyper") if st["hierarchical"] else None
    return {
        **_head(file, manifest, "study"),
        "study": {k: st[k] for k in ("kind", "shared", "hierarchical")},
        "models": models,
        "hyperpriors": hyper,
        "settings": manifest["settings"],
        "metadata": manifest["metadata"],
        "posterior": {
            name: {**row, "rhat_inf": _infinite(row.get("rhat"))}
            for name, row in study.summary(0.9).items()
        },
        "convergence": study.convergence or None,
        "converged": _converged(study.convergence),
    }
