"""An emulator's output index as ``gpmsa info`` gives it: one line for a person, a record for
``--json`` (an emulator file, and each model of a study file)."""

from __future__ import annotations

from gpmsa.cli.text import numbers, safe


def index_text(emulator) -> str | None:
    """The output index for a person (the text of ``gpmsa info``'s "output index:" line): an
    index of several columns always (its points, columns, labels and spans), one column only
    where ``SimData(index_names=, index_units=)`` labelled it; None otherwise."""
    grid = emulator.standardizer.grid
    labels = _labels_text(emulator)
    if grid.ndim == 2:  # an output index of several columns (SEPIA's (l, d) y_ind)
        spans = " x ".join("[{}, {}]".format(*numbers(float(c.min()), float(c.max())))
                           for c in grid.T)  # fmt: skip
        return (f"{grid.shape[0]} points in {grid.shape[1]} columns{labels}, "
                f"{spans} (interpolated on their triangulation)")  # fmt: skip
    if labels:
        span = "[{}, {}]".format(*numbers(float(grid.min()), float(grid.max())))
        return f"{grid.shape[0]} points{labels}, {span}"
    return None


def index_record(emulator) -> dict | None:
    """The output index for ``--json`` (a multivariate output, l_sim > 1; else None): its
    points, columns, each column's [min, max], and the names and units given (or null)."""
    if emulator.l_sim <= 1:
        return None
    columns = emulator.standardizer.grid.reshape(emulator.l_sim, -1)
    ranges = [[float(c.min()), float(c.max())] for c in columns.T]
    return {
        "points": int(columns.shape[0]),
        "columns": int(columns.shape[1]),
        "ranges": ranges,
        "names": _listed(emulator.index_names),
        "units": _listed(emulator.index_units),
    }


def _listed(labels) -> list[str] | None:
    """``labels`` (a tuple or None) as ``--json`` gives them: a list, or null."""
    return None if labels is None else list(labels)


def _labels_text(emulator) -> str:
    """The output index's labels for its line, " (name [unit], ...)" (no names: "-" each);
    "" where ``SimData(index_names=, index_units=)`` gave none."""
    names, units = emulator.index_names, emulator.index_units
    if names is None and units is None:
        return ""
    d = len(names if names is not None else units)
    cells = [f"{safe(n, 60)}{' [' + safe(u, 60) + ']' if u else ''}"
             for n, u in zip(names or ("-",) * d, units or ("",) * d, strict=True)]  # fmt: skip
    return f" ({', '.join(cells)})"
