"""Categorical inputs: which columns of [x, t] are categorical, their levels, and level checks.

A categorical input takes integer levels (native units; map labels to integers first). The
standardiser maps it like any input, (level - min) / (max - min): distinct levels stay distinct
and equal levels stay exactly equal, which is all the categorical correlation
(``gpmsa.model.correlation``) looks at. Levels never seen in the simulation design are refused.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from gpmsa.errors import GPMSAError

Levels = tuple[tuple[int, ...] | None, ...]
"""Per input column of [x, t]: the sorted training levels of a categorical input, None for a
continuous one."""


def columns(spec: Sequence | None, names: tuple[str, ...], what: str) -> tuple[int, ...]:
    """Sorted column indices from ``spec``: column indices or names (None: none).

    >>> columns(["b", 0], ("a", "b", "c"), "x_categorical")
    (0, 1)
    """
    if spec is None:
        return ()
    if isinstance(spec, np.ndarray) and spec.ndim == 0:
        spec = spec.item()  # a 0-d array: its one value
    if isinstance(spec, (str, int, np.integer)):
        spec = [spec]
    elif isinstance(spec, (bytes, bytearray)) or not isinstance(spec, Iterable):
        raise GPMSAError(f"{what} must hold column indices or names, got {spec!r}")
    spec = list(spec)
    hint = _sepia_hint(what)
    out = set()
    for item in spec:
        if isinstance(item, str):
            if item not in names:
                raise GPMSAError(f"{what}: {item!r} is not an input; the inputs are {names}")
            k = names.index(item)
        elif isinstance(item, (int, np.integer)) and not isinstance(item, bool):
            if not 0 <= int(item) < len(names):
                raise GPMSAError(f"{what}: column {item} out of range [0, {len(names)}){hint}")
            k = int(item)
        else:
            raise GPMSAError(f"{what} must hold column indices or names, got {item!r}")
        if k in out:
            raise GPMSAError(f"{what} lists column {k} ({names[k]}) twice{hint}")
        out.add(k)
    return tuple(sorted(out))


def _sepia_hint(what: str) -> str:
    """Advice for SEPIA's form of ``what`` (x_cat_ind: a level count per column, 0 for a
    continuous one), which reads here as column indices."""
    sepia = f"{what[0]}_cat_ind"
    return (f" ({what} lists the categorical columns, by index or name; SEPIA's {sepia}, one "
            f"level count per column with 0 for a continuous one, is not this form: for "
            f"{sepia}=[0, 3] pass {what}=[1])")  # fmt: skip


def check_integer_levels(arr: np.ndarray, cols: tuple[int, ...], names, what: str) -> None:
    """GPMSAError naming the input unless every value of the categorical columns is an integer."""
    for k in cols:
        col = arr[:, k]
        bad = col != np.round(col)
        if bad.any():
            raise GPMSAError(
                f"{what} {names[k]} is categorical: its levels must be integers, got "
                f"{col[bad][0]!r} (map labels to integer codes first)"
            )


def levels_of(x: np.ndarray, t: np.ndarray, x_cols, t_cols) -> Levels:
    """The training levels of every column of [x, t] (None for continuous columns)."""
    out: list[tuple[int, ...] | None] = []
    for arr, cols in ((x, x_cols), (t, t_cols)):
        for k in range(arr.shape[1]):
            out.append(tuple(int(v) for v in np.unique(arr[:, k])) if k in cols else None)
    return tuple(out)


def mask(levels: Levels) -> np.ndarray | None:
    """Boolean mask (p + q,) of the categorical columns, or None when there are none."""
    m = np.array([lv is not None for lv in levels], dtype=bool)
    return m if m.any() else None


def check_levels(values: np.ndarray, levels: Levels, names: Sequence[str], what: str) -> None:
    """GPMSAError naming the input and the level when a categorical column of ``values`` (N, d,
    native, the columns of ``levels``/``names``) holds a level not seen in training."""
    for k, lv in enumerate(levels):
        if lv is None:
            continue
        new = np.setdiff1d(values[:, k], np.asarray(lv, dtype=np.float64))
        if new.size:
            level = np.format_float_positional(new[0], trim="-")  # every digit: 1.0000000001
            raise GPMSAError(
                f"{what}: categorical input {names[k]} has level {level}, never seen in "
                f"training (levels {list(lv)})"
            )


def snap_to_levels(values, levels: Sequence) -> np.ndarray:
    """``values`` (q,) with each element that has levels (a sequence; None: continuous) moved to
    its nearest level (the first of two equally near)."""
    out = np.array(values, dtype=np.float64).reshape(-1)
    for k, lv in enumerate(levels):
        if lv is not None:
            lv = np.asarray(lv, dtype=np.float64)
            out[k] = lv[np.argmin(np.abs(lv - out[k]))]
    return out


def refuse_categorical_theta(levels: Levels, p: int, names: Sequence[str], what: str) -> None:
    """GPMSAError for calibrating a categorical calibration parameter (not supported)."""
    for k, lv in enumerate(levels[p:]):
        if lv is not None:
            raise GPMSAError(
                f"{what}: calibration parameter {names[p + k]} is categorical; a categorical "
                "theta is calibrated by gpmsa.calibrate (and gpmsa.Calibrator) on the numpy "
                "(fast or not) or torch backend only (with or without a discrepancy; "
                "docs/categorical-and-constraints.md)"
            )
