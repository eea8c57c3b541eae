"""Checks of an emulator file's record (manifest + arrays) before an Emulator is built from it.

The content hash shows only that a file is as its writer left it: whoever can edit a file can
recompute the hash. So the reader checks every field itself: shapes (first from the manifest's
declarations, before anything is decompressed, then from the arrays), finiteness, ranges and
positive scales, the priors, names and settings the code relies on, and the redundancies a
consistent file has (the output mean and sd are those of the training outputs, the basis
weights are the outputs' projection on the basis, the design spans the unit cube, the point
estimate lies within its posterior draws). Each failure raises EmulatorFileError naming the
field ("arrays/K", "priors.lamOs.a", "names.x", ...). ``Emulator.save`` applies the same checks
before writing, so that it never writes a file ``gpmsa.load`` refuses.

A file that passes is an internally consistent, numerically valid emulator; it is not
necessarily the emulator its sender fitted (a consistent rewrite with a recomputed hash passes):
compare ``content_sha256`` with a value received over a trusted channel (``gpmsa.load(path,
sha256=...)``) for that.
"""

from __future__ import annotations

import math
import re

import numpy as np

from gpmsa.errors import EmulatorFileError, GPMSAError, numbers_text
from gpmsa.mcmc.sampler import none_as_nan
from gpmsa.model import kronecker
from gpmsa.model.basis import ORTHOGONAL_TOL, basis_digest
from gpmsa.model.data import as_float, column_scales, output_scale
from gpmsa.model.fixed_elements import label
from gpmsa.model.index_points import check_points
from gpmsa.model.mean_basis import KINDS as MEAN_BASIS_KINDS
from gpmsa.model.priors import MAX_PRIOR_SHAPE, theta_prior_overflow
from gpmsa.model.transforms import UNIT_TOL, Y_GIVEN

EMULATOR_PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")
STD_FIELDS = ("x_min", "x_max", "t_min", "t_max", "y_mean", "grid")
REQUIRED = ("x_unit", "t_unit", "y", "K", "w", "log_post", "y_sd", *STD_FIELDS) + tuple(
    f"param_{k}" for k in EMULATOR_PARAMS
)
"""Arrays every emulator file holds."""
CALIBRATION_ARRAYS = ("theta", "theta_native", "lamOs", "betaV", "lamVz")
PRECISIONS = ("lamVz", "lamUz", "lamWs", "lamWOs", "lamOs")
PRIOR_SCALARS = ("theta_mean", "theta_sd", "rho_a", "rho_b", "rho_cap")
PRIOR_OPTIONAL = ("rhoV_a", "rhoV_b")
"""betaV's own Beta prior: in a file both or neither (a file without them: betaU's)."""
SMALLEST_PRECISION = 1.0 / float(np.finfo(float).max)
"""1 / the largest float64: a precision lam at or below it (a subnormal one) has a variance
1 / lam that overflows, and is refused in a file and in ``Emulator`` params alike. (Divided as
Python floats: numpy's scalar division of this subnormal raised at import under a caller's
``np.seterr(under="raise")``.)"""
REL_TOL = 1e-9
"""Relative tolerance of the recomputed redundancies (y_mean, y_sd)."""
W_TOL = 1e-7
"""Tolerance of the recomputed basis weights, relative to their largest magnitude (plus 1)."""
DISCREPANCY_KINDS = ("constant", "linear", "given", "list")
"""A recorded discrepancy basis: named, "given" (an array the caller passed) or "list" (one
array per experiment, which an emulator file keeps: ``DISCREPANCY_ARRAY``)."""
DISCREPANCY_ARRAY = "discrepancy_D"
"""The array of a joint fit's per-experiment discrepancy bases (settings.discrepancy "list"):
the normalised bases stacked (sum of l_j, p_v), split by settings.obs_lengths."""
KRON_ARRAY = "kron_factor"
"""A separable design's declaration (``SimData(separable=)``): the factor (0, 1, ...; factor
0 varies slowest) of each input column of [x, t], (p + q,); written only for such a design."""
NORM_TOL = 1e-9
"""Tolerance of the stored per-experiment bases' normalisation (largest diag(D D^T) = 1)."""
BASIS_VECTORS = {"constant": 1, "linear": 2}
"""The number of vectors of each named discrepancy basis (``gpmsa.model.basis``)."""
EMULATOR_BASES = ("pca", "given")
"""settings.basis: the runs' PCA, or a basis the caller gave (``fit(..., basis=)``)."""
FIXABLE_CALIBRATION = ("theta", "lamOs", "betaV", "lamVz")
"""A joint fit's parameters that ``fit(..., fixed=)`` can hold (their draws: ``cal_<name>``)."""
MAX_SWEEPS = 2**63 - 1
"""Largest sweep count a file's settings may record (a C int64; a JSON integer has any size,
and a continuation weighs acceptance rates by these counts in floats)."""
APPENDED = ("appended_to", "appended_after", "pooled_sweeps", "sweeps_run")
"""The settings of an appended fit (``fit(..., append=True)``), all four or none."""
SHA256_RE = re.compile(r"[0-9a-f]{64}")


def _fail(field: str, problem: str) -> EmulatorFileError:
    return EmulatorFileError(f"{field}: {problem}")


def _short(value, n: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= n else text[: n - 3] + "..."


# --- shapes (from declarations or arrays) -------------------------------------------------------
def check_shapes(shapes: dict[str, tuple[int, ...]]) -> dict[str, int]:
    """Sizes (m, p, q, l_sim, p_u, n_draws; d, the output index's columns) of a record whose
    arrays have these shapes."""
    missing = [k for k in REQUIRED if k not in shapes]
    if missing:
        raise EmulatorFileError(f"arrays: required arrays missing: {missing}")

    def two(name: str) -> tuple[int, int]:
        s = shapes[name]
        if len(s) != 2:
            raise _fail(f"arrays/{name}", f"must be 2-D, has shape {list(s)}")
        return s

    m, p = two("x_unit")
    _, q = two("t_unit")
    l_sim, p_u = two("K")
    if q < 1:  # p = 0 (no known inputs) is a valid emulator; q = 0 is not
        raise _fail("arrays/t_unit", f"needs q >= 1 parameters, got {q}")
    if m < p + q + 2:
        raise _fail("arrays/x_unit", f"{m} runs: at least p + q + 2 = {p + q + 2} are needed")
    if l_sim < 1 or not 1 <= p_u <= min(m, l_sim):
        raise _fail("arrays/K", f"shape {[l_sim, p_u]}: need l_sim >= 1, 1 <= p_u <= min(m, l_sim)")
    n = shapes["log_post"][0] if len(shapes["log_post"]) == 1 else -1
    if n < 0:
        raise _fail("arrays/log_post", f"must be 1-D, has shape {list(shapes['log_post'])}")
    pshape = {"betaU": (p + q, p_u), "lamUz": (p_u,), "lamWs": (p_u,), "lamWOs": (1,)}
    want = {
        "t_unit": (m, q), "y": (m, l_sim), "w": (m, p_u), "x_min": (p,), "x_max": (p,),
        "t_min": (q,), "t_max": (q,), "y_mean": (l_sim,), "grid": (l_sim,),
        "y_sd": (l_sim,) if tuple(shapes["y_sd"]) == (l_sim,) else (1,),  # (l_sim,): columnwise
        **{f"param_{k}": v for k, v in pshape.items()},
    }  # fmt: skip
    grid = tuple(shapes["grid"])
    if len(grid) == 2 and grid[0] == l_sim and grid[1] >= 2:  # index points (l_sim, d)
        want["grid"] = grid
    if "index" in shapes:
        want["index"] = want["grid"]
    for name in shapes:
        if n == 0 and name.startswith(("draw_", "cal_")):  # would average nothing into NaN
            raise _fail(f"arrays/{name}", "needs >= 1 draw (log_post has none)")
        if name.startswith("draw_"):
            key = name[5:]
            if key not in pshape:
                raise _fail(
                    f"arrays/{name}", f"unknown emulator parameter (have {EMULATOR_PARAMS})"
                )
            want[name] = (n, *pshape[key])
        elif name.startswith("cal_"):
            if name[4:] not in CALIBRATION_ARRAYS:
                raise _fail(f"arrays/{name}", f"unknown calibration array ({CALIBRATION_ARRAYS})")
            if not shapes[name] or shapes[name][0] != n:
                raise _fail(f"arrays/{name}", f"shape {list(shapes[name])}: needs {n} draws first")
            if name[4:] in ("theta", "theta_native"):
                want[name] = (n, q)
            elif name[4:] == "lamOs":
                want[name] = (n, 1)
        elif name.startswith("param_"):
            if name[6:] not in pshape:
                raise _fail(
                    f"arrays/{name}", f"unknown emulator parameter (have {EMULATOR_PARAMS})"
                )
        elif name == DISCREPANCY_ARRAY:
            if len(shapes[name]) != 2 or min(shapes[name]) < 1:
                raise _fail(f"arrays/{name}", f"shape {list(shapes[name])}: must be (sum of the "
                                              "experiments' lengths, p_v), p_v >= 1")  # fmt: skip
        elif name == KRON_ARRAY:
            want[name] = (p + q,)
        elif name not in REQUIRED and name != "index":
            raise _fail(  # a save would drop it: not a file this library wrote
                f"arrays/{name}",
                "unknown array (an emulator file holds only the arrays of docs/emulator-file.md)",
            )
    _check_complete(shapes, n)
    if "cal_lamVz" in shapes:  # a discrepancy's draws: lamVz (n, G), betaV (n, p, G)
        lam = tuple(shapes["cal_lamVz"])
        if len(lam) != 2 or lam[1] < 1:
            raise _fail("arrays/cal_lamVz", f"shape {list(lam)}: must be (n_draws, G), G >= 1 "
                                            "discrepancy precision groups")  # fmt: skip
        want["cal_betaV"] = (n, p, lam[1])
    for name, shape in want.items():
        if tuple(shapes[name]) != tuple(shape):
            raise _fail(f"arrays/{name}", f"has shape {list(shapes[name])}, expected {list(shape)}")
    d = want["grid"][1] if len(want["grid"]) == 2 else 1
    return {"m": m, "p": p, "q": q, "l_sim": l_sim, "p_u": p_u, "n_draws": n, "d": d}


def _check_complete(shapes: dict[str, tuple[int, ...]], n: int) -> None:
    """Draws come whole: with n >= 1 rows of log_post every emulator parameter's ``draw_``
    array; calibration draws (``cal_``) hold theta, theta_native and lamOs, betaV and lamVz
    together (a discrepancy) or neither (a fit writes them so; the readers of draws rely on it)."""
    missing = [f"draw_{k}" for k in EMULATOR_PARAMS if f"draw_{k}" not in shapes]
    if n and missing:
        raise _fail(
            "arrays/log_post",
            f"{n} draws, but the draws of {missing} are missing (a file holds the draws of "
            "every emulator parameter, or none)",
        )
    cal = {k[4:] for k in shapes if k.startswith("cal_")}
    if not cal:
        return
    need = {"theta", "theta_native", "lamOs"} | (
        {"betaV", "lamVz"} if cal & {"betaV", "lamVz"} else set()
    )
    if need - cal:
        missing = sorted(f"cal_{k}" for k in need - cal)
        raise _fail("arrays/cal_", f"calibration draws without {missing}")


# --- manifest fields ----------------------------------------------------------------------------
def _number(value, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(field, f"must be a number, got {_short(value)}")
    try:
        v = float(value)
    except OverflowError:  # a JSON integer beyond float64 (10**400)
        raise _fail(field, f"{_short(value)} is beyond float64") from None
    if math.isnan(v):
        raise _fail(field, "must be a number, got NaN")
    return v


def _strings(value, n: int, field: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(s, str) for s in value):
        raise _fail(field, f"must be a list of strings, got {_short(value)}")
    if len(value) != n:
        raise _fail(field, f"must have {n} entries (one per column), got {len(value)}")
    return value


def check_priors(priors, q: int | None = None) -> None:
    """The priors as ``Priors.to_dict`` writes them, with valid values; per-element theta
    priors (lists) one per each of the ``q`` calibration parameters (None: not checked)."""
    if not isinstance(priors, dict):
        raise _fail("priors", f"must be an object, got {_short(priors)}")
    expected = {*PRIOR_SCALARS, *PRECISIONS, "corrected"}
    if set(priors) - set(PRIOR_OPTIONAL) != expected or len(set(priors) & {*PRIOR_OPTIONAL}) == 1:
        raise _fail(
            "priors",
            f"fields {sorted(priors)} differ from the expected {sorted(expected)} "
            f"(and optionally both of {list(PRIOR_OPTIONAL)})",
        )
    if PRIOR_OPTIONAL[0] in priors:
        _check_rhov(priors)
    _check_theta_priors(priors, q)
    for name in ("rho_a", "rho_b", "rho_cap"):
        v = _number(priors[name], f"priors.{name}")
        ok = 0 < v < 1 if name == "rho_cap" else math.isfinite(v) and v > 0
        if not ok:
            allowed = "(0, 1)" if name == "rho_cap" else "(0, inf), finite"
            raise _fail(f"priors.{name}", f"{v!r} is out of range: allowed {allowed}")
    if not isinstance(priors["corrected"], bool):
        raise _fail("priors.corrected", f"must be true or false, got {_short(priors['corrected'])}")
    for name in PRECISIONS:
        g = priors[name]
        if name == "lamVz" and isinstance(g, list):  # one prior per discrepancy precision group
            if not g:
                raise _fail("priors.lamVz", "an empty list: per-group priors need one per group")
            for i, e in enumerate(g):
                _check_gamma(e, f"priors.lamVz[{i}]")
        else:
            _check_gamma(g, f"priors.{name}")


def _check_theta_priors(priors: dict, q: int | None) -> None:
    """theta_mean (finite), theta_sd (finite, > 0) as ``Priors.to_dict`` writes them: each a
    number, or a list of one number per calibration parameter (``q`` of them where given; two
    lists of equal length), every (mean, sd) pair with a float64 density."""
    values = {}
    for name, rule in (("theta_mean", "finite"), ("theta_sd", "(0, inf), finite")):
        v = priors[name]
        items = v if isinstance(v, list) else [v]
        if not items:
            raise _fail(f"priors.{name}", "an empty list: per-element priors need one per "
                                          "calibration parameter")  # fmt: skip
        if isinstance(v, list) and q is not None and len(v) != q:
            raise _fail(f"priors.{name}", f"{len(v)} per-element theta priors, but the model has "
                                          f"q = {q} calibration parameter(s)")  # fmt: skip
        out = []
        for i, e in enumerate(items):
            field = f"priors.{name}[{i}]" if isinstance(v, list) else f"priors.{name}"
            x = _number(e, field)
            if not (math.isfinite(x) and (name == "theta_mean" or x > 0)):
                raise _fail(field, f"{x!r} is out of range: allowed {rule}")
            out.append(x)
        values[name] = out
    means, sds = values["theta_mean"], values["theta_sd"]
    if len(means) > 1 and len(sds) > 1 and len(means) != len(sds):
        raise _fail("priors.theta_sd", f"{len(sds)} per-element values, but priors.theta_mean "
                                       f"has {len(means)}")  # fmt: skip
    n = max(len(means), len(sds))
    listed = isinstance(priors["theta_mean"], list) or isinstance(priors["theta_sd"], list)
    for k in range(n):
        bad = theta_prior_overflow(means[k % len(means)], sds[k % len(sds)])
        if bad is not None:
            raise _fail(f"priors.{bad[0]}" + (f"[{k}]" if listed else ""), bad[1])


def _check_rhov(priors: dict) -> None:
    """rhoV_a, rhoV_b as ``Priors.to_dict`` writes them: both numbers, or both non-empty lists
    of numbers of equal length, each finite and > 0."""
    a, b = priors["rhoV_a"], priors["rhoV_b"]
    for name, v in (("rhoV_a", a), ("rhoV_b", b)):
        items = v if isinstance(v, list) else [v]
        if not items:
            raise _fail(f"priors.{name}", "an empty list: per-group priors need one per group")
        for i, e in enumerate(items):
            field = f"priors.{name}[{i}]" if isinstance(v, list) else f"priors.{name}"
            x = _number(e, field)
            if not (math.isfinite(x) and x > 0):
                raise _fail(field, f"{x!r} is out of range: allowed (0, inf), finite")
    if isinstance(a, list) != isinstance(b, list) or (isinstance(a, list) and len(a) != len(b)):
        raise _fail(
            "priors.rhoV_b",
            f"{_short(b)} must match priors.rhoV_a {_short(a)}: both numbers, or both lists of "
            "one number per discrepancy precision group",
        )


def _check_gamma(g, field: str) -> None:
    """One Gamma prior as ``Priors.to_dict`` writes it, with valid values."""
    if not isinstance(g, dict) or set(g) != {"a", "b", "lower", "upper"}:
        raise _fail(field, f"must be an object {{a, b, lower, upper}}, got {_short(g)}")
    a, b = _number(g["a"], f"{field}.a"), _number(g["b"], f"{field}.b")
    if not 0 < a <= MAX_PRIOR_SHAPE:
        raise _fail(f"{field}.a", f"{a!r} is out of range: allowed (0, {MAX_PRIOR_SHAPE:g}]")
    if not (0 < b and math.isfinite(b)):
        raise _fail(f"{field}.b", f"{b!r} is out of range: allowed (0, inf), finite")
    lo = _number(g["lower"], f"{field}.lower")
    hi = math.inf if g["upper"] == "inf" else _number(g["upper"], f"{field}.upper")
    if not (math.isfinite(lo) and 0 <= lo < hi):
        raise _fail(f"{field}.lower", f"bounds ({lo!r}, {hi!r}): need 0 <= lower < upper")


def check_prior_groups(priors: dict, shapes: dict[str, tuple[int, ...]]) -> None:
    """Per-group lamVz and betaV priors (lists) give one prior per precision group of a joint
    fit's discrepancy draws (``cal_lamVz``, (n_draws, G))."""
    lam = shapes.get("cal_lamVz")
    if lam is None:
        return
    n_grp = lam[1]  # check_shapes: (n_draws, G)
    for name in ("lamVz", "rhoV_a"):
        groups = priors.get(name)
        if isinstance(groups, list) and len(groups) != n_grp:
            raise _fail(
                f"priors.{name}",
                f"{len(groups)} per-group priors, but arrays/cal_lamVz holds draws of {n_grp} "
                "discrepancy precision group(s)",
            )


def group_count(kind, groups, field: str) -> int:
    """The number of precision groups G of a recorded discrepancy: a ``kind`` basis
    (``DISCREPANCY_KINDS``) with ``groups`` ("discrepancy_groups": None for one group, else one
    integer 0 .. G-1 per basis vector, G >= 2, each used). EmulatorFileError naming ``field``
    for groups that number no such G, or that a basis of ``kind`` cannot have (one group per
    basis vector: "constant" has one, "linear" two)."""
    if groups is None:
        return 1
    ints = isinstance(groups, list) and all(
        isinstance(g, int) and not isinstance(g, bool) for g in groups
    )
    n_grp = len(set(groups)) if ints else 0
    if n_grp < 2 or min(groups) != 0 or max(groups) != n_grp - 1:  # 0 .. G-1, each used
        raise _fail(field, f"must number two or more groups 0 .. G-1, got {_short(groups)}")
    n_vec = BASIS_VECTORS.get(kind)
    if n_vec is not None and len(groups) != n_vec:
        raise _fail(field, f"{_short(groups)}: one group per basis vector, but a {kind!r} "
                           f"discrepancy has {n_vec}")  # fmt: skip
    return n_grp


def check_discrepancy_record(settings: dict, shapes: dict[str, tuple[int, ...]]) -> None:
    """A joint fit's record of its discrepancy (settings "discrepancy" and
    "discrepancy_groups", as ``gpmsa.fit`` writes them) against its calibration draws: a basis
    exactly where there are discrepancy draws, and the G groups of their ``cal_lamVz`` (n_draws,
    G). Files without calibration draws, or written before "discrepancy" was recorded, have
    nothing to compare."""
    _check_bases_shape(settings, shapes)
    if "cal_theta" not in shapes or "discrepancy" not in settings:
        return
    kind, lam = settings["discrepancy"], shapes.get("cal_lamVz")
    if kind is not None and kind not in DISCREPANCY_KINDS:
        raise _fail("settings.discrepancy", f"must be null or one of {DISCREPANCY_KINDS}, got "
                                            f"{_short(kind)}")  # fmt: skip
    if (kind is None) != (lam is None):
        held = "holds" if lam is not None else "holds none (arrays/cal_betaV, arrays/cal_lamVz)"
        raise _fail("settings.discrepancy", f"{_short(kind)}, but the file {held} of "
                                            "discrepancy draws")  # fmt: skip
    if lam is None:
        return
    groups = settings.get("discrepancy_groups")
    n_grp = group_count(kind, groups, "settings.discrepancy_groups")
    if n_grp != lam[1]:
        raise _fail("settings.discrepancy_groups", f"{_short(groups)} (None: one group) numbers "
                    f"{n_grp} group(s), but arrays/cal_lamVz holds draws of {lam[1]}")  # fmt: skip


def check_discrepancy_scale(settings: dict) -> None:
    """settings.discrepancy_scale (absent for the named kinds and in files written before it
    was recorded): the divisor that normalised a discrepancy basis given as an array or a list
    (settings.discrepancy "given" or "list"), a finite number > 0."""
    if "discrepancy_scale" not in settings:
        return
    scale, kind = settings["discrepancy_scale"], settings.get("discrepancy")
    if isinstance(scale, bool) or not isinstance(scale, int | float) or not 0 < scale < math.inf:
        raise _fail("settings.discrepancy_scale", f"must be a finite number > 0, got "
                                                  f"{_short(scale)}")  # fmt: skip
    if kind not in ("given", "list"):
        raise _fail("settings.discrepancy_scale", f"belongs to a discrepancy basis given as an "
                    f"array or a list (settings.discrepancy 'given' or 'list'), not "
                    f"{_short(kind)}")  # fmt: skip


def _check_bases_shape(settings: dict, shapes: dict[str, tuple[int, ...]]) -> None:
    """``DISCREPANCY_ARRAY`` exactly where settings.discrepancy is "list" (with calibration
    draws), one row per observed value (the sum of settings.obs_lengths) and, with several
    precision groups, one column per entry of settings.discrepancy_groups."""
    kind = settings.get("discrepancy")
    held = shapes.get(DISCREPANCY_ARRAY)
    field = f"arrays/{DISCREPANCY_ARRAY}"
    if held is None:
        if isinstance(kind, str) and kind == "list" and "cal_theta" in shapes:
            raise _fail("settings.discrepancy", f"'list', but the file holds no {field} (the "
                                                "per-experiment bases)")  # fmt: skip
        return
    if not (isinstance(kind, str) and kind == "list"):
        raise _fail(
            field,
            "the per-experiment discrepancy bases of a joint fit whose "
            f"settings.discrepancy is 'list', but it is {_short(kind)}",
        )
    if "cal_theta" not in shapes:
        raise _fail(
            field,
            "the per-experiment discrepancy bases of a joint fit, but the file "
            "holds no calibration draws (arrays/cal_theta)",
        )
    lengths = settings.get("obs_lengths")
    if not isinstance(lengths, list):  # check_fields: null or a list of integers >= 1
        raise _fail("settings.obs_lengths", f"must list the experiments' lengths beside {field}")
    if held[0] != sum(lengths):
        raise _fail(field, f"has {held[0]} rows, but settings.obs_lengths {_short(lengths)} "
                           f"has {sum(lengths)} observed values (one row each)")  # fmt: skip
    groups = settings.get("discrepancy_groups")
    if isinstance(groups, list) and len(groups) != held[1]:
        raise _fail("settings.discrepancy_groups", f"{_short(groups)}: one group per basis "
                    f"vector, but {field} has {held[1]} columns")  # fmt: skip


def kron_groups(arrays: dict[str, np.ndarray]) -> tuple[tuple[int, ...], ...] | None:
    """The factor column groups of ``KRON_ARRAY`` (None where the record has none); an
    EmulatorFileError unless it numbers at least two factors 0, 1, ... each holding an input
    (the design's product structure is checked when the emulator is built)."""
    held = arrays.get(KRON_ARRAY)
    if held is None:
        return None
    codes = np.asarray(held, dtype=float).reshape(-1)
    ok = (
        codes.size
        and np.all(np.isfinite(codes))
        and 0 <= np.min(codes) <= np.max(codes) < codes.size
    )
    k = int(np.max(codes)) + 1 if ok else 0  # a factor per input at most: np.arange(k) small
    if k < 2 or not np.array_equal(np.unique(codes), np.arange(k)):
        raise _fail(f"arrays/{KRON_ARRAY}", f"{_short(codes.tolist())}: must number the "
                    "factor of each input 0, 1, ..., at least two factors, each holding an "
                    "input")  # fmt: skip
    return tuple(tuple(int(c) for c in np.flatnonzero(codes == f)) for f in range(k))


def split_bases(arrays: dict[str, np.ndarray], settings: dict) -> tuple[np.ndarray, ...] | None:
    """The per-experiment bases of ``DISCREPANCY_ARRAY`` (None where the record has none),
    split by settings.obs_lengths (checked: ``_check_bases_shape``)."""
    stacked = arrays.get(DISCREPANCY_ARRAY)
    if stacked is None:
        return None
    cuts = np.cumsum(settings["obs_lengths"])[:-1]
    return tuple(np.split(stacked, cuts, axis=0))


def check_discrepancy_bases(settings: dict, arrays: dict[str, np.ndarray]) -> None:
    """The stored per-experiment discrepancy bases: finite, normalised jointly (largest
    diag(D_j D_j^T) over the experiments 1, within NORM_TOL, so not all zero; one experiment's
    may be: it has no discrepancy, as a zero ``obsData(k).Dobs`` in GPM/SA) and the bases (and
    groups) whose digest settings.discrepancy_sha256 records."""
    if DISCREPANCY_ARRAY not in arrays:
        return
    field = f"arrays/{DISCREPANCY_ARRAY}"
    stacked = _finite(arrays, DISCREPANCY_ARRAY)
    bases = split_bases(arrays, settings)
    with np.errstate(over="ignore"):
        top = float(np.max(np.sum(stacked**2, axis=1)))
    if not abs(top - 1.0) <= NORM_TOL:
        raise _fail(field, f"is not normalised: its largest diag(D D^T) is {top:.6g}, not 1")
    groups = settings.get("discrepancy_groups")
    digest = settings.get("discrepancy_sha256")
    if digest != basis_digest(bases, None if groups is None else tuple(groups)):
        raise _fail(field, f"split by settings.obs_lengths {_short(settings['obs_lengths'])}, "
                           "differs from the bases (and groups) whose digest "
                           "settings.discrepancy_sha256 records")  # fmt: skip


def check_fixed_record(settings: dict, shapes: dict[str, tuple[int, ...]]) -> dict:
    """settings.fixed as ``gpmsa.fit`` writes it (absent in files without it): parameter name ->
    the values it was held at whole (nested lists of its shape), or {"elements": [index, ...],
    "values": [...]} of held single elements, each index within its shape and named once; every
    value a finite number, of a parameter this file holds. Returns name -> (the element index
    tuples, None for the whole parameter; the values), for ``check_fixed_draws``."""
    fixed = settings.get("fixed")
    if fixed is None:
        return {}
    if not isinstance(fixed, dict):
        raise _fail("settings.fixed", f"must be an object name -> values, got {_short(fixed)}")
    params = {k: tuple(shapes[f"param_{k}"]) for k in EMULATOR_PARAMS}
    params.update({k: tuple(shapes[f"cal_{k}"][1:]) for k in FIXABLE_CALIBRATION
                   if f"cal_{k}" in shapes})  # fmt: skip
    out = {}
    for name, rec in fixed.items():
        field = f"settings.fixed[{_short(name, 40)}]"
        if name not in params:
            raise _fail(field, f"names no parameter of this file (it has {sorted(params)})")
        shape = params[name]
        if isinstance(rec, dict):
            out[name] = _held_elements(rec, shape, field)
            continue
        values = _finite_values(rec, field)
        if values.shape != shape and not values.size == 0 == math.prod(shape):
            raise _fail(field, f"{_short(rec)}: the values of {name} held whole need its shape "
                               f"{list(shape)}, got {list(values.shape)}")  # fmt: skip
        out[name] = (None, values)
    return out


def _held_elements(rec: dict, shape: tuple[int, ...], field: str) -> tuple[list, np.ndarray]:
    """A held-elements entry of settings.fixed ({"elements", "values"}) as (index tuples,
    values), each index an element of a parameter of ``shape``."""
    els, vals = rec.get("elements"), rec.get("values")
    if set(rec) != {"elements", "values"} or not (
        isinstance(els, list) and els and isinstance(vals, list) and len(vals) == len(els)
    ):
        raise _fail(field, f"held elements need {{elements: [index, ...], values: [...]}}, one "
                           f"value per element, got {_short(rec)}")  # fmt: skip
    seen = []
    for i, idx in enumerate(els):
        ok = isinstance(idx, list) and len(idx) == len(shape) and all(
            isinstance(k, int) and not isinstance(k, bool) and 0 <= k < n
            for k, n in zip(idx, shape, strict=True))  # fmt: skip
        if not ok or tuple(idx) in seen:
            why = "named twice" if ok else f"not an element of shape {list(shape)}"
            raise _fail(f"{field}.elements[{i}]", f"{_short(idx)} is {why}")
        seen.append(tuple(idx))
    values = _finite_values(vals, f"{field}.values")
    if values.ndim != 1:
        raise _fail(f"{field}.values", f"must be one number per element, got {_short(vals)}")
    return seen, values


def file_floats(value, field: str) -> np.ndarray:
    """``value``, a file's record of numbers in nested lists, as a float array;
    EmulatorFileError naming ``field`` as a damaged record for anything else (text, bools,
    null, objects, ragged lists, an integer beyond float64): ``as_float``'s message without
    its advice on a user's own data (a CSV table's text)."""
    try:
        return as_float(value, field, advice=False)
    except GPMSAError as exc:
        raise EmulatorFileError(f"{exc} (a damaged record: gpmsa writes numbers there)") from None


def _finite_values(value, field: str) -> np.ndarray:
    """``value`` (numbers in nested lists) as a float array; EmulatorFileError naming ``field``
    for anything else (text, bools, null, ragged lists) or a value that is not finite."""
    arr = file_floats(value, field)
    if not np.all(np.isfinite(arr)):
        raise _fail(field, f"must be finite numbers, got {_short(value)}")
    return arr


def check_fixed_draws(held: dict, arrays: dict[str, np.ndarray]) -> None:
    """The draws of each parameter settings.fixed holds (``check_fixed_record``'s ``held``) are
    its values: a fit records the held values exactly, and a record its draws contradict would
    tell ``gpmsa info`` and a continuation of another model."""
    for name, (elements, values) in held.items():
        draws = arrays.get(f"draw_{name}", arrays.get(f"cal_{name}"))
        if draws is None or not values.size:  # no draws (n = 0), no element: nothing to compare
            continue
        got = draws if elements is None else draws[(slice(None), *np.array(elements).T)]
        if np.all(got == values):
            continue
        if elements is None:
            what, at = name, _short(values.tolist())
        else:
            k = int(np.argmax(np.any(got != values, axis=0)))
            what, at = label(name, elements[k]), repr(float(values[k]))
        raise _fail(f"settings.fixed[{_short(name, 40)}]",
                    f"holds {what} at {at}, but its draws are not held there")  # fmt: skip


HOT_RECORD = ("hot_states", "hot_step_widths")
"""A numpy or torch tempered fit's settings holding each hot copy's last state (the model's
scale: theta on the unit scale) and its step widths, name -> (n_chains, K - 1, *shape), from
which its continuation (either backend's) resumes every copy
(``gpmsa.fitting.continuation.resumes_copies``); both or neither."""

MAX_HOT_VALUES = 50_000
"""Most numbers the hot copies' record may hold (both fields; ~25-50 bytes each in the JSON
manifest, whose limit is ``limits.MAX_MANIFEST_BYTES``): a larger tempered fit records none,
and its continuation warms its copies up as one without the record does."""


def hot_record_given(settings: dict, what: str) -> bool:
    """Whether a tempered ``what``'s (``"fit"``, ``"study"``) ``settings`` hold the hot copies'
    record (``HOT_RECORD``): both fields (True) or neither (False); EmulatorFileError naming
    the one missing where only one is."""
    given = [k for k in HOT_RECORD if settings.get(k) is not None]
    if given and len(given) < len(HOT_RECORD):
        lacking = next(k for k in HOT_RECORD if k not in given)
        raise _fail(f"settings.{lacking}", f"a tempered {what} records {list(HOT_RECORD)} "
                                           f"together; the file has only {given}")  # fmt: skip
    return bool(given)


def check_hot_record(settings: dict, shapes: dict[str, tuple[int, ...]]) -> None:
    """A numpy or torch tempered fit's hot copies (settings ``HOT_RECORD``, absent in other
    files, in those written before the record existed and in those above ``MAX_HOT_VALUES``),
    both or neither, each an object naming parameters with draws (``draw_``/``cal_`` arrays),
    its value (n_chains, K - 1, *shape), K the length of settings.temperatures (where that is a
    list of 2 or more; a continuation names a damaged ladder): hot_states finite numbers,
    hot_step_widths numbers > 0 and finite, or null (an element not sampled)."""
    if not hot_record_given(settings, "fit"):
        return
    temps = settings.get("temperatures")  # a damaged ladder: the continuation names it
    n_hot = len(temps) - 1 if isinstance(temps, list) and len(temps) >= 2 else None
    n_chains = settings.get("n_chains", 1)
    for key in HOT_RECORD:
        record = settings[key]
        if not isinstance(record, dict):
            raise _fail(f"settings.{key}", f"must be an object name -> values, got "
                                           f"{_short(record)}")  # fmt: skip
        for name, value in record.items():
            field = f"settings.{key}[{_short(name, 40)}]"
            shape = shapes.get(f"draw_{name}", shapes.get(f"cal_{name}"))
            if shape is None:
                raise _fail(field, "names no parameter with draws in the file")
            # null: a NaN written (a state's is not finite, a width's not sampled)
            arr = file_floats(none_as_nan(value), field)
            if key == "hot_states" and not np.all(np.isfinite(arr)):
                raise _fail(field, f"must be finite numbers, got {_short(value)}")
            bad = ~np.isnan(arr) & ~(np.isfinite(arr) & (arr > 0))
            if key == "hot_step_widths" and bad.any():
                raise _fail(field, f"must be numbers > 0 and finite, or null, got "
                                   f"{_short(arr[bad].tolist())}")  # fmt: skip
            hot = arr.shape[1] if n_hot is None and arr.ndim > 1 else n_hot
            want = (n_chains, hot, *shape[1:])
            if arr.shape != want and not (arr.size == 0 and 0 in want):  # JSON: no empty shape
                raise _fail(field, f"has shape {list(arr.shape)}, expected {list(want)} "
                                   "(chains, hot copies, *the parameter's shape)")  # fmt: skip


def check_fields(manifest: dict, dims: dict[str, int]) -> None:
    """Names, units, priors, the model sizes and the settings the code reads."""
    p, q, l_sim = dims["p"], dims["q"], dims["l_sim"]
    names, units = manifest.get("names"), manifest.get("units")
    for field, value in (("names", names), ("units", units)):
        if not isinstance(value, dict) or set(value) != {"x", "t", "y"}:
            raise _fail(field, f"must be an object with x, t and y lists, got {_short(value)}")
    for kind, n in (("x", p), ("t", q), ("y", l_sim)):
        _strings(names[kind], n, f"names.{kind}")
        _strings(units[kind], n, f"units.{kind}")
    inputs = names["x"] + names["t"]
    if len(set(inputs)) != len(inputs):
        raise _fail("names", f"input names must be unique, got {_short(inputs)}")
    if len(set(names["y"])) != len(names["y"]):
        raise _fail("names.y", "output names must be unique")
    check_priors(manifest.get("priors"), q)
    model = manifest.get("model")
    if not isinstance(model, dict):
        raise _fail("model", f"must be an object, got {_short(model)}")
    for key in ("m", "p", "q", "l_sim", "p_u"):
        if key in model and model[key] != dims[key]:
            raise _fail(f"model.{key}", f"{_short(model[key])}, but the arrays give {dims[key]}")
    settings = manifest.get("settings")
    if not isinstance(settings, dict):
        raise _fail("settings", f"must be an object, got {_short(settings)}")
    if "n_chains" in settings:
        n_ch = settings["n_chains"]
        if isinstance(n_ch, bool) or not isinstance(n_ch, int) or n_ch < 1:
            raise _fail("settings.n_chains", f"must be an integer >= 1, got {_short(n_ch)}")
        n_draws = dims.get("n_draws", 0)
        if n_draws and n_draws % n_ch:
            raise _fail(
                "settings.n_chains",
                f"{n_ch} chains cannot hold the {n_draws} draws (each chain keeps as many)",
            )
    basis = settings.get("basis", "pca")  # absent in files written before it: the PCA
    if not (isinstance(basis, str) and basis in EMULATOR_BASES):
        raise _fail("settings.basis", f"must be one of {EMULATOR_BASES}, got {_short(basis)}")
    lengths = settings.get("obs_lengths")  # full_prediction compares them with its obs
    if lengths is not None and not (
        isinstance(lengths, list)
        and lengths
        and all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in lengths)
    ):
        raise _fail(
            "settings.obs_lengths",
            f"must be null or a list of integers >= 1 (the joint fit's experiments), got "
            f"{_short(lengths)}",
        )
    for key in ("metadata", "diagnostics"):
        if not isinstance(manifest.get(key), dict):
            raise _fail(key, f"must be an object, got {_short(manifest.get(key))}")
    check_sweeps(settings, dims.get("n_draws", 0))
    check_accept(manifest["diagnostics"])
    if manifest.get("convergence") is not None and not isinstance(manifest["convergence"], dict):
        raise _fail("convergence", f"must be an object, got {_short(manifest['convergence'])}")
    _check_model_options(model, inputs)
    check_index_labels(model, l_sim, dims.get("d", 1))


def check_index_labels(model: dict, l_sim: int, d: int) -> None:
    """model.index_names and model.index_units (``SimData(index_names=, index_units=)``), each
    absent (files without them, every file before them) or a list of ``d`` strings, one per
    column of the output index, of a functional output (``l_sim`` > 1); names non-empty and
    unique."""
    for key in ("index_names", "index_units"):
        if key not in model:
            continue
        field = f"model.{key}"
        if l_sim == 1:
            raise _fail(field, "a scalar output (l_sim 1) has no output index to label")
        value = _strings(model[key], d, field)
        if key == "index_units":
            continue
        if not all(s.strip() for s in value):
            raise _fail(field, f"names must be non-empty, got {_short(value)}")
        if len(set(value)) != d:
            raise _fail(field, f"names must be unique, got {_short(value)}")


def _sweep_count(settings: dict, key: str, low: int) -> int | None:
    """settings[key], a sweep count: null (or absent) or an integer in [low, MAX_SWEEPS]."""
    v = settings.get(key)
    if v is not None and (isinstance(v, bool) or not isinstance(v, int)
                          or not low <= v <= MAX_SWEEPS):  # fmt: skip
        raise _fail(f"settings.{key}", f"must be null or an integer in [{low}, {MAX_SWEEPS}], "
                                       f"got {_short(v)}")  # fmt: skip
    return v


def check_sweeps(settings: dict, n_draws: int, unsaved: bool = False) -> None:
    """The sweep counts a continuation reads (``gpmsa.fitting.continuation``): n_iter and n_burn
    (0 <= n_burn < n_iter) and an appended fit's record (``APPENDED``, all or none):
    appended_to the source's digest (64 hex digits; with ``unsaved``, a study's, also null: a
    source never saved), appended_after the source's draws per chain (at least one, and
    fewer than each chain's ``n_draws / n_chains``), pooled_sweeps and sweeps_run (per chain;
    null or above n_iter, the continuation's own, and pooled_sweeps <= sweeps_run)."""
    n_iter, n_burn = _sweep_count(settings, "n_iter", 1), _sweep_count(settings, "n_burn", 0)
    if n_iter is not None and n_burn is not None and n_burn >= n_iter:
        raise _fail("settings.n_burn", f"{n_burn} must be below n_iter={n_iter}")
    given = [k for k in APPENDED if k in settings]
    if not given:
        return
    if len(given) < len(APPENDED):
        lacking = [k for k in APPENDED if k not in settings]
        raise _fail(f"settings.{lacking[0]}", f"an appended fit records {list(APPENDED)} "
                                              f"together; the file has only {given}")  # fmt: skip
    digest = settings["appended_to"]
    if not (isinstance(digest, str) and SHA256_RE.fullmatch(digest)) and not (
        unsaved and digest is None
    ):
        raise _fail("settings.appended_to", f"must be the source's digest (64 hex digits), got "
                                            f"{_short(digest)}")  # fmt: skip
    per = n_draws // settings.get("n_chains", 1)  # n_chains checked: it divides n_draws
    after = settings["appended_after"]
    if isinstance(after, bool) or not isinstance(after, int) or not 1 <= after < per:
        raise _fail("settings.appended_after", f"must be an integer in [1, {per - 1}] (the "
                    f"source's draws of each chain, before the continuation's), got "
                    f"{_short(after)}")  # fmt: skip
    pooled, run = (
        _sweep_count(settings, "pooled_sweeps", 1),
        _sweep_count(settings, "sweeps_run", 1),
    )
    for key, v in (("pooled_sweeps", pooled), ("sweeps_run", run)):
        if v is not None and n_iter is not None and v <= n_iter:
            raise _fail(f"settings.{key}", f"{v} must exceed n_iter={n_iter} (the source's "
                                           "sweeps, then the continuation's)")  # fmt: skip
    if pooled is not None and run is not None and pooled > run:
        raise _fail("settings.pooled_sweeps", f"{pooled} exceeds sweeps_run={run}")


def check_rate(value, field: str) -> None:
    """An acceptance rate as a file records it: null (NaN) or a number in [0, 1]."""
    ok = value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)
                           and 0.0 <= value <= 1.0)  # fmt: skip
    if not ok:
        raise _fail(field, f"must be null or an acceptance rate in [0, 1], got {_short(value)}")


def check_accept(diagnostics: dict) -> None:
    """Each parameter's acceptance rates in ``diagnostics`` (its "accept", where recorded: a
    list of rates, ``check_rate``), which an appended fit pools (``pool_accept``)."""
    for name, entry in diagnostics.items():
        if not isinstance(entry, dict) or "accept" not in entry:
            continue
        field, rates = f"diagnostics[{_short(name, 40)}].accept", entry["accept"]
        if rates is None:
            continue
        if not isinstance(rates, list):
            raise _fail(field, f"must be null or a list of acceptance rates, got {_short(rates)}")
        for i, v in enumerate(rates):
            check_rate(v, f"{field}[{i}]")


def _check_model_options(model: dict, inputs: list[str]) -> None:
    """The declared categorical inputs (model.categorical: name -> sorted integer levels, at
    least two) and the mean basis (model.mean_basis: null or a named kind); absent in files
    written before they existed."""
    cat = model.get("categorical", {})
    if not isinstance(cat, dict):
        raise _fail("model.categorical", f"must be an object name -> levels, got {_short(cat)}")
    for name, levels in cat.items():
        field = f"model.categorical.{name}"
        if name not in inputs:
            raise _fail(field, f"is not an input (inputs {_short(inputs)})")
        ok = isinstance(levels, list) and len(levels) >= 2 and all(
            isinstance(v, int) and not isinstance(v, bool) for v in levels)  # fmt: skip
        if not ok or levels != sorted(set(levels)):
            raise _fail(field, f"must be a sorted list of >= 2 distinct integers, got "
                        f"{_short(levels)}")  # fmt: skip
    if "input_ranges" in model:  # absent in files without given ranges (all before it)
        _check_input_ranges(model["input_ranges"], inputs, cat)
    if "y_given" in model:  # absent in files without a given y_mean, y_sd (all before it)
        given = model["y_given"]
        ok = isinstance(given, list) and given and all(isinstance(k, str) for k in given)
        if not ok or len(set(given)) != len(given) or not set(given) <= set(Y_GIVEN):
            raise _fail("model.y_given", f"must be a non-empty list of distinct entries of "
                        f"{list(Y_GIVEN)}, got {_short(given)}")  # fmt: skip
    kind = model.get("mean_basis")
    if kind is not None and kind not in MEAN_BASIS_KINDS:
        raise _fail("model.mean_basis",
                    f"must be null or one of {MEAN_BASIS_KINDS}, got {_short(kind)}")  # fmt: skip


def _check_input_ranges(ranged, inputs: list[str], cat: dict) -> None:
    """model.input_ranges: the inputs whose unit domain (x/t min and max) is a range the user
    gave (``SimData(x_range=, t_range=)``): distinct input names, none categorical."""
    ok = isinstance(ranged, list) and ranged and all(isinstance(n, str) for n in ranged)
    if not ok or len(set(ranged)) != len(ranged):
        raise _fail("model.input_ranges", f"must be a non-empty list of distinct input names, "
                    f"got {_short(ranged)}")  # fmt: skip
    for name in ranged:
        if name not in inputs:
            raise _fail("model.input_ranges",
                        f"{_short(name)} is not an input (inputs {_short(inputs)})")  # fmt: skip
        if name in cat:
            raise _fail("model.input_ranges", f"{_short(name)} is categorical: its unit scale is "
                        "its levels', never a given range")  # fmt: skip


def ranged_columns(manifest: dict, dims: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """Per x and t column, whether its unit domain is a given range (model.input_ranges,
    checked by ``check_fields``): such a design column lies in [0, 1] without spanning it."""
    ranged = manifest["model"].get("input_ranges", [])
    return (np.array([n in ranged for n in manifest["names"]["x"]], dtype=bool),
            np.array([n in ranged for n in manifest["names"]["t"]], dtype=bool))  # fmt: skip


def check_categorical(manifest: dict, arrays: dict[str, np.ndarray], dims: dict[str, int]) -> None:
    """Each declared categorical input's levels are exactly the integer values its design
    column takes (native units, from the unit design and its min/max)."""
    cat = manifest.get("model", {}).get("categorical", {})
    names = manifest["names"]["x"] + manifest["names"]["t"]
    design = np.hstack([
        arrays["x_unit"] * (arrays["x_max"] - arrays["x_min"]) + arrays["x_min"],
        arrays["t_unit"] * (arrays["t_max"] - arrays["t_min"]) + arrays["t_min"],
    ])  # fmt: skip
    for name, levels in cat.items():
        col = design[:, names.index(name)]
        codes = np.round(col)
        if np.any(np.abs(col - codes) > 1e-6 * np.maximum(1.0, np.abs(codes))):
            raise _fail(f"model.categorical.{name}", "its design column holds non-integer values")
        found = [int(v) for v in np.unique(codes)]
        if found != levels:
            raise _fail(
                f"model.categorical.{name}",
                f"declares levels {_short(levels)} but the design has {_short(found)}",
            )


def check_kron_design(manifest: dict, arrays: dict[str, np.ndarray]) -> None:
    """A separable declaration (``KRON_ARRAY``, `kron_groups`) matches the unit design: its
    factors' product in C order (``kronecker.structure``), and no mean basis (the separable
    likelihood has none); EmulatorFileError naming the array otherwise."""
    groups = kron_groups(arrays)
    if groups is None:
        return
    field = f"arrays/{KRON_ARRAY}"
    if manifest["model"].get("mean_basis") is not None:  # check_fields checked it
        raise _fail(field, "a separable design declared with a mean basis "
                    f"(model.mean_basis {_short(manifest['model']['mean_basis'])}): a separable "
                    "fit has the zero-mean GP only")  # fmt: skip
    names = tuple(manifest["names"]["x"]) + tuple(manifest["names"]["t"])
    try:
        kronecker.structure(np.hstack([arrays["x_unit"], arrays["t_unit"]]), groups, names)
    except GPMSAError as exc:
        codes = np.asarray(arrays[KRON_ARRAY]).reshape(-1).tolist()
        raise _fail(field, f"{_short(codes)} does not match the design: {exc}") from None


def check_manifest(manifest: dict) -> None:
    """The declared content of a file, before its arrays are decompressed (``read_raw``'s
    ``check``): the shapes the manifest lists and every other field."""
    specs = manifest["arrays"]
    shapes = {k: tuple(v["shape"]) for k, v in specs.items()}
    dims = check_shapes(shapes)
    for name in specs:
        if _known(name) and specs[name]["dtype"] != "<f8":
            raise _fail(f"arrays/{name}", f"dtype {specs[name]['dtype']}: must be <f8 (float64)")
    check_fields(manifest, dims)
    check_prior_groups(manifest["priors"], shapes)
    check_discrepancy_record(manifest["settings"], shapes)
    check_discrepancy_scale(manifest["settings"])
    check_fixed_record(manifest["settings"], shapes)


def _known(name: str) -> bool:
    return name in (*REQUIRED, "index", DISCREPANCY_ARRAY) or name.startswith(
        ("draw_", "cal_", "param_")
    )


# --- values ------------------------------------------------------------------------------------
def _finite(arrays: dict[str, np.ndarray], name: str) -> np.ndarray:
    a = arrays[name]
    if a.dtype != np.float64:
        raise _fail(f"arrays/{name}", f"dtype {a.dtype.str}: must be <f8 (float64)")
    bad = ~np.isfinite(a)
    if bad.any():
        pos = tuple(int(i) for i in np.argwhere(bad)[0])
        raise _fail(f"arrays/{name}", f"must be finite, holds {a[pos]} at index {list(pos)}")
    return a


def _resolvable_precision(a: np.ndarray, name: str, param: str) -> None:
    """A precision whose variance 1 / value overflows float64 (a subnormal one) is refused as
    the Emulator refuses it in params, naming the array."""
    resolvable = a > SMALLEST_PRECISION
    if not np.all(resolvable):
        pos = tuple(int(i) for i in np.argwhere(~resolvable)[0])
        raise _fail(f"arrays/{name}", f"holds {a[pos]} at index {list(pos)}: a precision whose "
                                      f"variance 1 / {param} overflows float64")  # fmt: skip


def _positive(arrays: dict[str, np.ndarray], name: str) -> np.ndarray:
    a = _finite(arrays, name)
    if a.size and not np.all(a > 0):
        pos = tuple(int(i) for i in np.argwhere(~(a > 0))[0])
        raise _fail(f"arrays/{name}", f"must be > 0, holds {a[pos]} at index {list(pos)}")
    return a


def _in_unit(arrays: dict[str, np.ndarray], name: str, span) -> None:
    """arrays[name] finite and in [0, 1]; where ``span`` (True, False, or one bool per
    column: a design column whose range was given lies inside [0, 1] without spanning it)
    each column spanning [0, 1]."""
    a = _finite(arrays, name)
    if a.size and (a.min() < -UNIT_TOL or a.max() > 1 + UNIT_TOL):
        low, high = numbers_text(a.min(), a.max(), 0.0, 1.0)[:2]  # 1 + 2e-9 not read as 1
        raise _fail(f"arrays/{name}", f"must lie in [0, 1], spans [{low}, {high}]")
    if a.size and np.any(span):
        lo, hi = a.min(axis=0), a.max(axis=0)
        k = np.flatnonzero(span & ((lo > UNIT_TOL) | (hi < 1 - UNIT_TOL)))
        if k.size:
            j = int(k[0])
            low, high = numbers_text(lo[j], hi[j], 0.0, 1.0)[:2]  # 1 - 2e-9 not read as 1
            raise _fail(
                f"arrays/{name}",
                f"column {j} spans [{low}, {high}]: a design maps its own range "
                "onto [0, 1] exactly",
            )


def check_values(
    arrays: dict[str, np.ndarray],
    dims: dict[str, int],
    ranged: tuple | None = None,
    given: tuple[str, ...] = (),
) -> None:
    """Finite values, ranges, positive scales and the file's internal redundancies. ``ranged``:
    per x and t column whether its range was given (`ranged_columns`; None: none), where the
    design lies inside [0, 1] without spanning it. ``given``: which of y_mean, y_sd the user
    gave (model.y_given), not recomputed from the runs (the weights still are their
    projection)."""
    x_span, t_span = (True, True) if ranged is None else (~ranged[0], ~ranged[1])
    _in_unit(arrays, "x_unit", span=x_span)
    _in_unit(arrays, "t_unit", span=t_span)
    for lo_name, hi_name in (("x_min", "x_max"), ("t_min", "t_max")):
        lo, hi = _finite(arrays, lo_name), _finite(arrays, hi_name)
        bad = np.flatnonzero(~(lo < hi))
        if bad.size:
            j = int(bad[0])
            raise _fail(
                f"arrays/{lo_name}",
                f"[{j}] = {lo[j]!r} must be below {hi_name}[{j}] = {hi[j]!r} (a design column "
                "with no spread)",
            )
        with np.errstate(over="ignore"):
            width = hi - lo
        tiny = np.finfo(float).tiny * np.maximum(1.0, np.maximum(np.abs(lo), np.abs(hi)))
        bad = np.flatnonzero(~(np.isfinite(width) & (width > tiny)))
        if bad.size:  # the unit scale divides by it: overflow, or nothing left of the spread
            j = int(bad[0])
            raise _fail(
                f"arrays/{lo_name}",
                f"[{j}] = {lo[j]!r} to {hi_name}[{j}] = {hi[j]!r}: the width {width[j]!r} is not "
                "a finite, normal number",
            )
    for name in ("y", "K", "w", "y_mean", "grid", "log_post"):
        _finite(arrays, name)
    if "index" in arrays:
        _finite(arrays, "index")
    for name in ("grid", "index"):  # the basis and the mean are interpolated along it
        g = arrays.get(name)
        if g is not None and g.ndim == 2:  # index points (l_sim, d): their own checks
            try:
                check_points(g, f"arrays/{name}")
            except GPMSAError as exc:
                raise EmulatorFileError(str(exc)) from None
        elif g is not None and np.any(np.diff(g) <= 0):
            raise _fail(f"arrays/{name}", "must be strictly increasing (the output grid)")
    y_sd = _positive(arrays, "y_sd")
    y_sd = float(y_sd[0]) if y_sd.size == 1 else y_sd  # (l_sim,), l_sim > 1: columnwise
    y, y_mean = arrays["y"], arrays["y_mean"]
    mean = y.mean(axis=0)
    tol = REL_TOL * (y_sd + np.abs(mean))
    if "y_mean" not in given and np.any(np.abs(mean - y_mean) > tol):
        raise _fail("arrays/y_mean", "differs from the mean of the training outputs arrays/y")
    if "y_sd" in given:  # the user's (SimData(y_mean=, y_sd=)): its square a normal float64
        with np.errstate(over="ignore", under="ignore"):
            square = np.asarray(y_sd) ** 2
        if not np.all((square >= np.finfo(np.float64).tiny) & np.isfinite(square)):
            raise _fail("arrays/y_sd", f"{_short(y_sd)}: its square is not a normal float64")
    else:
        _check_runs_sd(y, y_sd)
    K = arrays["K"]
    lam = np.sum(K**2, axis=0)
    if not np.all(lam > 0):
        raise _fail("arrays/K", "has a basis vector of zero length")
    if dims["l_sim"] == 1:
        if K[0, 0] != 1.0:
            raise _fail("arrays/K", f"{K.tolist()}: a scalar output's basis is [[1.0]]")
    else:
        gram = K.T @ K
        off = np.abs(gram - np.diag(np.diag(gram)))
        if off.max() > ORTHOGONAL_TOL * lam.max():
            raise _fail("arrays/K", "basis vectors are not orthogonal")
    if given:  # SimData's bound on a given scale: the standardised runs, squared, in float64
        with np.errstate(over="ignore", invalid="ignore"):
            big = float(np.max(np.abs((y - y_mean) / y_sd)))
        if not (np.isfinite(big) and np.isfinite(big * big)):
            raise _fail(" and ".join(f"arrays/{k}" for k in given),
                        "the training outputs standardised by the given scale overflow float64 "
                        f"(largest |y - y_mean| / y_sd = {big:.3g})")  # fmt: skip
    w = arrays["w"]
    w_ref = ((y - y_mean) / y_sd) @ np.linalg.pinv(K).T
    if np.max(np.abs(w - w_ref)) > W_TOL * (1.0 + np.max(np.abs(w_ref))):
        raise _fail("arrays/w", "differs from the projection of the training outputs on arrays/K")
    for k in EMULATOR_PARAMS:
        prm = _positive(arrays, f"param_{k}")
        if k.startswith("lam"):
            _resolvable_precision(prm, f"param_{k}", k)
        if f"draw_{k}" in arrays:
            draws = _positive(arrays, f"draw_{k}")
            if k.startswith("lam"):
                _resolvable_precision(draws, f"draw_{k}", k)
            if draws.shape[0]:
                lo, hi = draws.min(axis=0), draws.max(axis=0)
                slack = 1e-9 * np.maximum(np.abs(lo), np.abs(hi))
                if np.any(prm < lo - slack) or np.any(prm > hi + slack):
                    raise _fail(
                        f"arrays/param_{k}", "lies outside the range of its posterior draws"
                    )
    for name in arrays:
        if name.startswith("cal_"):
            if name[4:] == "theta":
                _in_unit(arrays, name, span=False)
            elif name[4:] == "theta_native":
                _finite(arrays, name)
            else:
                _positive(arrays, name)


def _check_runs_sd(y: np.ndarray, y_sd: float | np.ndarray) -> None:
    """``y_sd`` (a float, or (l_sim,) columnwise) is the training outputs' own sd, as
    ``Standardizer.from_sim`` computes it (relative ``REL_TOL``)."""
    try:
        sd = output_scale(y) if np.ndim(y_sd) == 0 else column_scales(y, range(y.shape[1]))
    except GPMSAError as exc:  # zero spread, or a spread that overflows
        raise _fail("arrays/y", str(exc)) from None
    if np.ndim(y_sd) == 0:
        if abs(sd - y_sd) > REL_TOL * sd:
            raise _fail("arrays/y_sd", f"{y_sd!r}, but the training outputs' sd is {sd!r}")
    elif (bad := np.flatnonzero(np.abs(sd - y_sd) > REL_TOL * sd)).size:
        k = int(bad[0])
        raise _fail("arrays/y_sd", f"[{k}] = {float(y_sd[k])!r}, but the sd of the training "
                    f"outputs' column {k} is {float(sd[k])!r} (scaled columnwise)")  # fmt: skip


def check_record(manifest: dict, arrays: dict[str, np.ndarray]) -> dict[str, int]:
    """Every check of a record (shapes, fields, values); returns its sizes."""
    for name, arr in arrays.items():
        if not isinstance(arr, np.ndarray):
            raise _fail(f"arrays/{name}", f"must be an array, got {type(arr).__name__}")
    shapes = {k: v.shape for k, v in arrays.items()}
    dims = check_shapes(shapes)
    check_fields(manifest, dims)
    check_prior_groups(manifest["priors"], shapes)
    check_discrepancy_record(manifest["settings"], shapes)
    check_discrepancy_scale(manifest["settings"])
    held = check_fixed_record(manifest["settings"], shapes)
    given = tuple(manifest["model"].get("y_given", ()))  # check_fields checked it
    check_values(arrays, dims, ranged_columns(manifest, dims), given)
    check_discrepancy_bases(manifest["settings"], arrays)
    check_fixed_draws(held, arrays)
    check_hot_record(manifest["settings"], shapes)
    check_categorical(manifest, arrays, dims)
    check_kron_design(manifest, arrays)
    return dims
