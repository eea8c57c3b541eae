"""Constraints on the calibration parameters: a function of native theta that is False outside
the allowed region, which then has zero prior mass (every sampler rejects a proposal there
before computing its likelihood; the Calibrator's grid gives it zero weight)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gpmsa.errors import GPMSAError, StartRejectedError, numbers_text
from gpmsa.model.data import as_float, by_column_names, check_finite


@dataclass(frozen=True, eq=False)
class ThetaConstraint:
    """``fn(theta)`` of native theta (q,) -> bool, applied to unit-scale theta.

    t_min, t_max (q,): the native range of the design (unit 0 and 1); names: theta's names.

    >>> c = ThetaConstraint(lambda th: th[0] < th[1], np.zeros(2), np.full(2, 10.0), ("a", "b"))
    >>> c(np.array([0.1, 0.2])), c(np.array([0.3, 0.2]))
    (True, False)
    """

    fn: Callable[[np.ndarray], bool]
    t_min: np.ndarray
    t_max: np.ndarray
    names: tuple[str, ...]
    categorical: tuple[bool, ...] = ()

    def native(self, theta_unit: np.ndarray) -> np.ndarray:
        """Unit-scale theta (q,) or (k, q) -> native, the same shape; a categorical element
        (``categorical``) exactly its integer level (the unit scale's round trip can miss it by
        an ulp: 13 -> 12.999999999999998 with 24 levels)."""
        native = np.asarray(theta_unit, dtype=np.float64) * (self.t_max - self.t_min) + self.t_min
        return round_levels(native, self.categorical)

    def __call__(self, theta_unit: np.ndarray) -> bool:
        """Whether unit-scale theta (q,) is allowed; GPMSAError if ``fn`` fails or is not bool."""
        return self._verdict(self.native(theta_unit))

    def allows(self, native: np.ndarray) -> np.ndarray:
        """(k,) bool: whether each row of native theta (k, q) is allowed (``fn`` called once
        per row, on a copy); GPMSAError as ``__call__``.

        >>> c = ThetaConstraint(lambda th: th[0] < th[1], np.zeros(2), np.ones(2), ("a", "b"))
        >>> c.allows(np.array([[1.0, 2.0], [3.0, 2.0]])).tolist()
        [True, False]
        """
        return np.array([self._verdict(row) for row in native], dtype=bool)

    def _verdict(self, native: np.ndarray) -> bool:
        """``fn`` at native theta (q,), checked."""
        try:
            ok = self.fn(native.copy())
        except Exception as exc:
            at = self.describe(native)
            raise GPMSAError(f"the theta constraint failed at {at}: {exc}") from exc
        if not isinstance(ok, (bool, np.bool_)):
            raise GPMSAError(
                f"the theta constraint must return True or False, got {ok!r} at "
                f"{self.describe(native)}"
            )
        return bool(ok)

    def describe(self, native: np.ndarray) -> str:
        """``name=value, ...`` of native theta."""
        return ", ".join(f"{n}={float(v):.6g}" for n, v in zip(self.names, native, strict=True))

    def check_start(self, theta_unit: np.ndarray, what: str) -> None:
        """GPMSAError naming the constraint and theta when the start ``theta_unit`` is refused."""
        if not self(theta_unit):
            value = self.describe(self.native(theta_unit))
            if what == "fixed theta":  # theta_init cannot move a fixed value
                raise GPMSAError(
                    f"fixed theta: the theta constraint rejects the fixed value {value}; fix theta "
                    "inside the allowed region, or drop the constraint"
                )
            if what == "fixed theta (held elements)":  # the others' start may help, or not
                raise StartRejectedError(
                    f"{what}: the theta constraint rejects the start {value} (the held "
                    "elements at their fixed values): hold them inside the allowed region, or "
                    "pass theta_init= (native units) for the others inside it",
                    {"theta_init": ...},
                )
            raise StartRejectedError(
                f"{what}: the theta constraint rejects the initial value {value}; pass "
                "theta_init= (native units) inside the allowed region",
                {"theta_init": ...},
            )


def round_levels(native: np.ndarray, categorical) -> np.ndarray:
    """Native theta (..., q) with each categorical element (``categorical``, (q,) flags; empty:
    none) rounded to its integer level, in place; the same array."""
    for k, flag in enumerate(categorical):
        if flag:
            native[..., k] = np.round(native[..., k])
    return native


def make(constraint, t_min, t_max, names, categorical=()) -> ThetaConstraint | None:
    """A ``ThetaConstraint`` from the user's ``constraint`` (None: no constraint);
    ``categorical``: (q,) flags of the categorical elements (empty: none)."""
    if constraint is None:
        return None
    if not callable(constraint):
        raise GPMSAError(
            f"constraint must be a callable of native theta (q,) -> bool, got {constraint!r}"
        )
    return ThetaConstraint(constraint, np.asarray(t_min, dtype=np.float64),
                           np.asarray(t_max, dtype=np.float64), tuple(names),
                           tuple(bool(c) for c in categorical))  # fmt: skip


def theta_native(value, names, what: str = "theta_init") -> np.ndarray:
    """A theta given natively as values in the order of ``names``: a dict by its keys (which
    must be ``names``), a pandas Series or one-row table by its labels, a sequence or array
    by position; flattened, float."""
    if isinstance(value, dict):
        keys = [str(k) for k in value]
        if sorted(keys) != sorted(str(n) for n in names):
            raise GPMSAError(f"{what} has the keys {keys}; expected {list(names)} (in any order)")
        value = [value[k] for k in names]
    value = by_column_names(value, names, what)  # pandas: by label, not position
    return as_float(value, what).reshape(-1)


def theta_init_unit(
    theta_init, t_min, t_max, names, closed=None, what: str = "theta_init"
) -> np.ndarray | None:
    """The user's ``theta_init`` (native, (q,); a dict, a pandas Series or a one-row table by
    its keys or labels, ``names``) on the unit scale; GPMSAError naming ``what`` outside (0, 1)
    (outside [0, 1] for the elements that ``closed`` (q,) bool marks: categorical levels)."""
    if theta_init is None:
        return None
    q = len(names)
    arr = theta_native(theta_init, names, what)
    if arr.size != q:
        raise GPMSAError(f"{what} must have {q} values ({names}), got {arr.size}")
    check_finite(arr, what)
    unit = (arr - np.asarray(t_min)) / (np.asarray(t_max) - np.asarray(t_min))
    closed = np.zeros(q, dtype=bool) if closed is None else np.asarray(closed, dtype=bool)
    bad = ~np.where(closed, (unit >= 0.0) & (unit <= 1.0), (unit > 0.0) & (unit < 1.0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        kind = "closed range [" if closed[k] else "open range ("
        v, lo, hi = numbers_text(arr[k], t_min[k], t_max[k])
        raise GPMSAError(
            f"{what} {names[k]}={v} lies outside the {kind}{lo}, {hi}"
            f"{']' if closed[k] else ')'} of the design"
        )
    return unit
