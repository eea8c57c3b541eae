"""Single elements of a parameter held fixed (SEPIA's per-element ``SepiaParam.fixed`` mask).

``fit(..., fixed={"lamVz": {1: 1e6}})``: a ``fixed=`` value given as a dict element index ->
value holds those elements at their values; the parameter's other elements are sampled as usual.
Index forms:

- a 1-D parameter (theta (q,), lamVz (G,), lamUz and lamWs (p_u,), lamWOs and lamOs (1,)): an
  int k, or the 1-tuple (k,);
- a 2-D parameter (betaU (p + q, p_u): input i, basis component j; betaV (p, G): known input
  i, precision group j): the tuple (i, j). An int i is read as (i, 0) only where the parameter
  has one column (p_u = 1, G = 1); with more columns it would be ambiguous and is refused.

Indices count from 0 and are never negative. A dict that names every element holds the whole
parameter, exactly as the array of those values (``Problem.fixed``); one that names some holds
those (``Problem.fixed_elements``). ``gpmsa.fit`` also takes theta's elements by their t_names.
"""

from __future__ import annotations

import numpy as np

from gpmsa.errors import GPMSAError, numbers_text
from gpmsa.model import categorical, constraints
from gpmsa.model.data import as_real

Index = tuple[int, ...]


def _is_int(key) -> bool:
    """An integer index (a Python or numpy int; not a bool)."""
    return isinstance(key, (int, np.integer)) and not isinstance(key, (bool, np.bool_))


def _allowed(name: str, shape: tuple[int, ...]) -> str:
    """The index forms and ranges ``name`` of ``shape`` takes, for an error message."""
    if 0 in shape:
        return f"none ({name} has shape {shape}: no elements)"
    if len(shape) == 1:
        return f"an int in 0..{shape[0] - 1} ({name} has shape {shape})"
    one_col = f", or an int i in 0..{shape[0] - 1} (one column)" if shape[1] == 1 else ""
    return (f"a tuple (i, j) with i in 0..{shape[0] - 1} and j in 0..{shape[1] - 1} ({name} has "
            f"shape {shape}){one_col}")  # fmt: skip


def element_index(name: str, key, shape: tuple[int, ...]) -> Index:
    """The element of ``name`` (of ``shape``, 1-D or 2-D) that dict key ``key`` names, as a
    full index tuple; GPMSAError naming the parameter, the key and the allowed range for a key
    of the wrong type or out of range."""
    what = f"fixed[{name!r}]: element index {key!r}"
    if _is_int(key) and len(shape) == 2 and shape[1] > 1:
        raise GPMSAError(f"{what} must be {_allowed(name, shape)}: an int names a row only "
                         "where there is one column")  # fmt: skip
    if _is_int(key):
        key = (key, 0) if len(shape) == 2 else (key,)
    if not (isinstance(key, tuple) and all(_is_int(k) for k in key)):
        raise GPMSAError(f"{what} must be {_allowed(name, shape)}")
    if len(key) != len(shape):
        raise GPMSAError(f"{what} has {len(key)} entries; {name} takes {_allowed(name, shape)}")
    idx = tuple(int(k) for k in key)
    if any(not 0 <= k < n for k, n in zip(idx, shape, strict=True)):
        raise GPMSAError(f"{what} is out of range; {name} takes {_allowed(name, shape)}")
    return idx


def parse(name: str, given: dict, shape: tuple[int, ...]) -> dict[Index, float]:
    """``given`` (element index -> value) as full index tuple -> float, in C order; GPMSAError
    naming the parameter for an empty dict, a bad index (`element_index`), two keys naming one
    element, or a value that is not one finite number."""
    if not given:
        raise GPMSAError(f"fixed[{name!r}] is an empty dict: give element index -> value for "
                         "the elements to hold (or leave the parameter out)")  # fmt: skip
    out: dict[Index, float] = {}
    keys: dict[Index, object] = {}
    for key, val in given.items():
        idx = element_index(name, key, shape)
        if idx in out:
            raise GPMSAError(
                f"fixed[{name!r}]: the entries {keys[idx]!r} and {key!r} both name element "
                f"{label(name, idx)}; give each element once"
            )
        x = as_real(val, f"fixed[{name!r}][{key!r}]")
        if not np.isfinite(x):
            raise GPMSAError(f"fixed[{name!r}][{key!r}] must be finite, got {x}")
        out[idx], keys[idx] = x, key
    return dict(sorted(out.items()))


def label(name: str, idx: Index) -> str:
    """The element's name as the diagnostics write it: "lamVz[1]", "betaU[2,0]"."""
    return f"{name}[{','.join(map(str, idx))}]"


def theta_by_position(given: dict, names) -> dict:
    """fit's ``fixed['theta']`` dict with each key that is one of ``names`` (the t_names) replaced
    by its position; other keys are left for `element_index` to judge. GPMSAError for an unknown
    name, or a name and a position that both name one element."""
    names = [str(n) for n in names]
    out: dict = {}
    for key, val in given.items():
        if isinstance(key, str):
            if key not in names:
                raise GPMSAError(
                    f"fixed['theta']: unknown calibration parameter {key!r}; give a name of "
                    f"{names} or a position 0..{len(names) - 1}"
                )
            pos = names.index(key)
        else:
            pos = int(key) if _is_int(key) else key
        if _is_int(pos) and pos in out:
            raise GPMSAError(
                f"fixed['theta']: two entries name element {pos} ({names[pos]!r} and "
                f"{pos}); give each element once"
            )
        out[pos] = val
    return out


def theta_unit(value, std, names, levels=None):
    """``fixed['theta']`` (native) on the unit scale: the whole vector (as ``theta_init``, an
    array (q,)), or for a dict of some elements (by t_name or position) a dict position -> unit
    value; a dict that names every element is the whole vector. Each value is checked as
    ``theta_init``'s: inside the design's range ``std.t_min`` .. ``std.t_max``, and a
    categorical element (``levels``: per element its unit-scale levels or None; None: all
    continuous) at one of its levels (within 1e-12 on the unit scale), returned as exactly
    that level: ``fit``, ``calibrate`` and the studies hold it so (`held_native` is its
    native value)."""
    names = list(names)
    closed = None if levels is None else [lv is not None for lv in levels]
    keep = None
    if isinstance(value, dict):
        given = parse("theta", theta_by_position(value, names), (len(names),))
        if len(given) < len(names):
            keep = [k for (k,) in given]
            # the other elements: the centre, only to check these
            value = 0.5 * (np.asarray(std.t_min, dtype=float) + np.asarray(std.t_max, dtype=float))
            for (k,), x in given.items():
                value[k] = x
        else:
            value = list(given.values())
    unit = constraints.theta_init_unit(value, std.t_min, std.t_max, names, closed,
                                       "fixed['theta']")  # fmt: skip
    for k, lv in enumerate(levels or ()):
        if keep is not None and k not in keep:
            continue
        if lv is not None and not np.any(np.isclose(lv, unit[k], rtol=0, atol=1e-12)):
            lo, span = float(std.t_min[k]), float(std.t_max[k] - std.t_min[k])
            got, *codes = numbers_text(lo + span * unit[k], *(lo + span * np.asarray(lv)))
            raise GPMSAError("fixed theta: categorical calibration parameter "
                             f"{names[k]} must be one of its training levels "
                             f"[{', '.join(codes)}], got {got}")  # fmt: skip
    unit = categorical.snap_to_levels(unit, levels or ())  # a categorical one: its level
    return unit if keep is None else {k: float(unit[k]) for k in keep}


def held_native(value, names, levels=None) -> dict[int, float]:
    """position -> native value of each theta element that ``fixed['theta']`` (``value``, as
    `theta_unit` takes it, checked there) holds: exactly the value given, a categorical
    element (``levels`` as `theta_unit`'s: per element its levels or None; None: all
    continuous) its level's integer code (the value `theta_unit` snaps to). The draws report
    these, not their unit values read back through the range (which can come back an ulp
    off)."""
    names = [str(n) for n in names]
    if isinstance(value, dict):
        given = parse("theta", theta_by_position(value, names), (len(names),))
        out = {k: x for (k,), x in given.items()}
    else:
        out = dict(enumerate(map(float, constraints.theta_native(value, names, "fixed['theta']"))))
    cat = [lv is not None for lv in levels] if levels is not None else [False] * len(names)
    return {k: float(np.round(x)) if cat[k] else x for k, x in out.items()}


def record(values: dict) -> dict:
    """The JSON-able record of held parameters (``gpmsa.fit``'s ``settings["fixed"]``,
    ``calibrate``'s ``info["fixed"]``) from ``values``: name -> the array of a parameter held
    whole (recorded as its value list), or index -> value of its held elements (recorded as
    {"elements": [index, ...], "values": [...]}); by name."""
    out: dict = {}
    for name, val in sorted(values.items()):
        if isinstance(val, dict):
            idx = sorted(val)
            out[name] = {"elements": [list(i) for i in idx],
                         "values": [float(val[i]) for i in idx]}  # fmt: skip
        else:
            out[name] = np.asarray(val, dtype=float).tolist()
    return out


def check_values(name: str, elements: dict[Index, float], priors, levels=None) -> None:
    """GPMSAError naming the element and its allowed range where a value of ``elements`` (index
    -> value, model scale) lies outside its prior's bounds under ``priors`` (a ``Priors``);
    ``levels``: theta's per-element levels (unit scale; None: continuous), a categorical
    element must be one of them."""
    for idx, x in elements.items():
        lv = None if levels is None else levels[idx[0]]
        if lv is not None:
            if bool(np.any(lv == x)):
                continue
            x_text = numbers_text(x, *np.asarray(lv, dtype=float).ravel())[0]
            where = f"its levels {np.asarray(lv).tolist()}"
        elif priors.scalar_log_prior(name, idx[-1])(x) > -np.inf:
            continue
        else:
            lower, upper, scale = _bounds(name, idx[-1], priors)
            x_text, lo, hi = numbers_text(x, lower, upper)
            where = f"its prior's bounds ({lo}, {hi}){scale}"
        raise GPMSAError(f"fixed[{name!r}]: element {label(name, idx)} = {x_text} lies outside "
                         f"{where} (zero prior density)")  # fmt: skip


def _bounds(name: str, element: int, priors) -> tuple[float, float, str]:
    """The open support (lower, upper) of element ``element`` of ``name``'s prior (model
    scale), and the scale's name where it is not the model's own ("": it is)."""
    if name == "theta":
        return 0.0, 1.0, " (unit scale)"
    if name in ("betaU", "betaV"):
        return 0.0, np.inf, ""
    g = priors.precision_prior(name, element)
    return float(g.lower), float(g.upper), ""
