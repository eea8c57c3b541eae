"""``gpmsa info FILE [--json]``: print an emulator file's manifest for a person (verified)."""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from gpmsa.cli.index_text import index_record, index_text
from gpmsa.cli.text import (
    internal_error,
    level_moves_text,
    number,
    numbers,
    plain,
    safe,
    tempering_text,
    value,
)
from gpmsa.errors import GPMSAError
from gpmsa.fitting.validation import DISCREPANCY_ARRAY
from gpmsa.mcmc.diagnostics import beyond, element_names, says_infinite_rhat
from gpmsa.model.basis import variance_shares


def add_parser(sub) -> None:
    """Add the ``info`` subcommand to an argparse subparsers object."""
    p = sub.add_parser("info", help="print an emulator or study file's manifest (verifies it "
                       "first)")  # fmt: skip
    p.add_argument("file", help="path to a .gpmsa file (an emulator or a study)")
    p.add_argument("--json", action="store_true", help="print the same facts as one JSON object "
                   "(keys: docs/emulator-file.md; the raw manifest under 'manifest')")  # fmt: skip
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand; exit status 0, or 2 with a message on stderr for a bad file or path
    (1 for an unexpected error, named in one line).

    The file is verified as ``gpmsa.load`` verifies it (hash and every field of the content)
    before anything is printed; every string from it is printed escaped (``gpmsa.cli.text``).
    A study file (``gpmsa.load_study``) is verified with every model file it lists.
    """
    from gpmsa.cli.info_json import dumps, emulator_info, study_info
    from gpmsa.cli.study_info import study_lines
    from gpmsa.fitting.emulator import Emulator
    from gpmsa.fitting.validation import check_manifest
    from gpmsa.io.container import FORMAT, STUDY_FORMAT, read_raw
    from gpmsa.studies.record import check_study_manifest
    from gpmsa.studies.study import load_study

    def check(manifest: dict) -> None:
        is_study = manifest["format"] == STUDY_FORMAT
        (check_study_manifest if is_study else check_manifest)(manifest)

    try:
        manifest, arrays = read_raw(args.file, check, formats=(FORMAT, STUDY_FORMAT))
        if manifest["format"] == STUDY_FORMAT:
            study = load_study(args.file)
        else:
            emulator = Emulator.from_record(manifest, arrays)
        if args.json and manifest["format"] == STUDY_FORMAT:
            text = dumps(study_info(args.file, manifest, study))
        elif args.json:
            text = dumps(emulator_info(args.file, manifest, _facts(manifest, arrays, emulator)))
        elif manifest["format"] == STUDY_FORMAT:
            lines = study_lines(args.file, manifest, study)
            lines.append(_convergence_line(study.convergence))  # from the draws, as load_study
            text = "\n".join(lines)
        else:
            text = "\n".join(_lines(args.file, manifest, arrays, emulator))
    except GPMSAError as exc:  # a damaged file (EmulatorFileError), or no file path at all
        print(f"gpmsa info: {safe(exc)}", file=sys.stderr)
        return 2
    except Exception as exc:  # a gap in the checks a hostile file found: one line, no traceback
        print(f"gpmsa info: {safe(args.file)}: {internal_error(exc)}", file=sys.stderr)
        return 1
    print(text)
    return 0


def _bases_text(manifest: dict) -> str:
    """The per-experiment discrepancy bases a file keeps (settings.discrepancy "list"), in
    words; "" for none."""
    spec = manifest["arrays"].get(DISCREPANCY_ARRAY)
    if spec is None:
        return ""
    n_exp, p_v = len(manifest["settings"]["obs_lengths"]), spec["shape"][1]
    return f" (one basis per experiment: {n_exp} experiments x {p_v} vectors, in the file)"


def _variance_share(emulator) -> float | None:
    """The share of the standardised runs' variance that the emulator basis holds; None for
    runs without variance."""
    total = float(np.sum(emulator.standardizer.y_to_std(emulator.y) ** 2))
    if total <= 0:
        return None
    return float(np.sum(variance_shares(emulator.w, emulator.lam_sim, total)))


def _basis_line(settings: dict, emulator) -> str:
    """Where the emulator basis came from, its size and the share of the standardised runs'
    variance it holds."""
    given = settings.get("basis") == "given"
    held = _variance_share(emulator)
    share = f", {held:.2%} of the runs' variance" if held is not None else ""
    source = "given (fit(..., basis=))" if given else "PCA of the runs"
    return f"{source}, {emulator.K.shape[1]} vector(s){share}"


def _separable_text(emulator) -> str:
    """A separable design's factors (``Emulator.separable``, validated), in words."""
    sep, names = emulator.separable, emulator.x_names + emulator.t_names
    factors = " x ".join(
        f"[{', '.join(safe(names[k], 60) for k in g)}] ({n} points)"
        for g, n in zip(sep.groups, sep.sizes, strict=True)
    )
    return f"{factors}, the first varying slowest (SimData(separable=); arrays/kron_factor)"


def _facts(manifest: dict, arrays: dict, emulator) -> dict:
    """What ``_lines`` derives from the file beyond its manifest's fields, for ``--json``
    (``gpmsa.cli.info_json.emulator_info``): the model's sha256, separable factors, output
    scale, output index, basis, the posterior's diagnostics (held positions and those of an
    infinite R-hat marked, theta's means native) and the number of array values."""
    std, sep = emulator.standardizer, emulator.separable
    names = emulator.x_names + emulator.t_names
    separable = None
    if sep is not None:
        separable = {"groups": [[names[k] for k in g] for g in sep.groups],
                     "sizes": list(sep.sizes)}  # fmt: skip
    y_sd = [float(np.min(std.y_sd)), float(np.max(std.y_sd))] if "y_sd" in std.y_given else None
    scale = {"y_mean_given": "y_mean" in std.y_given, "y_sd_given": "y_sd" in std.y_given,
             "columnwise": bool(std.columnwise), "y_sd_range": y_sd}  # fmt: skip
    given = manifest["settings"].get("basis") == "given"
    basis = {"source": "given" if given else "pca", "vectors": int(emulator.K.shape[1]),
             "variance_share": _variance_share(emulator)}  # fmt: skip
    fixed = manifest["settings"].get("fixed")
    fixed = fixed if isinstance(fixed, dict) else {}
    shapes = _shapes(emulator)
    posterior = {}
    for name, d in manifest["diagnostics"].items():
        if not (isinstance(d, dict) and isinstance(d.get("mean"), list)):
            posterior[name] = d  # a record gpmsa does not write: as it is
            continue
        held = _held_positions(fixed.get(name), shapes.get(name), len(d["mean"]))
        apart = _infinite_rhat(manifest.get("convergence"), name, shapes.get(name), len(d["mean"]))
        posterior[name] = {"mean": d["mean"], "ess": d.get("ess"), "rhat": d.get("rhat"),
                           "held": sorted(held), "rhat_inf": sorted(apart - held)}  # fmt: skip
        native = _native_means(manifest, d["mean"], std) if name == "theta" else None
        if native is not None:
            posterior[name]["mean_native"] = dict(zip(emulator.t_names, native, strict=True))
    return {"model_sha256": emulator.model_sha256, "separable": separable, "output_scale": scale,
            "output_index": index_record(emulator), "basis": basis, "posterior": posterior,
            "array_values": sum(int(a.size) for a in arrays.values())}  # fmt: skip


def _shapes(emulator) -> dict[str, tuple[int, ...]]:
    """The element shapes of the 2-D parameters (betaU, a joint fit's betaV)."""
    shapes = {"betaU": (emulator.p + emulator.q, emulator.p_u)}
    if emulator.calibration and "betaV" in emulator.calibration:
        shapes["betaV"] = emulator.calibration["betaV"].shape[1:]
    return shapes


def _given_scale(std) -> str:
    """The output standardisation of a Standardizer with a given y_mean or y_sd, in words."""
    each = std.columnwise  # an sd per output element (given, or y_scale="columnwise")
    mean = "centred by the given y_mean" if "y_mean" in std.y_given else "centred by the runs' mean"
    if "y_sd" in std.y_given:
        low, high = numbers(float(np.min(std.y_sd)), float(np.max(std.y_sd)))
        values = low + (f" to {high}" if each else "")
        kind = "one per output element" if each else "one sd"
        sd = f"divided by the given y_sd ({kind}: {values})"
    else:
        sd = "divided by the runs' sd" + (" (each output element by its own)" if each else "")
    return f"{mean}, {sd}"


def _lines(file: str, manifest: dict, arrays: dict, emulator) -> list[str]:
    """The manifest for a person (the content already validated: names, units, domain, model);
    ``emulator``: the loaded one, for theta in native units and its ``model_sha256`` (what a
    calibration's Posterior records as info "emulator_sha256")."""
    standardizer = emulator.standardizer
    model = manifest.get("model", {})
    lines = [
        f"file:            {safe(file)}",
        f"format:          {manifest['format']} schema {manifest['schema_version']} "
        f"(gpmsa {plain(manifest.get('library_version'))}, written "
        f"{plain(manifest.get('created_utc'))})",
        f"content sha256:  {safe(manifest['content_sha256'])} (verified)",
        f"model sha256:    {emulator.model_sha256} (a calibration's info 'emulator_sha256')",
        f"model:           m={model.get('m')} runs, p={model.get('p')}, q={model.get('q')}, "
        f"l_sim={model.get('l_sim')}, p_u={model.get('p_u')}",
    ]
    units = manifest["units"]
    for kind, label in (("x", "known inputs"), ("t", "parameters"), ("y", "outputs")):
        names = manifest["names"][kind]
        if kind == "y" and len(names) > 8:
            lines.append(f"{label + ':':17s}{len(names)} ({safe(names[0], 60)} .. "
                         f"{safe(names[-1], 60)})")  # fmt: skip
            continue
        parts = []
        for n, u in zip(names, units[kind], strict=True):
            dom = manifest["domain"].get(n) if kind != "y" else None
            rng = " in [{}, {}]".format(*numbers(*dom)) if dom else ""
            if dom and n in (model.get("input_ranges") or ()):
                rng += " (range given, design inside)"
            parts.append(f"{safe(n, 60)}{' [' + safe(u, 60) + ']' if u else ''}{rng}")
        lines.append(f"{label + ':':17s}{', '.join(parts) or 'none'}")
    index = index_text(emulator)
    if index is not None:
        lines.append(f"output index:    {index}")
    if emulator.separable is not None:  # SimData(separable=): file array kron_factor
        lines.append(f"separable:       {_separable_text(emulator)}")
    cat = model.get("categorical") or {}
    if cat:
        lines.append("categorical:     " + ", ".join(
            f"{safe(n, 60)} levels [{safe(', '.join(str(v) for v in lv), 300)}]"
            for n, lv in cat.items()))  # fmt: skip
    if standardizer.y_given:  # SimData(y_mean=, y_sd=): the user's, not the runs' own
        lines.append(f"output scale:    {_given_scale(standardizer)}")
    elif standardizer.columnwise:  # one sd over all outputs (GPM/SA's) is not said
        lines.append("output scale:    columnwise (each output element by its own sd)")
    lines.append(f"basis:           {_basis_line(manifest['settings'], emulator)}")
    mean = model.get("mean_basis")
    lines.append(f"mean basis:      {'zero (GPM/SA)' if mean is None else safe(mean, 60)}")
    fixed = manifest["settings"].get("fixed")
    if isinstance(fixed, dict) and fixed:
        cells = [_fixed_cell(manifest, k, v, standardizer) for k, v in fixed.items()]
        some = any(_held_elements(v) for v in fixed.values())
        lines.append("fixed:           " + ", ".join(cells)
                     + (" (single elements: the others sampled)" if some else ""))  # fmt: skip
    lines.extend(_prior_lines(manifest["priors"], manifest["names"]["t"]))
    s = manifest["settings"]
    flat = [f"{safe(k, 60)}={plain(v)}" for k, v in s.items() if not isinstance(v, (list, dict))]
    lines.append("settings:        " + ", ".join(flat))
    if "temperatures" in s:  # parallel tempering (fit(..., temperatures=)): lists, not above
        lines.append(f"tempering:       {tempering_text(s)}")
    if "level_offsets" in s:  # a categorical theta's joint level move: a dict, not above
        lines.append(f"level moves:     {level_moves_text(s['level_offsets'])}")
    if s.get("discrepancy") is not None:
        groups = s.get("discrepancy_groups")
        lines.append(f"discrepancy:     {plain(s['discrepancy'])}{_bases_text(manifest)}, "
                     "precision groups "
                     f"{plain(groups) if isinstance(groups, list) else 'one'}")  # fmt: skip
    options = s.get("backend_options")
    if isinstance(options, dict) and options:
        lines.append("backend options: " + ", ".join(
            f"{safe(k, 60)}={plain(v)}" for k, v in options.items()))  # fmt: skip
    for source in ("settings", "metadata"):
        versions = manifest[source].get("versions")
        if isinstance(versions, dict):
            lines.append(
                f"versions ({source}): "
                + ", ".join(f"{safe(k, 40)} {plain(v)}" for k, v in versions.items())
            )
    for k, v in manifest["metadata"].items():
        if k != "versions" or not isinstance(v, dict):
            lines.append(f"metadata {safe(k, 60)}: {value(v)}")
    shapes = _shapes(emulator)
    fixed = fixed if isinstance(fixed, dict) else {}
    for name, d in manifest["diagnostics"].items():
        if isinstance(d, dict) and isinstance(d.get("mean"), list):
            held = _held_positions(fixed.get(name), shapes.get(name), len(d["mean"]))
            apart = _infinite_rhat(manifest.get("convergence"), name, shapes.get(name),
                                   len(d["mean"]))  # fmt: skip
            cells = {}
            for key, fmt in (("mean", ".4g"), ("ess", ".0f"), ("rhat", ".3f")):
                vals = d.get(key, [])
                cells[key] = (
                    _cells(vals, fmt, held if key != "mean" else set(),
                           apart if key == "rhat" else set())
                    if isinstance(vals, list) else value(vals)
                )  # fmt: skip
            label = safe(name, 60)
            if name in shapes and min(shapes[name]) > 1:  # summarize flattens in C order
                label += " ({} x {}, row by row)".format(*shapes[name])
            if name == "theta":  # stored on the unit scale; printed native, as calibrate does
                native = _native_theta(manifest, d["mean"], standardizer)
                label, cells["mean"] = native or ("theta (unit scale)", cells["mean"])
            if held and len(held) == len(d["mean"]):  # fixed= whole: no ESS or R-hat to give
                lines.append(f"posterior {label}: held at [{safe(cells['mean'], 300)}] (fixed=)")
                continue
            lines.append(
                f"posterior {label}: mean [{safe(cells['mean'], 300)}] ESS "
                f"[{safe(cells['ess'], 300)}] R-hat [{safe(cells['rhat'], 300)}]"
            )
        else:
            lines.append(f"diagnostics {safe(name, 60)}: {value(d)}")
    lines.append(_convergence_line(manifest.get("convergence"), s.get("source")))
    n_arr = sum(int(a.size) for a in arrays.values())
    lines.append(f"arrays:          {len(arrays)} ({n_arr} values)")
    return lines


def _gamma(g: dict) -> str:
    """A validated Gamma prior of the manifest as text: Gamma(a, b) on (lower, upper)."""
    upper = math.inf if g["upper"] == "inf" else g["upper"]
    a, b, lower, high = numbers(g["a"], g["b"], g["lower"], upper)
    text = f"Gamma({a}, {b})"
    if g["lower"] != 0 or g["upper"] != "inf":
        text += f" on ({lower}, {high})"
    return text


def _beta_v(priors: dict) -> str:
    """betaV's prior of validated priors: its own Beta(rhoV_a, rhoV_b) on rho = exp(-betaV / 4)
    (one per group where so set), or "betaV as betaU"."""
    a, b = priors.get("rhoV_a"), priors.get("rhoV_b")
    if a is None:
        return "betaV as betaU"
    pairs = zip(a, b, strict=True) if isinstance(a, list) else [(a, b)]
    cells = ["Beta({}, {})".format(*numbers(x, y)) for x, y in pairs]
    text = f"[{', '.join(cells)}] (one per group)" if isinstance(a, list) else cells[0]
    return f"rho = exp(-betaV / 4) {text}"


def _theta_prior(priors: dict, t_names: list[str]) -> str:
    """theta's prior of validated priors: one Normal(mean, sd) on (0, 1) shared by every
    calibration parameter, or NAME Normal(mean, sd) for each (per-element priors)."""
    m, s = priors["theta_mean"], priors["theta_sd"]
    if not isinstance(m, list) and not isinstance(s, list):
        return "theta Normal({}, {}) on (0, 1) (unit scale)".format(*numbers(m, s))
    ms, ss = (v if isinstance(v, list) else [v] * len(t_names) for v in (m, s))
    cells = [f"{safe(n, 60)} Normal({', '.join(numbers(a, b))})"
             for n, a, b in zip(t_names, ms, ss, strict=True)]  # fmt: skip
    return f"theta [{', '.join(cells)}] on (0, 1) (unit scale, one per parameter)"


def _prior_lines(priors: dict, t_names: list[str]) -> list[str]:
    """The priors (validated): those a calibration with this file uses (theta, one per
    calibration parameter ``t_names`` where so set, lamOs, lamVz, one per precision group where
    so set; ``Emulator.with_calibration_priors`` changes them), then the emulator's own
    (data-corrected)."""
    vz = priors["lamVz"]
    lam_vz = ("[" + ", ".join(_gamma(g) for g in vz) + "] (one per group)"
              if isinstance(vz, list) else _gamma(vz))  # fmt: skip
    return [
        f"calibration priors: {_theta_prior(priors, t_names)}, lamOs "
        f"{_gamma(priors['lamOs'])}, lamVz {lam_vz}, {_beta_v(priors)}",
        "emulator priors: rho = exp(-betaU / 4) Beta({}, {}), ".format(
            *numbers(priors["rho_a"], priors["rho_b"])
        )
        + f"lamUz {_gamma(priors['lamUz'])}, lamWs "
        f"{_gamma(priors['lamWs'])}, lamWOs {_gamma(priors['lamWOs'])}"
        + (" (with GPM/SA's data corrections)" if priors["corrected"] is True else ""),
    ]


def _native_theta(manifest: dict, means: object, standardizer) -> tuple[str, str] | None:
    """The label and the unit-scale theta ``means`` (a fixed theta, the diagnostics' means) as
    NAME=VALUE in native units (``standardizer.t_from_unit``); None for means that are not one
    number per parameter."""
    native = _native_means(manifest, means, standardizer)
    if native is None:
        return None
    names = manifest["names"]["t"]
    cells = [f"{safe(n, 60)}={_in_domain(standardizer, k, v)}" for k, (n, v) in
             enumerate(zip(names, native, strict=True))]  # fmt: skip
    return "theta (native)", ", ".join(cells)


def _native_means(manifest: dict, means: object, standardizer) -> list[float] | None:
    """Unit-scale theta ``means`` in native units; None for means that are not one number per
    parameter."""
    names = manifest["names"]["t"]
    if not isinstance(means, list) or len(means) != len(names):
        return None
    if not all(isinstance(u, (int, float)) and not isinstance(u, bool) for u in means):
        return None
    try:
        unit = np.array([means], dtype=float)
    except OverflowError:  # an integer beyond float64 (10**400 in a file's diagnostics)
        return None
    return [float(v) for v in standardizer.t_from_unit(unit)[0]]


def _in_domain(standardizer, k: int, v: float) -> str:
    """Calibration parameter ``k``'s native value ``v`` with 4 significant digits, or as many
    more as tell it from its domain's ends (``numbers``: 1e6 + 0.5 in [1e6 + 0.003, 1e6 +
    0.935] is not "1e+06")."""
    ends = (float(standardizer.t_min[k]), float(standardizer.t_max[k]))
    return numbers(float(v), *ends, digits=4)[0]


def _cells(vals: list, fmt: str, held: set[int], infinite: set[int]) -> str:
    """A diagnostic's values, one cell per element in its place: "held" at ``held``'s
    positions, "inf" for a value stored as null at ``infinite``'s (an R-hat of chains stuck
    apart, `_infinite_rhat`), "nan" for another value stored as null (not computable) among
    others (a free element beside a held one too: a categorical theta element whose draws all
    sit at one level has no ESS); none where every value is null and none held or infinite (a
    diagnostic one chain cannot give)."""
    if not (held or infinite) and all(v is None for v in vals):
        return ""
    return ", ".join("held" if k in held else number(v, fmt) if v is not None
                     else "inf" if k in infinite else "nan"
                     for k, v in enumerate(vals))  # fmt: skip


def _infinite_rhat(record: object, name: str, shape, size: int) -> set[int]:
    """The positions (C order) of the ``size`` elements of parameter ``name`` whose R-hat is
    infinite (each chain constant, the chains apart): those the convergence ``record`` flags
    so (``INFINITE_RHAT``). The diagnostics store such an R-hat as null, as they store one
    that cannot be computed (every draw one value). ``shape``: a 2-D parameter's; None: 1-D."""
    flagged = record.get("flagged") if isinstance(record, dict) else None
    if not isinstance(flagged, dict):
        return set()
    two_d = shape is not None and len(shape) == 2 and shape[0] * shape[1] == size
    names = element_names(name, tuple(shape) if two_d else (size,))
    reasons = [flagged.get(el) for el in names]
    return {k for k, why in enumerate(reasons) if says_infinite_rhat(why)}


def _held_positions(record: object, shape, size: int) -> set[int]:
    """The positions (C order, as the diagnostics list them) of the ``size`` elements that a
    ``settings["fixed"]`` entry holds: all for a parameter held whole, its elements' for held
    elements (``shape``: a 2-D parameter's; None: 1-D); none for no entry, or one unread."""
    if isinstance(record, list):
        return set(range(size))
    held = _held_elements(record)
    if held is None:
        return set()
    cols = shape[1] if shape is not None and len(shape) == 2 else 1
    flat = {i[0] * cols + (i[1] if len(i) == 2 else 0) for i, _ in held if i}
    return {k for k in flat if 0 <= k < size}


def _held_elements(record: object) -> list[tuple[list[int], float]] | None:
    """A ``settings["fixed"]`` entry of held elements ({"elements": [index, ...], "values":
    [...]}) as (index, value) pairs; None for any other entry (a whole parameter's values)."""
    if not (isinstance(record, dict) and set(record) == {"elements", "values"}):
        return None
    els, vals = record["elements"], record["values"]
    if not (isinstance(els, list) and isinstance(vals, list) and len(els) == len(vals) and els):
        return None
    ints = all(isinstance(i, list) and i and all(isinstance(k, int) and not isinstance(k, bool)
               and k >= 0 for k in i) for i in els)  # fmt: skip
    nums = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals)
    return list(zip(els, vals, strict=True)) if ints and nums else None


def _fixed_cell(manifest: dict, name: str, record: object, standardizer) -> str:
    """One entry of ``settings["fixed"]`` as printed: NAME=VALUES for a whole parameter, or
    NAME[i]=VALUE per held element; theta (stored on the unit scale) native, by name."""
    held = _held_elements(record)
    if name == "theta" and held is not None:
        names = manifest["names"]["t"]
        if all(len(i) == 1 and i[0] < len(names) for i, _ in held):
            unit = np.full((1, len(names)), 0.5)
            for (k,), u in held:
                unit[0, k] = u
            native = standardizer.t_from_unit(unit)[0]
            cells = [f"{safe(names[k], 60)}={_in_domain(standardizer, k, native[k])}"
                     for (k,), _ in held]  # fmt: skip
            return f"theta (native)=[{', '.join(cells)}]"
    if held is not None:
        return ", ".join(f"{safe(name, 60)}[{','.join(map(str, i))}]={plain(v)}" for i, v in held)
    native = _native_theta(manifest, record, standardizer) if name == "theta" else None
    return f"theta (native)=[{native[1]}]" if native else f"{safe(name, 60)}={plain(record)}"


def _element(name: object) -> str:
    """The element a worst value belongs to, as " (NAME)"; "" for none."""
    return f" ({safe(name, 60)})" if name else ""


def _figure(val: object, limit: object, places: int, none: str, above: bool) -> str:
    """A worst R-hat (``above``: failing above its limit) or ESS (below) of a record with
    ``places`` decimals, or with as many more as show it beyond its ``limit`` where it fails
    (an R-hat of 1.0102 against 1.01: not "1.010")."""
    if val is None:
        return none
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in (val, limit)):
        try:
            v, lim = float(val), float(limit)
        except OverflowError:  # an integer beyond float64 from a file's JSON
            return number(val, f".{places}f")
        if math.isfinite(v) and math.isfinite(lim) and (v > lim if above else v < lim):
            return beyond(v, lim, places)
    return number(val, f".{places}f")


def _convergence_line(rec: object, source: object = None) -> str:
    """One line on the chains' convergence (older files, and those of one chain from before
    one chain was judged, have no record, nor ``from_params``'s (``source``: the settings'),
    which sampled nothing; one chain's R-hat is its split R-hat)."""
    if not rec:
        if source == "from_params":
            return "convergence:     not checked (from_params: no chains were run)"
        return "convergence:     not checked (a file from before the check)"
    if not isinstance(rec, dict):
        return f"convergence:     {value(rec)}"
    try:
        (r_el, r_val), (e_el, e_val) = rec["max_rhat"], rec["min_ess"]
    except (KeyError, TypeError, ValueError):
        return f"convergence:     {value(rec)}"
    if r_val is None and e_val is None and not (r_el or e_el):
        worst = "R-hat and ESS undefined (constant draws)"
    else:  # a value None with an element: not finite (an infinite R-hat: stuck chains)
        r_txt = _figure(r_val, rec.get("rhat_max"), 3, "inf" if r_el else "undefined", True)
        e_txt = _figure(e_val, rec.get("ess_min"), 0, "undefined", False)
        worst = (f"max R-hat {r_txt}{_element(r_el)}, min bulk ESS {e_txt}"
                 f"{_element(e_el)}")  # fmt: skip
    chains = f"{plain(rec.get('n_chains'))} chains"
    if type(rec.get("n_chains")) is int and rec["n_chains"] == 1:  # split R-hat: its halves
        chains, worst = "1 chain", worst.replace("max R-hat", "max split R-hat")
    head = f"convergence:     {chains} x {plain(rec.get('n_draws'))} draws; {worst}; "
    flagged = rec.get("flagged") or {}
    if not flagged:
        return head + (f"converged (R-hat <= {plain(rec.get('rhat_max'))}, ESS >= "
                       f"{number(rec.get('ess_min'), '.0f')})")  # fmt: skip
    if not isinstance(flagged, dict):
        return head + "NOT converged: " + value(flagged)
    return (
        head
        + "NOT converged: "
        + "; ".join(f"{safe(k, 60)}: {plain(v)}" for k, v in flagged.items())
    )
