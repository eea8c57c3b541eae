"""Simulation and observation data containers (native units, validated on construction)."""

from __future__ import annotations

import datetime
import hashlib
import numbers
import re
import sys
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from gpmsa.errors import DomainWarning, GPMSAError, numbers_text, user_stacklevel
from gpmsa.model import categorical, index_points, kronecker

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


def _first_non_number(value) -> str | None:
    """The first entry of ``value`` that is not a real number, described ("str '1.5'",
    "bool True", "None"): numpy would read "1.5" as 1.5, True as 1 and None as NaN. None when
    every entry is a number (numpy's integer and float scalars are)."""
    stack, seen = [value], set()
    while stack:
        v = _tensor_array(stack.pop())  # (it walks lists itself: one tensor at a time)
        if v is None:
            return "None"
        if isinstance(v, (str, bytes, bool, np.bool_)):
            item = v.item() if isinstance(v, np.generic) else v
            return f"{type(item).__name__} {item!r}"
        if isinstance(v, (list, tuple)):
            if id(v) not in seen:  # a list that holds itself is walked once
                seen.add(id(v))
                stack.extend(reversed(v))
            continue
        if isinstance(v, (int, float, complex, np.number)):
            continue
        try:
            arr = v if isinstance(v, np.ndarray) else np.asarray(v)
        except (TypeError, ValueError, RuntimeError):
            continue  # the conversion fails later with its own message
        if arr.dtype.kind in "bUS":
            if not arr.size:
                return f"{arr.dtype.name} values"
            item = arr.reshape(-1)[0].item()
            return f"{type(item).__name__} {item!r}"
        if arr.dtype.kind in "mM":  # dates and durations: numbers only by an epoch and unit
            return f"{arr.dtype.name} values"
        if arr.dtype.kind == "O":
            stack.extend(x for x in reversed(arr.reshape(-1).tolist()) if x is not v)
    return None


def tensor_values(value, _depth: int = 0):
    """``value`` with its torch tensors as their values (`_tensor_array`): a tensor itself, or
    a list or tuple holding tensors (numpy's depth of nesting at most), which comes back as a
    list of their values; anything else, and a list without tensors, as it is."""
    if isinstance(value, (list, tuple)) and _depth < MAX_NESTING:
        items = [tensor_values(v, _depth + 1) for v in value]
        return items if any(a is not b for a, b in zip(items, value, strict=True)) else value
    return _tensor_array(value)


def _tensor_array(value):
    """``value``, or for a torch tensor (an object with a bool ``requires_grad`` and a
    ``detach`` method) its values as a numpy array: numpy refuses a tensor that records
    gradients ("Can't call numpy() on Tensor that requires grad") and warns that a tensor's
    ``__array__`` takes no ``copy`` when it copies one. A tensor numpy cannot hold (on a GPU)
    is returned as it is, for the caller's conversion to refuse."""
    if not isinstance(getattr(value, "requires_grad", None), bool):
        return value
    try:
        return np.asarray(value.detach())
    except (AttributeError, TypeError, RuntimeError):
        return value


MAX_NESTING = 64
"""The deepest nesting of lists `tensor_values` reads (numpy's largest number of dimensions)."""


def size_of(value) -> int:
    """The number of entries of ``value``, from its shape (``np.size`` of a torch tensor is
    the tensor's ``size`` method, not a count); ValueError for a ragged list, as numpy's."""
    return int(np.prod(np.shape(value)))


def check_not_masked(value, name: str) -> None:
    """GPMSAError naming ``name`` for a numpy masked array: converted, its masked entries would
    be read as data (numpy drops the mask)."""
    if isinstance(value, np.ma.MaskedArray):
        raise GPMSAError(
            f"{name} is a numpy masked array: converting it would drop the mask and read the "
            "masked entries as data; pass a plain array without the masked rows"
        )


def as_float(value, name: str, *, advice: bool = True) -> np.ndarray:
    """Return ``value`` as a float64 array (a copy); GPMSAError naming ``name`` when it is not
    real numbers (strings, even numeric ones, bools, None, objects, ragged lists; complex
    values, which are never cast to their real part). numpy integer and float scalars are
    numbers. A numpy masked array is refused (`check_not_masked`). ``advice``: the message
    says what is not converted and, for text, where it lies and what it may be (a CSV table's
    decimal comma, a missing-value mark); False for a value read from a file's record, whose
    caller says the record is damaged."""
    check_not_masked(value, name)
    value = tensor_values(value)
    bad = _first_non_number(value)
    if bad is not None and not advice:
        raise GPMSAError(f"{name} must be a numeric array, got {bad}")
    if bad is not None:
        raise GPMSAError(
            f"{name} must be a numeric array, got {bad} (text, bools, dates and None are not "
            f"converted){_text_hint(value) if bad.startswith('str ') else ''}"
        )
    try:
        is_complex = np.iscomplexobj(value)
        arr = None if is_complex else np.array(value, dtype=np.float64)
    except OverflowError as exc:  # a Python int beyond float64's range
        raise GPMSAError(f"{name} holds a number too large for float64: {exc}") from exc
    except (TypeError, ValueError) as exc:
        raise GPMSAError(
            f"{name} must be a numeric array, got {_kind_of(value)}{_device_hint(value)}"
        ) from exc
    except RuntimeError as exc:  # e.g. a list of torch tensors that record gradients
        raise GPMSAError(f"{name} cannot be converted to numbers: {exc}") from exc
    if arr is None:
        raise GPMSAError(f"{name} must hold real numbers, got complex values")
    return arr


def _device_hint(value) -> str:
    """For a torch tensor (or a list or tuple whose first entry is one) on another device than
    the CPU, which numpy cannot read: where it is and how to bring it; "" otherwise."""
    first = value
    for _ in range(MAX_NESTING):
        if not isinstance(first, (list, tuple)) or not first:
            break
        first = first[0]
    device = getattr(first, "device", None)
    kind = getattr(device, "type", None)
    if not isinstance(getattr(first, "requires_grad", None), bool) or kind in (None, "cpu"):
        return ""
    return (f" (a torch tensor on device {str(device)!r}: numpy reads tensors on the CPU only; "
            "bring its values there, e.g. a GPU's by tensor.cpu(), or tensor.detach().cpu() "
            "where it records gradients)")  # fmt: skip


_GROUPED = re.compile(r"[+-]?[\d.,'\s\u00a0\u202f]*\d[\d.,'\s\u00a0\u202f]*")
"""Text of digits with separators no float holds: a decimal comma ("1,5") or digit grouping
("1,234.5", "1.234,5", "1 234", "1'234")."""


def _text_hint(value) -> str:
    """For a value holding text (a table read from a CSV file whose column pandas kept as
    text): where its first entry that does not read as a number lies (a table's row and column
    labels, else the array index), and what it may be, for `as_float`'s message; "" where that
    cannot be told. Every entry numeric text: that it is so."""
    table = hasattr(value, "to_numpy")  # a pandas object: its labels place the entry
    try:
        arr = value.to_numpy(dtype=object) if table else np.asarray(value)
    except (TypeError, ValueError):
        return ""
    if arr.dtype.kind not in "OUS" or arr.ndim > 2:
        return ""
    for pos in np.ndindex(arr.shape):
        entry = arr[pos]
        if not isinstance(entry, str):
            continue
        try:
            float(entry)
        except ValueError:
            break
    else:
        return ("; its text entries all read as numbers: convert them first (a pandas table: "
                "df.apply(pd.to_numeric))")  # fmt: skip
    rows = getattr(value, "index", None) if table else None  # a list's .index: a method
    cols = getattr(value, "columns", None) if table else None
    if rows is not None and cols is not None and len(pos) == 2:
        where = f" at row {_label(rows[pos[0]])}, column {_label(cols[pos[1]])}"
    elif rows is not None and len(pos) == 1:
        where = f" at row {_label(rows[pos[0]])}"
    else:
        where = f" at index {pos}" if pos else ""  # one text value: no place to name
    text, entry = str(entry), repr(str(entry)[:40])  # numpy's str_ shown as text
    if _GROUPED.fullmatch(text):
        why = ("a decimal comma or a thousands separator? Read the file with "
               "pd.read_csv(..., decimal=',') or thousands=',' as it is written")  # fmt: skip
    else:
        why = ("a missing-value mark or a unit? Read the file with pd.read_csv(..., "
               f"na_values=[{entry}]) and drop or fill those rows")  # fmt: skip
    return f"; the first that is not a number: {entry}{where} ({why})"


def _label(label) -> str:
    """A table's row or column ``label`` for a message: numpy scalars as their Python value
    (``20``, not ``np.int64(20)``), at most 40 characters."""
    value = label.item() if isinstance(label, np.generic) else label
    return f"{value!r:.40}"


def _kind_of(value) -> str:
    """What ``value`` is, for the message of a value numpy cannot make a float array of: a
    ragged list or tuple (entries of different lengths) says so, with the lengths."""
    if isinstance(value, (list, tuple)):
        lengths = [len(e) if isinstance(e, (list, tuple, np.ndarray)) else 1 for e in value]
        if len(set(lengths)) > 1:
            shown = ", ".join(map(str, lengths[:8])) + (", ..." if len(lengths) > 8 else "")
            return (f"a ragged {type(value).__name__}: its entries have lengths [{shown}] (every "
                    "row needs the same number of values)")  # fmt: skip
    return type(value).__name__


def as_real(value, name: str) -> float:
    """``value`` as a float: a real number (a Python or numpy scalar, or a 0-d array); GPMSAError
    naming ``name`` for a string, a bool, None, a list or a larger array."""
    bad = _first_non_number(value)
    if bad is not None:
        raise GPMSAError(f"{name} must be a number, got {bad}")
    if isinstance(value, (list, tuple)) or np.ndim(value) != 0:
        raise GPMSAError(f"{name} must be a single number, got {value!r}")
    return float(as_float(value, name))


def check_flag(value, name: str) -> bool:
    """``value`` as a bool; GPMSAError naming ``name`` unless it is True or False (a string such
    as "no" is not read as a flag)."""
    if not isinstance(value, (bool, np.bool_)):
        raise GPMSAError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def column_labels(value) -> tuple[str, ...] | None:
    """The column labels of a table with named columns (a pandas DataFrame: anything with
    ``columns`` that is not a numpy array), as strings; None for any other value."""
    columns = getattr(value, "columns", None)
    if columns is None or isinstance(value, np.ndarray):
        return None
    return tuple(str(c) for c in columns)


def default_labels(labels) -> bool:
    """Whether table column ``labels`` (`column_labels`) are a frame's default labels '0', '1',
    ... in order: no names, so the columns are read by position, as an array's."""
    return labels is not None and tuple(labels) == tuple(str(k) for k in range(len(labels)))


def same_names(labels, names) -> bool:
    """Whether the labels ``labels`` (strings) are ``names`` in some order, as `column_order`
    matches them: as they are, or without their surrounding blanks (a CSV header's) where
    that leaves them apart."""
    labels, names = list(labels), list(names)
    if sorted(labels) == sorted(names):
        return True
    bare, keys = [str(c).strip() for c in labels], [str(n).strip() for n in names]
    return sorted(bare) == sorted(keys) and len(set(bare)) == len(bare)


def column_order(labels, names, name: str) -> list[int]:
    """The positions of ``names`` among a table's column ``labels`` (`same_names`); GPMSAError
    naming ``name`` when the labels are not ``names`` (in some order)."""
    labels, names = list(labels), list(names)
    if sorted(labels) == sorted(names):
        return [labels.index(n) for n in names]
    if same_names(labels, names):  # a CSV header's blanks
        bare, keys = [str(c).strip() for c in labels], [str(n).strip() for n in names]
        return [bare.index(n) for n in keys]
    raise GPMSAError(f"{name} has the columns {labels}; expected {names} (in any order)"
                     f"{_columns_hint(labels, names)}")  # fmt: skip


def _columns_hint(labels: list, names: list) -> str:
    """What table column ``labels`` that are not ``names`` may be, for `column_order`'s
    message: pandas' labels of a column without a header ("Unnamed: 3": a separator ending
    every line of a CSV file) or of a repeated one ("f.1"), names of another case, numbers (a
    file without a header row), or more columns than ``names``; "" otherwise."""
    labels, names = [str(c) for c in labels], [str(n) for n in names]
    unknown = [c for c in labels if c not in names]
    hints = []
    if unnamed := [c for c in unknown if c.startswith("Unnamed: ")]:
        hints.append(f"{unnamed[0]!r:.40} is pandas' label of a column without a header: a "
                     "separator ending every line of the CSV file? Drop it (e.g. "
                     "df.dropna(axis=1, how='all'))")  # fmt: skip
    twice = [c for c in unknown if re.fullmatch(r"(.+)\.\d+", c) and c.rsplit(".", 1)[0] in labels]
    if twice:
        hints.append(f"{twice[0]!r:.40} is pandas' label of a repeated header name: the file "
                     "names a column twice")  # fmt: skip
    if sorted(c.lower() for c in labels) == sorted(n.lower() for n in names):
        hints.append("names are case-sensitive: give them as the data's names spell them")
    elif all(_reads_as_number(c) for c in labels) and not all(_reads_as_number(n) for n in names):
        hints.append(
            "the labels are numbers: a file without a header row, its first row read "
            "as names? Read it with pd.read_csv(..., header=None, names=[...])"
        )
    elif not hints and set(names) < set(labels):
        hints.append(f"select the columns: table[{names!r:.200}]")
    return f" ({'; '.join(hints)})" if hints else ""


def _reads_as_number(text: str) -> bool:
    """Whether ``text`` reads as a number (float())."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def by_column_names(value, names, name: str):
    """A table with named columns (`column_labels`) as its columns in the order of ``names``;
    a pandas Series by its labels (`series_by_names`); any other value as it is. GPMSAError
    naming ``name`` when the table's columns are not ``names`` (in some order): its columns are
    never read by position."""
    if names is None:
        return value
    if is_series(value):
        return series_by_names(value, names, name)
    labels = column_labels(value)
    if labels is None:
        return value
    return value.iloc[:, column_order(labels, [str(n) for n in names], name)]


def pandas_rows(value, names=None):
    """The row labels of a pandas DataFrame, or of a Series read as the values of one input;
    None for any other value and for a Series indexed by ``names`` (one point, not rows)."""
    pd = sys.modules.get("pandas")
    if pd is None or not isinstance(value, pd.DataFrame | pd.Series):
        return None
    if isinstance(value, pd.Series) and names is not None:
        if same_names([str(i) for i in value.index], [str(n) for n in names]):
            return None
    return value.index


def check_same_rows(values: dict, names: dict | None = None) -> None:
    """GPMSAError when two pandas inputs (name -> value; ``names``: name -> the input names a
    one-point Series is indexed by) of as many rows (> 1) carry different row labels: gpmsa
    pairs rows by position, pandas by label, so their rows would be silently mispaired."""
    first = None
    for name, value in values.items():
        rows = pandas_rows(value, (names or {}).get(name))
        if rows is None:
            continue
        if first is None:
            first = (name, rows)
            continue
        ref, ref_rows = first
        if len(rows) == len(ref_rows) > 1 and not rows.equals(ref_rows):
            raise GPMSAError(
                f"{ref} and {name} are pandas objects whose row labels differ ({ref}: "
                f"{list(ref_rows[:5])}..., {name}: {list(rows[:5])}...): gpmsa pairs rows by "
                f"position, not by label; align them first (e.g. {name}.loc[{ref}.index]), or "
                "pass plain arrays (.to_numpy())"
            )


def is_series(value) -> bool:
    """Whether ``value`` is a pandas Series (without importing pandas: a Series exists only
    where pandas is imported already)."""
    pd = sys.modules.get("pandas")
    return pd is not None and isinstance(value, pd.Series)


def series_by_names(series, names, name: str) -> np.ndarray:
    """A pandas Series as values in the order of ``names`` (d names), matched by its labels:

    - indexed by ``names`` (in any order; e.g. a table's row, ``df.iloc[0]``): one point (1, d);
    - named as the only input, ``names == [series.name]`` (e.g. ``df["v"]``): its values (n,),
      the column of that input;
    - carrying no names (no ``name`` and an integer index): its values (n,), read as a plain
      1-D array (by position, as a list would be).

    Any other Series (e.g. the column ``df["b"]`` of one of several inputs, or an index of
    other names) is a GPMSAError naming ``name``: its entries are never matched by position
    against names it does not carry."""
    labels = tuple(str(i) for i in series.index)
    names = [str(n) for n in names]
    if same_names(labels, names):
        return series.to_numpy()[column_order(labels, names, name)][None, :]
    title = None if series.name is None else str(series.name)
    if title is not None and [title] == names:
        return series.to_numpy()
    if title is None and all(isinstance(i, int | np.integer) for i in series.index):
        return series.to_numpy()
    one = f", the values of the one input as a Series named {names[0]!r}" if len(names) == 1 else ""
    raise GPMSAError(
        f"{name} is a pandas Series named {title!r} with the index {list(labels)[:10]}: give one "
        f"point as a Series indexed by {names} (in any order){one}, or a table with these "
        "columns"
    )


def as_matrix(
    value, name: str, *, ncols: int | None = None, no_columns: bool = False
) -> np.ndarray:
    """Return ``value`` as a finite float64 2-D array; a 1-D array becomes one column, or, where
    ``ncols`` > 1 and it has exactly ``ncols`` entries, one row. ``no_columns``: a 2-D array of
    rows with no columns (n, 0) is accepted (known inputs x when there are none, p = 0).

    Raises GPMSAError naming ``name`` for non-numeric or complex values, a wrong shape or
    non-finite entries.
    """
    arr = as_float(value, name)
    given = arr.shape
    if arr.ndim == 1:
        one_row = ncols is not None and ncols > 1 and arr.size == ncols
        arr = arr[None, :] if one_row else arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0 or (arr.shape[1] == 0 and not no_columns):
        raise GPMSAError(
            f"{name} must be a non-empty 2-D array (rows x columns), got shape {given}"
        )
    if ncols is not None and arr.shape[1] != ncols:
        raise GPMSAError(f"{name} must have {ncols} columns, got shape {given}")
    check_finite(arr, name)
    return arr


NUMPY_PRINT_DEFAULTS = {
    "precision": 8, "threshold": 1000, "edgeitems": 3, "linewidth": 75, "suppress": False,
    "nanstr": "nan", "infstr": "inf", "sign": "-", "floatmode": "maxprec", "legacy": False,
    "formatter": None, "override_repr": None,
}  # fmt: skip
"""numpy's own print options (``np.get_printoptions()`` of a fresh session)."""


def array_text(arr, **options) -> str:
    """``str(arr)`` as numpy's default print options write it, whatever the user has set with
    ``np.set_printoptions`` (precision=2 or suppress=True showed 1.004 as 1.00 and 1e-9 as 0.00
    in a message about that very value; threshold=5 hid a NaN behind "..."); ``options``: the
    message's own (e.g. ``precision=3``), in place of those defaults."""
    given = np.get_printoptions()  # override_repr: numpy >= 2.1
    chosen = {k: v for k, v in NUMPY_PRINT_DEFAULTS.items() if k in given} | options
    with np.printoptions(**chosen):
        return str(np.asarray(arr))


def check_finite(arr: np.ndarray, name: str) -> None:
    """Raise GPMSAError if ``arr`` holds NaN or inf, naming the first bad position."""
    bad = ~np.isfinite(arr)
    if bad.any():
        pos = tuple(int(i) for i in np.argwhere(bad)[0])
        raise GPMSAError(f"{name} must be finite, got {arr[pos]} at index {pos}")


def check_count(value, name: str, low: int = 1, high: int | None = None) -> int:
    """``value`` as an int >= ``low`` (and <= ``high`` if given); GPMSAError naming ``name``
    otherwise (a bool, a float, a string or NaN is not a count)."""
    ok = not isinstance(value, bool) and isinstance(value, int | np.integer)
    if not ok or value < low or (high is not None and value > high):
        allowed = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise GPMSAError(f"{name} must be an integer {allowed}, got {value!r}")
    return int(value)


def evenly_spaced(n: int, k: int | None, name: str = "n_draws") -> np.ndarray:
    """Indices of at most ``k`` of ``n`` draws, evenly spaced from the first to the last
    (rounded to the nearest); all n for ``k`` None (``name``: the argument ``k`` came as, for
    the error). Every call that averages over a subset of draws (``Emulator.predict``,
    ``gpmsa.predictive``, calibration with ``emulator_params="draws"``) picks them so: the same
    count gives the same draws everywhere."""
    if k is None:
        return np.arange(n)
    k = min(check_count(k, name), n)
    return np.unique(np.linspace(0, n - 1, k).round().astype(int))


def check_level(level) -> float:
    """A probability ``level`` of a credible or prediction interval as a float in (0, 1);
    GPMSAError otherwise (a string, a bool or an array is not a level)."""
    real = not isinstance(level, bool) and isinstance(level, int | float | np.integer | np.floating)
    if not (real and 0.0 < level < 1.0):
        raise GPMSAError(f"level must be a number in (0, 1), got {level!r}")
    return float(level)


def _percent_key(value: float, tolerance: float) -> str:
    """``value`` in 6 significant digits, more until it prints within ``tolerance`` of itself."""
    for digits in range(6, 18):
        key = f"{value:.{digits}g}"
        if abs(float(key) - value) <= tolerance:
            break
    return key


def quantile_keys(level: float) -> tuple[str, str]:
    """``Posterior.summary``'s (and ``Emulator.theta_summary``'s) keys of the ends of the
    central interval of probability ``level``: "q" and the percentage, 100 (1 -+ level) / 2,
    in 6 significant digits ("q5", "q95" for 0.9; "q2.5", "q97.5" for 0.95), with more digits
    where an end needs them to print within 1e-5 of its distance to the nearest of 0, 50 and
    100 (e.g. "q49.999995", "q50.000005" for 1e-7; "q5e-07", "q99.9999995" for 0.99999999),
    so that no two levels' keys collide and no end prints as 0, 50 or 100. GPMSAError for a
    level so small that its ends are the median in float64 (below about 1e-16).
    (In gpmsa.calibration.posterior before session 74; still importable from there.)"""
    lo, hi = 100 * (1 - level) / 2, 100 * (1 + level) / 2
    tolerance = 1e-5 * min(lo, hi - 50.0)
    keys = _percent_key(lo, tolerance), _percent_key(hi, tolerance)
    if tolerance > 0 and keys[0] != keys[1]:
        return f"q{keys[0]}", f"q{keys[1]}"
    raise GPMSAError(
        f"level={level!r} is too small: the ends of its interval, at probabilities "
        "(1 -+ level) / 2, are both the median (0.5) in float64; give a larger level"
    )


SHOWN_PROBABILITIES = 10
"""A refused ``q`` of up to this many values is shown whole in ``check_probabilities``'s
message; a longer one by its first bad entry."""


def check_probabilities(q, name: str = "q") -> np.ndarray:
    """``q`` as a float64 array of probabilities in [0, 1] (a number: a 0-d array); GPMSAError
    naming ``name`` for none (an empty q), a NaN or an infinity, or one outside [0, 1] (the
    quantile functions' ``q``), with the value given where it holds up to
    ``SHOWN_PROBABILITIES`` values, else with its first bad entry, that entry's index and the
    count of bad ones (so that a message never prints a long array whole)."""
    arr = as_float(q, name)
    if arr.size == 0:
        raise GPMSAError(f"{name} must hold at least one probability, got {q!r}")
    bad = ~((arr >= 0) & (arr <= 1))  # NaN compares False
    if not bad.any():
        return arr
    if arr.size <= SHOWN_PROBABILITIES:
        raise GPMSAError(f"{name} must lie in [0, 1], got {q!r}")
    pos = tuple(int(i) for i in np.argwhere(bad)[0])
    raise GPMSAError(
        f"{name} must lie in [0, 1], got {arr[pos]} at index {pos} (the first of "
        f"{int(bad.sum())} of {arr.size} values outside it)"
    )


MAX_SEED = 2**128
"""Seeds are integers in [0, MAX_SEED) (numpy's SeedSequence takes non-negative integers)."""


def check_seed(seed, name: str = "seed", *, generator: bool = False):
    """Return ``seed`` if it is None or an integer in [0, 2**128) (or, with ``generator=True``,
    a ``numpy.random.Generator``); else raise GPMSAError naming the argument and the range.

    numpy itself refuses a negative seed deep inside SeedSequence; this says so up front.
    """
    if seed is None or (generator and isinstance(seed, np.random.Generator)):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        kinds = "None, an integer or a numpy Generator" if generator else "None or an integer"
        raise GPMSAError(f"{name} must be {kinds}, got {seed!r} ({type(seed).__name__})")
    if not 0 <= int(seed) < MAX_SEED:
        raise GPMSAError(f"{name}={int(seed)} is out of range: allowed integers in [0, 2**128)")
    return int(seed)


def run_seed(seed) -> int:
    """The integer seed a run (``fit``, ``calibrate``, a study) uses and records: ``seed``
    itself, one drawn from a numpy Generator, or for None one drawn from fresh OS entropy, so
    that every run can be repeated with ``seed=`` the recorded integer. GPMSAError as
    ``check_seed``."""
    seed = check_seed(seed, generator=True)
    if seed is None:
        seed = np.random.default_rng()
    if isinstance(seed, np.random.Generator):
        return int(seed.integers(2**63))
    return seed


def output_scale(y: np.ndarray) -> float:
    """GPM/SA's output scale of simulation outputs ``y`` (m, l): the sd (ddof=1) of all values
    after centring each column; GPMSAError naming ``y`` when it is zero, or when its square
    overflows (values too large) or underflows (a spread too small) float64."""
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        centred = y - y.mean(axis=0)
        big = float(np.max(np.abs(centred)))
        sd = big * float(np.std(centred / big, ddof=1)) if 0.0 < big < np.inf else big
        square = sd * sd
    if not (np.isfinite(sd) and np.isfinite(square)):
        raise GPMSAError(
            f"y is too large to standardise: its spread overflows float64 (largest |y| = "
            f"{np.abs(y).max():.3g}); rescale y (e.g. other units)"
        )
    if not sd > 0:
        raise GPMSAError("y has zero spread after centring each column; the output must vary")
    if not square >= np.finfo(np.float64).tiny:
        raise GPMSAError(
            f"y's spread (sd {sd:.3g} after centring each column) is too small to standardise: "
            "its square underflows float64; rescale y (e.g. other units)"
        )
    return sd


Y_SCALES = ("scalar", "columnwise")
"""``SimData(y_scale=)``: one sd over all outputs (GPM/SA's), or each output element its own
(SEPIA's ``standardize_y(scale='columnwise')``)."""


def column_scales(y: np.ndarray, names) -> np.ndarray:
    """Each column's own output scale (l,): `output_scale` of that column (the sd, ddof=1; for
    one column `output_scale` itself, to the bit); GPMSAError naming the column (``names``)
    that does not vary or whose spread float64 cannot hold."""
    out = np.empty(y.shape[1])
    for k in range(y.shape[1]):
        if np.ptp(y[:, k]) == 0.0:
            raise GPMSAError(
                f"y column {names[k]!r} is constant ({float(y[0, k])!r}): y_scale='columnwise' "
                "divides each output element by its own sd; drop the column or use "
                "y_scale='scalar'"
            )
        try:
            out[k] = output_scale(y[:, k : k + 1])
            _check_resolution(y[:, k : k + 1], out[k])
        except GPMSAError as exc:
            raise GPMSAError(f"y column {names[k]!r}: {exc}") from None
    return out


def _given_values(value, l_sim: int, name: str) -> np.ndarray:
    """A given ``y_mean`` or ``y_sd`` as a finite float64 array: a number (shape ()) or one value
    per output element (l_sim,); GPMSAError naming ``name`` and the shape otherwise."""
    arr = as_float(value, name)
    if arr.shape not in ((), (l_sim,)):
        raise GPMSAError(
            f"{name} must be a number or an array ({l_sim},), one per output element (y has "
            f"{l_sim} column(s)), got shape {arr.shape}"
        )
    check_finite(arr, name)
    return arr


def _given_scale(y_mean, y_sd, y: np.ndarray):
    """``SimData``'s given ``y_mean`` (as (l_sim,)) and ``y_sd`` (a float, or (l_sim,) for
    l_sim > 1), each None where not given; GPMSAError naming the argument for a y_sd that is
    not positive, whose square float64 cannot hold, or that (with y_mean) puts y's
    standardised values beyond float64."""
    l_sim = y.shape[1]
    if y_mean is not None:
        y_mean = np.broadcast_to(_given_values(y_mean, l_sim, "y_mean"), (l_sim,)).copy()
    if y_sd is not None:
        sd = _given_values(y_sd, l_sim, "y_sd")
        bad = np.flatnonzero(~(sd.reshape(-1) > 0))
        if bad.size:
            k = int(bad[0])
            at = f"[{k}] = " if sd.ndim else " = "
            raise GPMSAError(f"y_sd must be positive, got y_sd{at}{float(sd.reshape(-1)[k])!r}")
        with np.errstate(over="ignore", under="ignore"):
            square = sd * sd
        if not (np.all(np.isfinite(square)) and np.all(square >= np.finfo(np.float64).tiny)):
            raise GPMSAError(
                f"y_sd = {y_sd!r}: its square is not a normal float64 (the variances are scaled "
                "by it); rescale y (e.g. other units)"
            )
        y_sd = float(sd.reshape(-1)[0]) if sd.ndim == 0 or l_sim == 1 else sd
    if y_mean is not None or y_sd is not None:
        mean = y.mean(axis=0) if y_mean is None else y_mean
        with np.errstate(over="ignore", invalid="ignore"):
            z = (y - mean) / (output_scale(y) if y_sd is None else y_sd)
            big = float(np.max(np.abs(z)))
        if not (np.isfinite(big) and np.isfinite(big * big)):
            raise GPMSAError(
                "y standardised by the given y_mean and y_sd overflows float64 (largest "
                f"|y - y_mean| / y_sd = {big:.3g}); give a y_sd of the order of y's spread"
            )
    return y_mean, y_sd


RESERVED_NAMES = ("lamOs", "lamVz", "betaV")
"""Names a calibration posterior gives its other parameters (with "betaV[k]", "betaV[k,g]" and
"lamVz[g]", k, g = 0, 1, ...): no calibration parameter (t_names) may take them."""


def check_parameter_names(names, what: str = "t_names") -> None:
    """GPMSAError when a calibration parameter name is reserved (``RESERVED_NAMES`` or
    betaV[k], betaV[k,g], lamVz[g]): its draws would overwrite, or be confused with, those of
    that parameter."""
    for name in names:
        if name in RESERVED_NAMES or re.fullmatch(r"(betaV|lamVz)\[\d+(,\d+)?\]", name):
            raise GPMSAError(
                f"{what}: {name!r} is a reserved name: a calibration posterior names its other "
                f"parameters {', '.join(RESERVED_NAMES)}, betaV[k] and, with several discrepancy "
                "precision groups, betaV[k,g] and lamVz[g] (k, g = 0, 1, ...); rename the "
                "calibration parameter"
            )


def _labels(value, what: str, kind: str):
    """Names or units as given, a sequence of them as a tuple (a generator is read once);
    GPMSAError naming ``what`` for a value that is not an ordered sequence of them (a number,
    bytes, or a set or dict, whose order is not the columns')."""
    if value is None or isinstance(value, str):
        return value  # None: the defaults; a string: refused with its own message
    if isinstance(value, (set, frozenset, dict, bytes)) or not hasattr(value, "__iter__"):
        raise GPMSAError(
            f"{what} must be a list of {kind}, one per column in order, got {type(value).__name__}"
            f" {value!r}"
        )
    return tuple(value)


REPR_COLUMNS = 6
"""The columns a SimData's or ObsData's repr names with their ranges (the rest counted)."""


def _span(values: np.ndarray) -> str:
    """``[min, max]`` of ``values`` for a repr: 4 significant digits, more where the two would
    read alike (`numbers_text`: [1e6 + 0.02, 1e6 + 0.99] as "[1000000.02, 1000000.99]", not
    "[1e+06, 1e+06]"); a zero as "0", never "-0"."""
    if not np.size(values):
        return "[]"
    lo, hi = numbers_text(float(np.min(values)) + 0.0, float(np.max(values)) + 0.0, digits=4)
    return f"[{lo}, {hi}]"


def repr_names(names, shown: int = REPR_COLUMNS) -> str:
    """A list of names for a one-line repr: the first ``shown``, each cut to `REPR_NAME`
    characters (ending "...") and quoted as Python quotes it (a newline as \\n), then how many
    more ("['a', 'b', +14 more]")."""
    names = [str(n) for n in names]
    cut = [n if len(n) <= REPR_NAME else n[: REPR_NAME - 3] + "..." for n in names[:shown]]
    parts = [repr(n) for n in cut]
    if len(names) > shown:
        parts.append(f"+{len(names) - shown} more")
    return f"[{', '.join(parts)}]"


def _count(n: int, what: str) -> str:
    return f"{n} {what}{'' if n == 1 else 's'}"


REPR_NAME = 40
"""The characters of a column's name a repr shows (a longer one cut, ending "...")."""


def repr_name(name: str) -> str:
    """``name`` for a one-line repr: escaped where not printable (a newline as \\n), cut to
    `REPR_NAME` characters."""
    text = name if name.isprintable() else repr(name)[1:-1]
    return text if len(text) <= REPR_NAME else text[: REPR_NAME - 3] + "..."


def _columns_text(arr: np.ndarray, names) -> str:
    """Each column's name and range (the first `REPR_COLUMNS`, then how many more), for a repr;
    "none" without columns."""
    if arr.shape[1] == 0:
        return "none"
    parts = [f"{repr_name(name)} {_span(arr[:, k])}"
             for k, name in enumerate(names[:REPR_COLUMNS])]  # fmt: skip
    more = arr.shape[1] - REPR_COLUMNS
    return ", ".join(parts) + (f", ... ({more} more)" if more > 0 else "")


def _index_text(index: np.ndarray | None, names: tuple[str, ...] | None, l_sim: int) -> str:
    """The output index for ``SimData``'s repr: " on index [0, 1]", " on index points [0, 1] x
    [0, 2]", each column's range led by its name where ``names`` gives them (the default index
    0..l_sim-1 too); "" without an index or names."""
    if index is None and names is None:
        return ""
    cols = (np.arange(l_sim, dtype=np.float64) if index is None else index).reshape(l_sim, -1).T
    labels = [""] * len(cols) if names is None else [f"{repr_name(n)} " for n in names]
    kind = "index points" if len(cols) > 1 else "index"
    return f" on {kind} " + " x ".join(f"{a}{_span(c)}" for a, c in zip(labels, cols, strict=True))


def _label_text(entry, k: int, what: str, kind: str) -> str:
    """Entry ``k`` of the column labels ``what`` (x_names, t_units, ...) as text: a string, or a
    table's column label of another type as its text, as `column_labels` reads a table's (an
    integer column number, a number such as a wavelength, a date, a MultiIndex's tuple: so
    ``y_names=df.columns`` names what ``df`` alone does); GPMSAError naming ``what[k]`` for
    anything else (None, a bool, bytes, a list or array, a non-finite number), which would
    otherwise be kept as its repr ("None", "['a']"), and for a blank name (a posterior, a
    y_obs table and ``gpmsa calibrate`` read the columns by their names)."""
    if not isinstance(entry, str) and not _column_label(entry):
        hint = ": decode it (.decode())" if isinstance(entry, bytes) else ""
        raise GPMSAError(f"{what}[{k}] must be a {kind} (a string), got "
                         f"{type(entry).__name__} {entry!r:.80}{hint}")  # fmt: skip
    text = str(entry)
    if kind == "name" and not text.strip():
        raise GPMSAError(f"{what}[{k}] must be a non-empty name, got {entry!r}")
    return text


def _column_label(entry) -> bool:
    """Whether ``entry``, no string, is a table column label that reads as text: a real number
    (not a bool, finite), a date or time, or a tuple of such labels or strings (a pandas
    MultiIndex's)."""
    if isinstance(entry, bool | np.bool_):
        return False
    if isinstance(entry, numbers.Real):  # int, float and their numpy kinds
        return bool(np.isfinite(float(entry)))
    if isinstance(entry, datetime.date | datetime.time | np.datetime64):
        return True
    return (isinstance(entry, tuple) and len(entry) > 0
            and all(isinstance(e, str) or _column_label(e) for e in entry))  # fmt: skip


def _names(names: Sequence[str] | None, n: int, prefix: str, what: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{prefix}{i}" for i in range(n))
    if isinstance(names, str):
        raise GPMSAError(f"{what} must be a list of names, got the string {names!r} (for one "
                         f"name pass [{names!r}])")  # fmt: skip
    names = tuple(_label_text(s, k, what, "name") for k, s in enumerate(names))
    if len(names) != n:
        each = ""
        if what == "y_names" and len(names) == 1:  # one name for a functional output
            each = (f" (one name per output value, a functional output's too: they are the keys "
                    f"by which y_obs tables and `gpmsa calibrate --y` read it; to name them after "
                    f"one: [f\"{names[0]}{{k}}\" for k in range({n})])")  # fmt: skip
        raise GPMSAError(f"{what} must have {n} entries, got {len(names)}: {names}{each}")
    if len(set(names)) != n:
        raise GPMSAError(f"{what} must be unique, got {names}")
    return names


def _units(units: Sequence[str] | None, n: int, what: str) -> tuple[str, ...]:
    if units is None:
        return ("",) * n
    if isinstance(units, str):
        raise GPMSAError(f"{what} must be a list of units, got the string {units!r} (for one "
                         f"unit pass [{units!r}])")  # fmt: skip
    units = tuple(_label_text(s, k, what, "unit") for k, s in enumerate(units))
    if len(units) != n:
        each = ""
        if what == "y_units" and len(units) == 1:
            each = (
                f" (one per output value, on a functional output's grid too: [{units[0]!r}] * {n})"
            )
        raise GPMSAError(f"{what} must have {n} entries, got {len(units)}: {units}{each}")
    return units


def _index_labels(value, d: int, l_sim: int, what: str) -> tuple[str, ...] | None:
    """``SimData``'s ``index_names`` or ``index_units`` (``what``): None, or one string per
    column of the output index (``d`` columns; a single string for one column); names
    non-empty (not only blanks) and unique. GPMSAError naming ``what`` otherwise, and for a
    scalar output (``l_sim`` 1), which has no index to label."""
    if value is None:
        return None
    kind = "names" if what == "index_names" else "units"
    if l_sim == 1:
        raise GPMSAError(
            f"{what} labels the output index, but y has one column (a scalar output has no "
            f"index); leave {what} out"
        )
    if isinstance(value, str):
        if d != 1:
            raise GPMSAError(
                f"{what} must be a list of {d} {kind}, one per column of the output index "
                f"({l_sim}, {d}), got the string {value!r}"
            )
        value = (value,)
    value = _labels(value, what, kind)
    if len(value) != d:
        shape = f"({l_sim},)" if d == 1 else f"({l_sim}, {d})"
        raise GPMSAError(
            f"{what} must have {d} entries, one per column of the output index {shape}, got "
            f"{len(value)}: {value!r:.200}"
        )
    for k, entry in enumerate(value):
        if not isinstance(entry, str):
            raise GPMSAError(f"{what}[{k}] must be a string, got {type(entry).__name__} "
                             f"{entry!r:.80}")  # fmt: skip
        if kind == "names" and not entry.strip():
            raise GPMSAError(f"{what}[{k}] must be a non-empty name, got {entry!r}")
    if kind == "names" and len(set(value)) != d:
        raise GPMSAError(f"{what} must be unique, got {value}")
    return tuple(str(entry) for entry in value)


def _named_index(index, names):
    """An output ``index`` given as a pandas table or Series, and ``index_names``: a table
    whose column labels are names (`_label_names`) names the index columns where ``names`` is
    None, else is read by ``names`` (its columns in that order); so does a Series' name (a
    Series of another name than the one in ``names``: GPMSAError). Labels that are no names
    (a frame's default 0, 1, ..., blank or repeated ones) name nothing: the index is read by
    position, as an array. Returns (index, names); anything else as it is."""
    series = is_series(index)
    if series:
        labels = None if index.name is None else (str(index.name),)
    else:
        labels = column_labels(index)
    if names is None:
        return index, labels if _label_names(labels) else None
    given = (names,) if isinstance(names, str) else names
    if series:
        if _label_names(labels) and len(given) == 1 and labels != tuple(given):
            raise GPMSAError(f"index is a pandas Series named {labels[0]!r:.80}, but index_names "
                             f"gives {given!r:.80}: leave index_names out to take the Series' "
                             "name, or give that name")  # fmt: skip
        return index, names
    if not (labels is None or default_labels(labels)):
        index = by_column_names(index, given, "index")
    return index, names


def by_index_names(value, names, what: str):
    """An output-index table of several columns whose labels name them (`_label_names`; a
    pandas table, as ``full_prediction``'s ``grid``) as its columns in the order of ``names``
    (the simulation index's, ``SimData.index_names``): GPMSAError naming ``what`` where the
    labels are other names. Anything else, or ``names`` None: as it is (by position)."""
    labels = column_labels(value)
    if names is None or labels is None or len(labels) < 2 or not _label_names(labels):
        return value
    return value.iloc[:, column_order(labels, [str(n) for n in names], what)]


def _index_tables(index, n: int) -> tuple[object, tuple | None]:
    """An ObsData ``index`` (one grid for every experiment, or a list of one per experiment)
    with its pandas tables as arrays, and per experiment (``n``) the column labels of a table
    of several columns that names them (`_label_names`), else None; None where no table does.
    The labels order the columns by the simulation index's names (`ObsData.output_grids`)."""

    def one(g):
        labels = column_labels(g)
        if labels is None:
            return g, None
        named = len(labels) > 1 and _label_names(labels)
        return g.to_numpy(), (labels if named else None)

    if isinstance(index, (list, tuple)):
        pairs = [one(g) for g in index]
        index, labels = [g for g, _ in pairs], tuple(lb for _, lb in pairs)
    else:
        index, label = one(index)
        labels = (label,) * n
    return index, (labels if any(lb is not None for lb in labels) else None)


def _label_names(labels: tuple[str, ...] | None) -> bool:
    """Whether a table's or Series' ``labels`` name an index's columns: not a frame's default
    labels '0', '1', ..., none blank, none twice."""
    if labels is None or default_labels(labels):
        return False
    return all(s.strip() for s in labels) and len(set(labels)) == len(labels)


def _index(index, n: int, name: str) -> np.ndarray | None:
    """The simulation output grid: finite and strictly increasing (l,) (the basis and the mean
    are interpolated along it), or points of several columns (l, d), finite and distinct,
    spanning d dimensions (interpolated on their triangulation: ``index_points``)."""
    if index is None:
        return None
    arr = as_float(index, name)
    if arr.ndim == 2 and arr.shape[0] == n and arr.shape[1] > 1:
        check_finite(arr, name)
        index_points.check_points(arr, name)
        return arr
    if arr.ndim > 1 and sorted(arr.shape)[-2] > 1 and arr.size != n:
        raise GPMSAError(multi_column_index(name, arr.shape, n))
    arr = arr.reshape(-1)
    if arr.size != n:
        raise GPMSAError(f"{name} must have {n} entries (one per output column), got {arr.size}")
    check_finite(arr, name)
    check_increasing(arr, name)
    return arr


def multi_column_index(name: str, shape: tuple, n: int) -> str:
    """The message for an output index of a shape that is neither one grid (l,) nor one point
    per output value (l, d) (SEPIA's y_ind of (time, angle) pairs)."""
    return (
        f"{name} must be one output grid ({n},) or one point per output value ({n}, d), got "
        f"shape {tuple(shape)}" + ("; SEPIA's (d, l) layout: pass its transpose"
                                   if len(shape) == 2 and shape[1] == n else "")
    )  # fmt: skip


def check_increasing(grid: np.ndarray, name: str) -> None:
    """GPMSAError unless the output grid ``grid`` (l,) is strictly increasing (np.interp, which
    maps the basis and the mean onto other grids, silently misreads any other order)."""
    step = np.flatnonzero(~(np.diff(grid) > 0))
    if step.size:
        k = int(step[0])
        a, b = float(grid[k]), float(grid[k + 1])
        raise GPMSAError(
            f"{name} must be strictly increasing, got {a!r} then {b!r} at positions {k}, {k + 1};"
            " sort the output columns (the index and the columns of y together)"
        )


def _check_spans(arr: np.ndarray, name: str, names) -> None:
    """GPMSAError naming a design column that is constant (its span within 1e-12 of its largest
    magnitude, so that a column in small units, e.g. a permeability in m^2, still varies) or
    whose range overflows float64."""
    with np.errstate(over="ignore", invalid="ignore"):
        span = arr.max(axis=0) - arr.min(axis=0)
    for j in range(arr.shape[1]):
        label = names[j] if names is not None and len(names) > j else f"{name}[:, {j}]"
        col = arr[:, j]
        if not np.isfinite(span[j]):
            raise GPMSAError(f"design column {label} spans [{col.min()}, {col.max()}]: its width "
                             "overflows float64; rescale it (e.g. other units)")  # fmt: skip
        if span[j] <= 1e-12 * float(np.abs(col).max()):  # relative: small units are fine
            if span[j] == 0:
                dummy = (" (a dummy x, as SEPIA's 0.5 for a simulator without known inputs: "
                         "leave x out, SimData(t=..., y=...))") if name == "x" else ""  # fmt: skip
                raise GPMSAError(
                    f"design column {label} is constant ({col[0]}); every input must vary{dummy}"
                )
            raise GPMSAError(
                f"design column {label} varies by only {span[j]:.3g} around {col.mean():.6g} "
                "(within 1e-12 of its size, near float64's resolution there); subtract an "
                "offset or rescale it"
            )


RANGE_COVER_MIN = 0.1
"""A design column spanning less than this fraction of its given range (``SimData(x_range=,
t_range=)``) draws a ``DomainWarning``. Measured (30 runs of y = sin 4x + cos 3t + x t, x's
range widened, 2,000 sweeps, 3 designs; held-out rms error, y's sd 0.70): 0.018-0.031 with the
design's own range, 0.032-0.049 at 10 %, 0.09-0.12 at 7 %, 0.29-0.64 at 5 %, 0.50-0.66 at 3 %,
0.68 at 1 %, 0.70 at 0.1 % (the input ignored): to correlate over the sliver rho = exp(-beta/4)
must reach about 1e-8 at 10 % (the fits found 3e-8), 1e-30 at 5 %, which the sampler's steps on
rho do not. A design on part of a physical range (a third, a quarter) is normal and silent; a
unit mistake (mm for m, 1e-3; a range of 1e12 for a design in [0, 1]) lies far below."""


def _range_table(value, names: tuple[str, ...], attr: str):
    """A pandas DataFrame given as ``x_range`` / ``t_range`` read by its labels, as SimData
    reads its tables (never by position): columns that name inputs (SEPIA's (2, d) layout, each
    column (min, max)) or an index that names them (one (min, max) row per input), as a dict
    name -> (min, max); a table whose labels name no input as it is (its rows in column order).
    GPMSAError naming ``attr`` for a table naming an input twice."""
    labels = column_labels(value)
    if labels is None:
        return value
    rows = tuple(str(r) for r in value.index)
    for found, by_column in ((labels, True), (rows, False)):
        if found and all(n in names for n in found):
            if len(set(found)) != len(found):
                raise GPMSAError(f"{attr} names an input twice: {list(found)}")
            arr = value.to_numpy()
            return {n: arr[:, k] if by_column else arr[k] for k, n in enumerate(found)}
    return value


def _sepia_layout(rows: list, arr: np.ndarray) -> bool:
    """Whether ``rows``, a square (2, 2) range matrix's (min, max) rows (`_ranges`), fail for the
    design ``arr`` (m, 2) while their transpose (SEPIA's layout: a row of mins, a row of maxs)
    holds it, each column within finite min < max."""
    if len(rows) != 2 or any(not isinstance(r, np.ndarray) or r.shape != (2,) for r in rows):
        return False
    mat = np.array(rows)
    lo, hi = arr.min(axis=0), arr.max(axis=0)

    def holds(m: np.ndarray) -> bool:
        return bool(np.all(np.isfinite(m)) and np.all(m[:, 0] <= lo) and np.all(hi <= m[:, 1]))

    return not holds(mat) and holds(mat.T) and bool(np.all(mat.T[:, 0] < mat.T[:, 1]))


def _ranges(value, arr: np.ndarray, names: tuple[str, ...], cats: tuple[int, ...], attr: str):
    """``SimData``'s ``x_range`` / ``t_range`` as one (min, max) or None per column of ``arr``
    (None where no column is given); GPMSAError naming the column for a range that is not two
    finite numbers min < max (a width float64 holds), that a design column leaves, or that is
    given for a categorical column (whose unit scale is its levels')."""
    if value is None:
        return None
    d = arr.shape[1]
    value = _range_table(value, names, attr)
    sepia = False  # a square (2, 2) matrix may be SEPIA's layout, which its shape cannot tell
    if isinstance(value, dict):
        rows = [None] * d
        for name, pair in value.items():
            if name not in names:
                raise GPMSAError(f"{attr}: {name!r} is not a column; the columns are {names}")
            rows[names.index(name)] = pair
    elif isinstance(value, (list, tuple)) and len(value) == d and any(r is None for r in value):
        rows = list(value)  # as SimData stores it: one (min, max) or None per column
    else:
        mat = as_float(value, attr)
        if d == 1 and mat.shape == (2,):  # one column: its (min, max) alone
            mat = mat.reshape(1, 2)
        if mat.ndim != 2 or mat.shape != (d, 2):
            hint = " (SEPIA's (2, {d}) layout: transpose it)" if mat.shape == (2, d) else ""
            raise GPMSAError(
                f"{attr} must be ({d}, 2), one (min, max) per column, or a dict name -> "
                f"(min, max); got shape {mat.shape}{hint.format(d=d)}"
            )
        rows = list(mat)
        sepia = _sepia_layout(rows, arr)  # named where its transpose would hold the design
    hint = " (SEPIA's (2, 2) layout, mins then maxs? transpose it)" if sepia else ""
    out = []
    for j, pair in enumerate(rows):
        if pair is None:
            out.append(None)
            continue
        label = f"{attr}[{names[j]}]"
        lo_hi = as_float(pair, label)
        if lo_hi.shape != (2,):
            raise GPMSAError(f"{label} must be (min, max), got {pair!r}")
        lo, hi = float(lo_hi[0]), float(lo_hi[1])
        with np.errstate(over="ignore", invalid="ignore"):
            width = hi - lo
        tiny = np.finfo(float).tiny * max(1.0, abs(lo), abs(hi))
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise GPMSAError(
                f"{label} = ({lo!r}, {hi!r}) must be finite numbers with min < max{hint}"
            )
        if not (np.isfinite(width) and width > tiny):
            raise GPMSAError(f"{label} = ({lo!r}, {hi!r}): the width {width!r} is not a finite, "
                             "normal number; rescale the column")  # fmt: skip
        if j in cats:
            raise GPMSAError(f"{label}: {names[j]} is categorical; its unit scale is its levels', "
                             "give no range for it")  # fmt: skip
        col_lo, col_hi = float(arr[:, j].min()), float(arr[:, j].max())
        a, b, c, d = numbers_text(col_lo, col_hi, lo, hi)
        if col_lo < lo or col_hi > hi:
            raise GPMSAError(
                f"design column {names[j]} spans [{a}, {b}], outside its {attr} [{c}, {d}]: the "
                f"range must hold every run{hint}"
            )
        if (col_hi - col_lo) < RANGE_COVER_MIN * width:
            warnings.warn(
                f"design column {names[j]} spans [{a}, {b}], "
                f"{numbers_text((col_hi - col_lo) / width, RANGE_COVER_MIN, digits=3)[0]} of its "
                f"{attr} [{c}, {d}] (less than "
                f"{RANGE_COVER_MIN:g}): the runs fill a sliver of the unit interval, where the "
                "fit resolves the input poorly (below 0.05 it ignores it) and the emulator "
                "extrapolates over the rest; check the range's units, or give the range the "
                "design was drawn for",
                DomainWarning,
                stacklevel=user_stacklevel(),
            )
        out.append((lo, hi))
    return tuple(out) if any(r is not None for r in out) else None


def _check_resolution(y: np.ndarray, sd: float) -> None:
    """GPMSAError when the outputs' spread ``sd`` (`output_scale`) is within 1e-13 of the
    largest magnitude of a column that varies: float64 then holds y to about 2e-3 of its spread
    or coarser (y = 1e9 + 1e-7 f kept 3 distinct values of 30 runs; y = 1 + 1e-14 f, 27).
    y = 1e9 + 1e-3 f (6.5e-13) still calibrates as y = f does (t 0.307 +- 0.024 against 0.309
    +- 0.018). A constant column has nothing to round, whatever its size."""
    varying = y[:, np.ptp(y, axis=0) > 0]
    big = float(np.max(np.abs(varying)))
    if sd <= 1e-13 * big:
        raise GPMSAError(
            f"y varies by only sd {sd:.3g} around values up to {big:.6g} (within 1e-13 of their "
            f"size, near float64's resolution there: {np.unique(varying).size} distinct values "
            f"in {varying.size}); subtract the offset before the values are rounded (in the "
            "simulator or its output file), or rescale y"
        )


RANK_TOL = 1e-8
"""A design whose centred unit-scale columns [x, t] have a singular value below this fraction
of the largest is rank deficient (`_check_rank`)."""


def _check_rank(x: np.ndarray, t: np.ndarray, x_names, t_names) -> None:
    """GPMSAError when one design column is (to ``RANK_TOL``) a linear function of the others,
    e.g. t1 = 2 t0 + 1: the runs then lie on a line (plane) of the input box, the emulator never
    sees the other directions, and a calibration over the whole box reads its prior mean
    there (two collinear t: t0's sd 0.17 against 0.018 with t0 alone)."""
    design = np.hstack([x, t])
    if design.shape[1] < 2:
        return
    unit = (design - design.min(axis=0)) / (design.max(axis=0) - design.min(axis=0))
    unit = unit - unit.mean(axis=0)
    _, s, vt = np.linalg.svd(unit, full_matrices=False)
    if s[-1] > RANK_TOL * s[0]:
        return
    names = [*x_names, *t_names]
    involved = [names[j] for j in np.flatnonzero(np.abs(vt[-1]) > 1e-6)]
    raise GPMSAError(
        f"the design columns {', '.join(involved)} are linearly dependent (one is a linear "
        "function of the others across all runs): the runs lie on a lower-dimensional part of "
        "the input box, so the emulator cannot tell these inputs' effects apart and would "
        "extrapolate over the rest; drop one of them (calibrate their combination) or spread "
        "the design"
    )


@dataclass(frozen=True, eq=False)
class SimData:
    """Simulation runs: inputs ``x`` (m, p), parameters ``t`` (m, q), outputs ``y`` (m, l_sim).

    ``x`` may be omitted (None) or have no columns (m, 0) when the simulator has no known inputs
    (p = 0): the emulator then correlates over ``t`` only (docs/models.md, "No known inputs").
    ``t`` and ``y`` are required (keywords, or positionally after ``x``: ``SimData(x, t, y)``).

    ``index`` (l_sim,) is the output grid of a multivariate output (None: 0..l_sim-1); it must
    be strictly increasing (a descending or unsorted grid is refused: sort the index and the
    columns of ``y`` together). An index of several columns (l_sim, d), d >= 2 (SEPIA's
    ``y_ind_sim`` of (time, angle) pairs), gives each output value its point: finite, no point
    twice, spanning d dimensions; the basis and the mean are interpolated piecewise-linearly on
    the points' Delaunay triangulation (``gpmsa.model.index_points``).
    Names (``x_names``, ``t_names``, ``y_names``) default to x0.., t0.., y0..; units
    (``x_units``, ``t_units``, ``y_units``) to "". A name is a non-blank string, a unit a
    string; a table's column label of another type (a column number, a number such as a
    wavelength, a date, a MultiIndex's tuple) is taken as its text, as a table's own labels.
    ``t_names`` may not be a reserved name (lamOs, lamVz, betaV, betaV[k], betaV[k,g],
    lamVz[g]: the other parameters of a calibration posterior). A 1-D ``x``, ``t`` or ``y`` is
    one column. Every entry must be a real number (strings, bools and None are refused, never
    converted); every input column must vary, and so must y over the runs (y the same in every
    run, varying only along its index, is refused: the emulator learns how it changes with x
    and t). A pandas table names its columns (read by ``*_names`` where given), a named pandas
    Series (``df["a"]``) its one column; pandas inputs of several rows must carry the same row
    labels (rows pair by position).
    ``x_categorical``, ``t_categorical``: the categorical inputs (column indices or names; None:
    none), whose values are integer level codes; see docs/categorical-and-constraints.md.
    ``x_range``, ``t_range``: the native domain the unit scale maps onto [0, 1] (SEPIA's
    ``transform_xt(x_range=, t_range=)``), instead of the design's own min/max: an array
    (p, 2) / (q, 2) of (min, max) per column, or a dict name -> (min, max) for some columns
    (the others keep the design's min/max; so does a None row); a pandas DataFrame by its
    labels where its columns (SEPIA's (2, p) layout) or its index name the inputs, else by
    position (one row per column). Each finite with min < max,
    the design inside it (else a GPMSAError naming the column), not for a categorical column.
    Stored as one ``(min, max)`` or None per column (None: no column given). A theta's uniform
    prior then covers the whole given range, and an input inside it is inside the emulator's
    domain (docs/internals.md, "The unit domain").
    ``y_scale``: how y is standardised after centring each element: "scalar" (the default,
    GPM/SA's: one sd over all outputs) or "columnwise" (SEPIA's ``standardize_y(scale=
    'columnwise')``: each output element by its own sd, for outputs of different units or
    sizes in one functional output; every column must vary). Same for a scalar output.
    ``separable``: the runs are the Cartesian product of factor designs (SEPIA's
    ``xt_sim_sep``), stored run by run in Kronecker order: True (every input its own factor,
    in column order x then t), or the factors, slowest-varying first, each an input (name or
    index into [x, t]) or a list of them, e.g. ``[["v"], ["GD"]]``; the design is checked to be
    that product (``gpmsa.model.kronecker``; docs/internals.md, "Separable designs"). Stored as
    the column groups (indices), or None.
    ``y_mean``, ``y_sd``: the output centring and scale to use instead of the runs' own (SEPIA's
    ``standardize_y(y_mean=, y_sd=)``): y_mean a number or an array (l_sim,), y_sd a positive
    number or an array (l_sim,) (each output element its own sd); finite, y_sd's square a
    normal float64 (else a GPMSAError naming the argument and the shape or value). None (the
    default): the runs' mean, and the sd ``y_scale`` says. A given y_sd is refused with
    ``y_scale="columnwise"`` (which computes each element's sd: give one or the other); a
    given y_mean goes with either. Stored as y_mean (l_sim,) and y_sd a float or (l_sim,)
    (l_sim > 1). The priors are on the standardised scale: give a scale of the order of the
    outputs' spread (docs/internals.md, "The output scale").
    ``index_names``, ``index_units``: labels of the output index's columns for figures and
    ``gpmsa info`` (SEPIA has none): one string per column, a single string for a one-column
    index (``index`` (l_sim,), or None: 0..l_sim-1); names non-empty and unique. None (the
    default): "output index" ("output index[:, k]" per column of (l_sim, d)), no unit. An
    index given as a pandas table with named columns, or a named Series, names its columns
    where ``index_names`` is None (else its columns are read by those names; a Series of
    another name is refused); labels that are no names (a frame's default 0, 1, ..., blank
    or repeated ones) name nothing. Not for a scalar output. Labels only: the fit, its draws
    and ``model_sha256`` are the same without.
    """

    x: np.ndarray | None = None
    t: np.ndarray | None = None
    y: np.ndarray | None = None
    index: np.ndarray | None = None
    x_names: tuple[str, ...] | None = None
    t_names: tuple[str, ...] | None = None
    y_names: tuple[str, ...] | None = None
    x_units: tuple[str, ...] | None = None
    t_units: tuple[str, ...] | None = None
    y_units: tuple[str, ...] | None = None
    x_categorical: Sequence[int | str] | None = None
    t_categorical: Sequence[int | str] | None = None
    x_range: np.ndarray | Sequence | dict | None = None
    t_range: np.ndarray | Sequence | dict | None = None
    y_scale: str = "scalar"
    separable: bool | Sequence | None = None
    y_mean: float | np.ndarray | None = None
    y_sd: float | np.ndarray | None = None
    index_names: str | Sequence[str] | None = None
    index_units: str | Sequence[str] | None = None

    if TYPE_CHECKING:  # what the constructor takes (the fields above: what it stores)

        def __init__(
            self,
            x: ArrayLike | None = None,
            t: ArrayLike | None = None,
            y: ArrayLike | None = None,
            index: ArrayLike | None = None,
            x_names: Sequence[str] | None = None,
            t_names: Sequence[str] | None = None,
            y_names: Sequence[str] | None = None,
            x_units: Sequence[str] | None = None,
            t_units: Sequence[str] | None = None,
            y_units: Sequence[str] | None = None,
            x_categorical: Sequence[int | str] | None = None,
            t_categorical: Sequence[int | str] | None = None,
            x_range: ArrayLike | Sequence | dict | None = None,
            t_range: ArrayLike | Sequence | dict | None = None,
            y_scale: str = "scalar",
            separable: bool | Sequence | None = None,
            y_mean: ArrayLike | None = None,
            y_sd: ArrayLike | None = None,
            index_names: str | Sequence[str] | None = None,
            index_units: str | Sequence[str] | None = None,
        ) -> None: ...

    def __post_init__(self) -> None:
        check_same_rows({"x": self.x, "t": self.t, "y": self.y})
        for part in ("x", "t", "y", "index"):
            for kind in ("names", "units"):
                attr = f"{part}_{kind}"
                object.__setattr__(self, attr, _labels(getattr(self, attr), attr, kind))
        index, index_names = _named_index(self.index, self.index_names)
        object.__setattr__(self, "index", index)
        object.__setattr__(self, "index_names", index_names)
        for part in ("x", "t", "y"):  # a table: its columns by name, never by position
            value, names = getattr(self, part), getattr(self, f"{part}_names")
            labels = column_labels(value)
            if names is None and is_series(value) and value.name is not None:
                object.__setattr__(self, f"{part}_names", (str(value.name),))  # df["a"]: "a"
            elif labels is not None and names is None:
                object.__setattr__(self, f"{part}_names", labels)
            elif labels is not None:
                value = by_column_names(getattr(self, part), tuple(names), part)
                object.__setattr__(self, part, value)
        if self.t is None or self.y is None:
            raise GPMSAError(
                "SimData needs t (m, q) and y (m, l_sim); only x may be omitted (no known inputs)"
            )
        t = as_matrix(self.t, "t")
        y = as_matrix(self.y, "y")
        x = np.empty((t.shape[0], 0)) if self.x is None else as_matrix(self.x, "x", no_columns=True)
        m = x.shape[0]
        if t.shape[0] != m or y.shape[0] != m:
            raise GPMSAError(
                f"x, t and y must have the same number of rows (runs), got x {x.shape}, "
                f"t {t.shape}, y {y.shape}"
            )
        p, q = x.shape[1], t.shape[1]
        if m < p + q + 2:
            raise GPMSAError(
                f"need at least p + q + 2 = {p + q + 2} simulation runs for "
                f"{_count(p + q, 'input')}, got {m}"
            )
        _check_spans(x, "x", self.x_names)
        _check_spans(t, "t", self.t_names)
        if np.ptp(y) == 0.0:
            raise GPMSAError(f"y is constant ({y[0, 0]}); the simulation output must vary")
        if not np.any(np.ptp(y, axis=0) > 0.0):  # varying along the index only
            raise GPMSAError(
                f"y is the same in every run ({m} runs of {y.shape[1]} output values, none of "
                "which varies over the runs): the emulator learns how the output changes with "
                "x and t; check that each run's own output was read (not one run's for all)"
            )
        _check_resolution(y, output_scale(y))
        if not (isinstance(self.y_scale, str) and self.y_scale in Y_SCALES):
            raise GPMSAError(f"y_scale must be one of {Y_SCALES}, got {self.y_scale!r:.80}")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "index", _index(self.index, y.shape[1], "index"))
        d = 1 if self.index is None or self.index.ndim == 1 else self.index.shape[1]
        for attr in ("index_names", "index_units"):
            labels = _index_labels(getattr(self, attr), d, y.shape[1], attr)
            object.__setattr__(self, attr, labels)
        object.__setattr__(self, "x_names", _names(self.x_names, p, "x", "x_names"))
        object.__setattr__(self, "t_names", _names(self.t_names, q, "t", "t_names"))
        check_parameter_names(self.t_names)
        if shared := sorted(set(self.x_names) & set(self.t_names)):
            raise GPMSAError(
                f"x_names and t_names must not share a name (an input is either known or "
                f"calibrated), got {shared} in both"
            )
        object.__setattr__(self, "y_names", _names(self.y_names, y.shape[1], "y", "y_names"))
        object.__setattr__(self, "x_units", _units(self.x_units, p, "x_units"))
        object.__setattr__(self, "t_units", _units(self.t_units, q, "t_units"))
        object.__setattr__(self, "y_units", _units(self.y_units, y.shape[1], "y_units"))
        if self.y_scale == "columnwise" and self.y_sd is not None:
            raise GPMSAError(
                "y_sd is given and y_scale='columnwise' asks for each output element's own sd: "
                "give one or the other (a y_sd array (l_sim,) scales each element by its own)"
            )
        if self.y_scale == "columnwise":
            column_scales(y, self.y_names)  # refused here, not at the fit
        mean, sd = _given_scale(self.y_mean, self.y_sd, y)
        object.__setattr__(self, "y_mean", mean)
        object.__setattr__(self, "y_sd", sd)
        for arr, attr, names in ((x, "x_categorical", self.x_names),
                                 (t, "t_categorical", self.t_names)):  # fmt: skip
            cols = categorical.columns(getattr(self, attr), names, attr)
            categorical.check_integer_levels(arr, cols, names, attr[0])
            object.__setattr__(self, attr, cols)
        for part, arr in (("x", x), ("t", t)):
            attr = f"{part}_range"
            names, cats = getattr(self, f"{part}_names"), getattr(self, f"{part}_categorical")
            object.__setattr__(self, attr, _ranges(getattr(self, attr), arr, names, cats, attr))
        _check_rank(x, t, self.x_names, self.t_names)
        names = self.x_names + self.t_names  # a separable design: its product checked here
        if (groups := kronecker.parse_groups(self.separable, names)) is not None:
            kronecker.structure(np.hstack([x, t]), groups, names)
        object.__setattr__(self, "separable", groups)

    def __repr__(self) -> str:
        """Concise: the runs, each input's name and range, the output's length and range, and
        its index's columns' ranges (named where ``index_names`` names them)."""
        grid = _index_text(self.index, self.index_names, self.l_sim)
        return (f"SimData({self.m} runs; x: {_columns_text(self.x, self.x_names)}; "
                f"t: {_columns_text(self.t, self.t_names)}; y: {_count(self.l_sim, 'output')} "
                f"{_span(self.y)}{grid})")  # fmt: skip

    @property
    def m(self) -> int:
        """Number of simulation runs."""
        return self.x.shape[0]

    @property
    def p(self) -> int:
        """Number of known inputs."""
        return self.x.shape[1]

    @property
    def q(self) -> int:
        """Number of calibration parameters."""
        return self.t.shape[1]

    @property
    def l_sim(self) -> int:
        """Length of one simulation output."""
        return self.y.shape[1]

    @property
    def grid(self) -> np.ndarray:
        """Output index grid (l_sim,) or points (l_sim, d): ``index`` or 0..l_sim-1."""
        return self.index if self.index is not None else np.arange(self.l_sim, dtype=np.float64)

    @property
    def levels(self) -> categorical.Levels:
        """Per column of [x, t]: the training levels of a categorical input, None otherwise."""
        return categorical.levels_of(self.x, self.t, self.x_categorical, self.t_categorical)


def values_digest(x, experiments) -> str:
    """SHA-256 of observations' inputs x (n, p) and outputs (one array per experiment), as
    float64 with their shapes."""
    return _arrays_digest([x, *experiments])


def _arrays_digest(parts, tail: str = "") -> str:
    """SHA-256 of arrays (each numbered, with its shape, as little-endian float64), then
    ``tail``."""
    h = hashlib.sha256()
    for k, part in enumerate(parts):
        arr = np.ascontiguousarray(part, dtype="<f8")
        h.update(f"{k}:{arr.shape}".encode())
        h.update(arr.tobytes())
    h.update(tail.encode())
    return h.hexdigest()


def _index_points(index: list, ys: list[np.ndarray], names: list[str]) -> list[np.ndarray]:
    """Each experiment's output index of several columns (l_j, d), d >= 2 the same for all
    (SEPIA's y_ind_obs of (time, angle) pairs), finite, one point per value; in any order."""
    grids = [as_float(g, name) for g, name in zip(index, names, strict=True)]
    k = next(j for j, g in enumerate(grids) if g.ndim == 2 and g.shape[1] > 1)
    d = grids[k].shape[1]
    for j, (g, e, name) in enumerate(zip(grids, ys, names, strict=True)):
        if g.ndim != 2 or g.shape[1] != d:
            raise GPMSAError(
                f"{name} has shape {g.shape}: every experiment's index must be points of the "
                f"same columns, (l_j, {d}) as {names[k]}'s"
            )
        if g.shape[0] != e.size:
            raise GPMSAError(f"{name} has {g.shape[0]} points, y[{j}] has {e.size}")
        check_finite(g, name)
    return grids


@dataclass(frozen=True, eq=False)
class ObsData:
    """Field observations: known inputs ``x`` (n, p) and outputs ``y`` in native units.

    ``y`` is (n, l_obs), or a list of n 1-D arrays of differing lengths ("ragged"), each with its
    ``index`` grid (a list of arrays; a single array applies to every experiment; None means the
    simulation grid). An observation grid may be in any order (each point is interpolated on the
    simulation grid, which is increasing), but must lie within the simulation grid (a scalar
    output's: None, or its one point); the columns of ``y`` follow its order. With a simulation
    index of several columns (l_sim, d), each experiment's index is its points (l_j, d) (a list,
    ragged too; one (l, d) array applies to every experiment), within the simulation points'
    convex hull; a pandas table whose column labels name them is read by the simulation
    index's names in any column order (`output_grids`), as ``SimData`` reads its own.
    ``precision`` is the observation-error precision in native units
    (1/unit^2): None (identity in standardised units, GPM/SA's default), a scalar (the same for
    every experiment), or per experiment a scalar, an (l_j,) vector (one precision per value:
    the diagonal of the matrix) or an (l_j, l_j) matrix (a list, or an array of shape (n,),
    (n, l) or (n, l, l)). Every entry must be a real number (strings, bools and None are
    refused, never converted). ``x`` and ``y`` given as pandas objects of several rows must carry
    the same row labels (rows pair by position).

    ``x`` may be omitted (None) or have no columns (n, 0) for a simulator without known inputs
    (p = 0): the n experiments are then replicate observations of the one experiment (as
    SEPIA's dummy x); each row of a 2-D ``y`` (each array of a list) is one experiment, a 1-D
    ``y`` is one. ``y`` is required.
    """

    x: np.ndarray | None = None
    y: np.ndarray | list[np.ndarray] | None = None
    index: np.ndarray | list[np.ndarray] | None = None
    precision: np.ndarray | list[np.ndarray] | None = None
    experiments: list[np.ndarray] = field(init=False, repr=False)
    grids: list[np.ndarray | None] = field(init=False, repr=False)
    precisions: list[np.ndarray] | None = field(init=False, repr=False)
    x_columns: tuple[str, ...] | None = field(init=False, repr=False)
    y_columns: tuple[str, ...] | None = field(init=False, repr=False)
    index_columns: tuple[tuple[str, ...] | None, ...] | None = field(init=False, repr=False)

    if TYPE_CHECKING:  # what the constructor takes (the fields above: what it stores)

        def __init__(
            self,
            x: ArrayLike | None = None,
            y: ArrayLike | Sequence[ArrayLike] | None = None,
            index: ArrayLike | Sequence[ArrayLike] | None = None,
            precision: ArrayLike | Sequence[ArrayLike] | None = None,
        ) -> None: ...

    def __post_init__(self) -> None:
        check_same_rows({"x_obs": self.x, "y_obs": self.y})
        object.__setattr__(self, "x_columns", column_labels(self.x))
        object.__setattr__(self, "y_columns", column_labels(self.y))
        if self.y is None:
            raise GPMSAError("ObsData needs y (n, l_obs), the observed outputs; only x may be "
                             "omitted (no known inputs)")  # fmt: skip
        if self.x is None:
            ys = self._experiments(self.y, None)
            x = np.empty((len(ys), 0))
        else:
            x = as_matrix(self.x, "x_obs", no_columns=True)
            ys = self._experiments(self.y, x.shape[0])
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "experiments", ys)
        index, labels = _index_tables(self.index, len(ys))
        object.__setattr__(self, "index_columns", labels)
        object.__setattr__(self, "grids", self._grids(index, ys))
        object.__setattr__(self, "precisions", self._precisions(self.precision, ys))
        ragged = len({len(e) for e in ys}) > 1
        object.__setattr__(self, "y", ys if ragged else np.stack(ys))

    def inputs(self, x_names) -> np.ndarray:
        """x (n, p) with its columns in the order of ``x_names``: as given, or, for inputs given
        as a table with named columns (``x_columns``), by name; GPMSAError when those names are
        not ``x_names``."""
        if self.x_columns is None:
            return self.x
        return self.x[:, column_order(self.x_columns, x_names, "x_obs")]

    def outputs(self, y_names=None) -> list[np.ndarray]:
        """Every experiment's y (``experiments``); for y given as a table with named columns
        (``y_columns``) and no index, its columns in the order of ``y_names`` (by name, as
        ``gpmsa.calibrate`` reads a table y_obs; GPMSAError when those names are not
        ``y_names``). A table's default labels 0, 1, ... are no names: by position; with an
        index the columns follow it, by position (GPMSAError where they are ``y_names`` in
        another order: ambiguous); ``y_names`` None: as given."""
        order = self._output_order(y_names)
        return self.experiments if order is None else [e[order] for e in self.experiments]

    def output_grids(self, index_names=None) -> list[np.ndarray | None]:
        """Every experiment's index (``grids``); where an experiment's index of several columns
        was given as a table with named columns (``index_columns``), its columns in the order
        of ``index_names`` (the simulation index's, ``SimData.index_names``): by name, as
        ``SimData`` reads an index table (GPMSAError when those labels are other names). Arrays
        and tables of a frame's default labels 0, 1, ...: by position; ``index_names`` None:
        as given."""
        if self.index_columns is None or index_names is None:
            return self.grids
        names = [str(n) for n in index_names]
        out = []
        for j, (g, labels) in enumerate(zip(self.grids, self.index_columns, strict=True)):
            if labels is None or g is None or g.ndim != 2 or list(labels) == names:
                out.append(g)
            else:
                out.append(g[:, column_order(labels, names, f"ObsData index[{j}]")])
        return out

    def output_precisions(self, y_names=None) -> list[np.ndarray] | None:
        """``precisions`` with their rows and columns in the order `outputs` gives y's."""
        order = self._output_order(y_names)
        if order is None or self.precisions is None:
            return self.precisions
        return [lam[np.ix_(order, order)] for lam in self.precisions]

    def _output_order(self, y_names) -> list[int] | None:
        """The positions of ``y_names`` among y's named columns (`outputs`); None: as given."""
        labels = self.y_columns
        if labels is None or y_names is None:
            return None
        if default_labels(labels):
            return None
        names = [str(n) for n in y_names]
        if any(g is not None for g in self.grids):
            in_order = list(range(len(names)))  # as the names, a CSV header's blanks aside too
            if same_names(labels, names) and column_order(labels, names, "y") != in_order:
                raise GPMSAError(
                    f"ObsData y has the columns {list(labels)}, the simulation outputs' names in "
                    "another order, and an index, whose order its columns follow: give the "
                    "columns in the index's order, or y without the index (read by name)"
                )
            return None
        return column_order(labels, names, "ObsData y")

    def values_digest(self, x_names=None, y_names=None) -> str:
        """SHA-256 of x and every experiment's y (`values_digest`): what ``gpmsa.calibrate``
        records of its observations' values. ``x_names``: x with its columns in that order
        (`inputs`: a table's by name, as calibrate reads x_obs); ``y_names``: likewise y
        (`outputs`); None: as given."""
        x = self.x if x_names is None else self.inputs(x_names)
        return values_digest(x, self.outputs(y_names))

    def digest(self) -> str:
        """SHA-256 of the observations (x, every experiment's y, grid and precision, as float64):
        a joint fit records it, so a prediction conditioned on other observations is refused."""
        parts = [self.x, *self.experiments, *(g for g in self.grids if g is not None)]
        parts += self.precisions or []
        return _arrays_digest(parts, f"grids:{[g is None for g in self.grids]}")

    @staticmethod
    def _experiments(y, n: int | None) -> list[np.ndarray]:
        """y as one 1-D array per experiment; ``n``: the experiments x_obs gives (None: no x,
        a 1-D y is one experiment)."""
        y = tensor_values(y)  # (np.ndim reads a list of tensors that record gradients)
        if isinstance(y, (list, tuple)) and any(np.ndim(e) == 1 and size_of(e) > 1 for e in y):
            ys = [as_float(e, f"y_obs[{j}]").reshape(-1) for j, e in enumerate(y)]
        else:
            arr = as_float(y, "y_obs")
            if arr.ndim == 1:
                arr = arr[:, None] if arr.size == n else arr[None, :]
            if arr.ndim != 2:
                raise GPMSAError(
                    f"y_obs must be (n, l_obs) or a list of 1-D arrays, got {arr.shape}"
                )
            ys = list(arr)
            if not ys:  # np.stack of none raised numpy's "need at least one array to stack"
                raise GPMSAError(
                    f"y_obs has no experiments (shape {arr.shape}): ObsData needs at least one "
                    "observation (a study's every model needs its own)"
                )
        if n is not None and len(ys) != n:
            raise GPMSAError(f"y_obs must have one row per x_obs row ({n}), got {len(ys)}")
        for j, e in enumerate(ys):
            if e.size == 0:
                raise GPMSAError(f"y_obs[{j}] is empty")
            check_finite(e, f"y_obs[{j}]")
        return ys

    @staticmethod
    def _grids(index, ys: list[np.ndarray]) -> list[np.ndarray | None]:
        if index is None:
            return [None] * len(ys)
        per_experiment = isinstance(index, (list, tuple)) and len(index) > 0
        if per_experiment and len(index) == len(ys):
            if any(np.ndim(g) == 2 and min(np.shape(g)) > 1 for g in index):
                return _index_points(list(index), ys, [f"index[{j}]" for j in range(len(ys))])
        per_experiment = per_experiment and all(np.ndim(g) == 1 for g in index)
        if per_experiment and len(index) != len(ys) and all(size_of(g) == 1 for g in index):
            per_experiment = False  # one grid as a column of 1-point lists
        rows = isinstance(index, np.ndarray) and index.ndim == 2 and min(index.shape) > 1
        if rows and all(e.size == index.shape[0] != index.shape[1] for e in ys):
            return _index_points([index] * len(ys), ys, ["index"] * len(ys))  # SEPIA's y_ind
        if per_experiment or rows:  # an (n, l) array: a grid per experiment; (l, 1): one
            if len(index) != len(ys):
                raise GPMSAError(
                    f"index has {len(index)} grids for {len(ys)} experiment(s): give one "
                    "grid per experiment, or one grid for all"
                )
            grids = [as_float(g, f"index[{j}]").reshape(-1) for j, g in enumerate(index)]
        else:
            g = as_float(index, "index")
            if g.ndim > 1 and sorted(g.shape)[-2] > 1:
                raise GPMSAError(f"index must be one grid (l,) or one per experiment, got "
                                 f"shape {g.shape}")  # fmt: skip
            grids = [g.reshape(-1)] * len(ys)
        for j, (g, e) in enumerate(zip(grids, ys, strict=True)):
            name = f"index[{j}]" if per_experiment or rows else "index"
            if g.size != e.size:
                raise GPMSAError(f"{name} has {g.size} points, y[{j}] has {e.size}")
            check_finite(g, name)
        return grids

    @staticmethod
    def _precisions(precision, ys: list[np.ndarray]) -> list[np.ndarray] | None:
        if precision is None:
            return None
        if not isinstance(precision, (list, tuple)) and np.ndim(precision) == 0:
            precision = [precision] * len(ys)  # one scalar for every experiment
        if len(precision) != len(ys):
            raise GPMSAError(
                f"precision must have one entry per experiment ({len(ys)}), got {len(precision)}"
                " (a matrix for one experiment goes in a list: [matrix])"
            )
        out = []
        for j, (lam, e) in enumerate(zip(precision, ys, strict=True)):
            lam = as_float(lam, f"precision[{j}]")
            if lam.ndim == 0:
                lam = lam * np.eye(e.size)
            elif lam.shape == (e.size,):  # one precision per value
                if not np.all(lam > 0):
                    raise GPMSAError(f"precision[{j}] must be positive, got {lam.tolist()}")
                lam = np.diag(lam)
            if lam.shape != (e.size, e.size):
                raise GPMSAError(
                    f"precision[{j}] must be a scalar, ({e.size},) or ({e.size}, {e.size}), got "
                    f"{lam.shape}"
                )
            check_finite(lam, f"precision[{j}]")
            scale = float(np.max(np.abs(lam)))  # relative: a precision in small units is fine
            if not np.allclose(lam, lam.T, atol=1e-8 * scale) or np.linalg.eigvalsh(lam).min() <= 0:
                raise GPMSAError(f"precision[{j}] must be symmetric positive definite")
            out.append(lam)
        return out

    def __repr__(self) -> str:
        """Concise: the experiments, x's columns and ranges, y's lengths and range, and whether
        an index and precisions are given."""
        names = self.x_columns or tuple(f"x_obs[:, {k}]" for k in range(self.x.shape[1]))
        lengths = sorted({e.size for e in self.experiments})
        each = f"{lengths[0]}" if len(lengths) == 1 else f"{lengths[0]} to {lengths[-1]}"
        values = np.concatenate([np.ravel(e) for e in self.experiments])
        d = max((g.shape[1] for g in self.grids if index_points.is_points(g)), default=1)
        given = [f"{k} given" + (f" ({d} columns)" if k == "index" and d > 1 else "")
                 for k in ("index", "precision") if getattr(self, k) is not None]  # fmt: skip
        return (f"ObsData({_count(self.n, 'experiment')}; x: {_columns_text(self.x, names)}; "
                f"y: {each} value(s) each {_span(values)}"
                f"{''.join(f'; {k}' for k in given)})")  # fmt: skip

    @property
    def n(self) -> int:
        """Number of experiments."""
        return self.x.shape[0]
