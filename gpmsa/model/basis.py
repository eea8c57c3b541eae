"""Output bases: the PCA emulator basis K and the discrepancy basis D (GPM/SA conventions)."""

from __future__ import annotations

import hashlib
import itertools
import math
import warnings

import numpy as np
from scipy import stats

from gpmsa.errors import BasisWarning, GPMSAError, numbers_text, user_stacklevel
from gpmsa.model import index_points
from gpmsa.model.data import as_float, check_count, check_increasing
from gpmsa.model.index_points import is_points, n_points

VARIANCE_FRACTION = 0.995
ORTHOGONAL_TOL = 1e-8
"""Largest |off-diagonal of K^T K| relative to its largest diagonal element that counts as
orthogonal (a basis from a QR or SVD is orthogonal to ~1e-15); emulator files are held to it."""
WEIGHT_PRIOR_MASS = 0.99
"""`warn_weight_scale` warns when a basis vector's weights spread outside the central part of this
mass of what lamUz's prior allows."""


def pca_basis(
    y_std: np.ndarray, n_pc: int | float | None = None, fraction: float = VARIANCE_FRACTION
) -> np.ndarray:
    """PCA basis K (l_sim, p_u) of standardised outputs y_std (m, l_sim): K = U S / sqrt(m).

    p_u = ``n_pc`` if an integer; a float in (0, 1) is a variance fraction (as SEPIA's
    ``create_K_basis(n_pc=0.99)``): the fewest components reaching it, as ``fraction`` is when
    ``n_pc`` is None. A scalar output (l_sim = 1) gives K = [[1]].
    """
    m, l_sim = y_std.shape
    if isinstance(n_pc, float | np.floating) and 0.0 < n_pc < 1.0:
        n_pc, fraction = None, float(n_pc)
    elif n_pc is not None:
        if isinstance(n_pc, float | np.floating):
            raise GPMSAError(
                f"n_pc must be an integer >= 1 (components) or a variance fraction in (0, 1), "
                f"got {n_pc!r}"
            )
        n_pc = check_count(n_pc, "n_pc")
    if l_sim == 1:
        if n_pc not in (None, 1):
            raise GPMSAError(f"n_pc must be 1 for a scalar output, got {n_pc!r}")
        return np.ones((1, 1))
    u, s, _ = np.linalg.svd(y_std.T, full_matrices=False)
    if n_pc is None:
        if not 0 < fraction <= 1:
            raise GPMSAError(f"fraction must be in (0, 1], got {fraction}")
        share = np.cumsum(s**2) / np.sum(s**2)
        n_pc = int(np.searchsorted(share, fraction - 1e-12) + 1)
    if not 1 <= n_pc <= min(m, l_sim):
        raise GPMSAError(f"n_pc must be in [1, {min(m, l_sim)}], got {n_pc!r}")
    return u[:, :n_pc] * s[:n_pc] / np.sqrt(m)


def given_basis(basis, l_sim: int) -> np.ndarray:
    """A user's emulator basis K (l_sim, p_u) of standardised outputs of ``l_sim`` values,
    checked (GPM/SA's ``Ksim``, SEPIA's ``create_K_basis(K=)``, transposed: columns are the
    basis vectors on the simulation grid).

    GPMSAError unless finite, of l_sim rows and 1 <= p_u <= l_sim nonzero columns that are
    orthogonal (GPM/SA's simulation likelihood uses only diag(K^T K); it is exact for
    orthogonal columns alone). A scalar output's basis is [[1]]. The runs' weights on it are
    judged by `warn_weight_scale`.
    """
    K = as_float(basis, "basis")
    if K.ndim != 2:
        raise GPMSAError(f"basis must be a 2-D array (l_sim, p_u) = ({l_sim}, p_u), got shape "
                         f"{K.shape}")  # fmt: skip
    if K.shape[0] != l_sim:
        hint = "; SEPIA stores K as (p_u, l_sim): pass K.T" if K.shape[1] == l_sim else ""
        raise GPMSAError(
            f"basis must have one row per simulation output value ({l_sim}), columns the "
            f"basis vectors; got shape {K.shape}{hint}"
        )
    if not np.all(np.isfinite(K)):
        raise GPMSAError("basis must be finite")
    if l_sim == 1:
        if K.shape != (1, 1) or K[0, 0] != 1.0:
            raise GPMSAError(f"a scalar output's basis is [[1.0]], got {K.tolist()}")
        return K
    p_u = K.shape[1]
    if not 1 <= p_u <= l_sim:
        raise GPMSAError(f"basis must have 1 to {l_sim} columns, got {p_u}")
    with np.errstate(over="ignore", under="ignore"):
        gram = K.T @ K
    lam = np.diag(gram)
    if not np.all(np.isfinite(gram)):
        raise GPMSAError("basis columns are too large to square in float64")
    zero = np.flatnonzero(~(lam > np.finfo(np.float64).tiny))
    if zero.size:
        raise GPMSAError(f"basis column(s) {zero.tolist()} are zero (or too small to square)")
    off = np.abs(gram - np.diag(lam)).max()
    if off > ORTHOGONAL_TOL * lam.max():
        raise GPMSAError(
            f"basis columns must be orthogonal (largest |K^T K| off the diagonal "
            f"{numbers_text(off / lam.max(), ORTHOGONAL_TOL, digits=2)[0]} of the largest "
            "diagonal element, tolerance "
            f"{ORTHOGONAL_TOL:g}): GPM/SA's likelihood of the runs is exact only then. "
            "numpy.linalg.qr(K) or an SVD gives an orthogonal basis of the same span (the "
            "weights' GP prior then applies to its columns)"
        )
    return K


def warn_weight_scale(w: np.ndarray, lamuz_prior) -> None:
    """``BasisWarning`` naming each column of a given basis's weights w (m, p_u) whose root
    mean square lies outside 1 / sqrt(lamUz) over the central WEIGHT_PRIOR_MASS of lamUz's
    (truncated) Gamma prior ``lamuz_prior``; the PCA basis gives exactly 1."""
    a, b, lower, upper = lamuz_prior.a, lamuz_prior.b, lamuz_prior.lower, lamuz_prior.upper
    gamma = stats.gamma(a, scale=1.0 / b)
    tail = 0.5 * (1.0 - WEIGHT_PRIOR_MASS)
    c_lo, c_hi = gamma.cdf(lower), gamma.cdf(upper)
    lam_lo, lam_hi = gamma.ppf(c_lo + (c_hi - c_lo) * np.array([tail, 1.0 - tail]))
    sd_lo, sd_hi = 1.0 / np.sqrt(lam_hi), 1.0 / np.sqrt(lam_lo)
    rms = np.sqrt(np.mean(w**2, axis=0))
    bad = np.flatnonzero((rms < sd_lo) | (rms > sd_hi))
    if bad.size:
        shown = ", ".join(f"{j}: {rms[j]:.3g}" for j in bad[:5])
        unused = np.flatnonzero(rms <= 1e-12 * rms.max())
        drop = (f" Column(s) {unused.tolist()} hold none of the runs' variation: leave them out."
                if unused.size else "")  # fmt: skip
        warnings.warn(
            f"basis column(s) {bad.tolist()} give the runs weights of root mean square {shown}; "
            f"lamUz's prior (Gamma({a:g}, {b:g}) on ({lower:g}, {upper:g})) lets them spread "
            f"{sd_lo:.2g} to {sd_hi:.2g} ({WEIGHT_PRIOR_MASS:.0%} of its mass). Multiply column "
            "j of the basis by its weights' root mean square to give them the unit scale "
            f"GPM/SA's priors expect (the PCA basis's).{drop}",
            BasisWarning,
            stacklevel=user_stacklevel(),
        )


def variance_shares(w: np.ndarray, lam_sim: np.ndarray, total: float) -> np.ndarray:
    """(p_u,) the share of the standardised runs' sum of squares ``total`` each basis vector
    holds, ||w_j||^2 ||K_j||^2 / total (lam_sim = diag(K^T K); orthogonal columns: they add up
    to the basis's share); NaN where ``total`` is 0."""
    held = np.sum(w**2, axis=0) * lam_sim
    return held / total if total > 0 else held * np.nan


def basis_weights(y_std: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Weights w (m, p_u) = y_std K^+^T (least-squares projection on the basis)."""
    return y_std @ np.linalg.pinv(K).T


def interpolate_basis(K: np.ndarray, grid: np.ndarray, new_grid: np.ndarray | None) -> np.ndarray:
    """Basis columns interpolated linearly from ``grid`` (strictly increasing) onto ``new_grid``
    (any order; None: unchanged); from index points (l_sim, d) onto points (l, d), piecewise
    linearly on their triangulation (`index_points.weights`; exact on a simulation point)."""
    if new_grid is None or (new_grid.shape == grid.shape and np.array_equal(new_grid, grid)):
        return K
    if K.shape[0] == 1:
        return np.repeat(K, new_grid.size, axis=0)
    if is_points(grid) or is_points(new_grid):
        return index_points.weights(grid, new_grid, "observation index") @ K
    check_increasing(grid, "the simulation grid")
    lo, hi = grid.min(), grid.max()
    if not index_points.within(new_grid, lo, hi):  # an end reached by rounding: the end
        raise GPMSAError(
            f"observation index must lie within the simulation grid [{lo}, {hi}], "
            f"got [{new_grid.min()}, {new_grid.max()}]"
        )
    return np.column_stack([np.interp(new_grid, grid, K[:, j]) for j in range(K.shape[1])])


def discrepancy_basis(kind, grid: np.ndarray) -> np.ndarray | None:
    """Discrepancy basis D (l_obs, p_v) on ``grid`` (l_obs,), normalised so max diag(D D^T) = 1.

    ``kind``: None (no discrepancy), "constant", "linear" (1 and the index), or a given
    (l_obs, p_v) array. A list of per-experiment bases: `discrepancy_bases`.
    """
    if kind is None:
        return None
    if isinstance(kind, str):
        if kind == "constant":
            D = np.ones((n_points(grid), 1))
        elif kind == "linear" and is_points(grid):
            raise GPMSAError(
                f"discrepancy='linear' is [1, index] along one index grid; the output index "
                f"here has {grid.shape[1]} columns: pass the basis per experiment, e.g. "
                "discrepancy=[np.column_stack([np.ones(len(g)), g]) for g in obs.grids] "
                "(1 and each index column), or discrepancy='constant'"
            )
        elif kind == "linear":
            D = np.column_stack([np.ones(grid.size), grid])
        else:
            raise GPMSAError(
                f"discrepancy must be None, 'constant', 'linear', an array or a list of one "
                f"array per experiment, got {kind!r}"
            )
    else:
        if is_basis_list(kind):
            raise GPMSAError(
                f"discrepancy basis: a list of {len(kind)} matrices (one per experiment) is "
                "built by discrepancy_bases, on the experiments' grids"
            )
        D = as_float(kind, "discrepancy basis")
        if D.ndim == 1:
            D = D[:, None]
        n = n_points(grid)
        if D.ndim != 2 or D.shape[0] != n:
            hint = "; SEPIA stores D as (p_v, l_obs): pass its transpose" if (
                D.ndim == 2 and D.shape[1] == n) else ""  # fmt: skip
            raise GPMSAError(f"discrepancy basis must be ({n}, p_v), got {D.shape}{hint}")
        if D.shape[1] < 1:
            raise GPMSAError("discrepancy basis has no columns: give at least one basis vector")
        if not np.all(np.isfinite(D)):
            raise GPMSAError("discrepancy basis must be finite")
    return _normalised([D], "discrepancy basis is all zeros")[0]


def _normalised(bases: list[np.ndarray], zero: str) -> list[np.ndarray]:
    """``bases`` divided by one scale, so that the largest diag(D D^T) over all of them is 1
    (GPMSAError ``zero`` when they are all zero)."""
    big, scale = _scale(bases)
    if not scale > 0:
        raise GPMSAError(zero)
    with np.errstate(under="ignore"):  # entries far below the largest one: subnormal or 0
        return [(D if big is None else D / big) / np.sqrt(scale) for D in bases]


def _scale(bases: list[np.ndarray]) -> tuple[float | None, float]:
    """`_normalised`'s divisors: the largest diag(D D^T) over ``bases``, after dividing them by
    ``big`` (their largest |value|; None where the squares neither over- nor underflow)."""
    with np.errstate(over="ignore", under="ignore"):
        scale = max(np.max(np.sum(D**2, axis=1)) for D in bases)
    if not np.finfo(np.float64).tiny <= scale < np.inf and any(np.any(D) for D in bases):
        big = max(np.max(np.abs(D)) for D in bases)  # squares over/underflow: rescale first
        with np.errstate(under="ignore"):  # (entries far below ``big``: to 0)
            return big, max(np.max(np.sum((D / big) ** 2, axis=1)) for D in bases)
    return None, scale


def scaled_as(bases: list[np.ndarray], D: np.ndarray) -> np.ndarray:
    """``D`` divided as `_normalised` divides ``bases`` (the same basis functions on another
    grid keep the fit's normalisation)."""
    big, scale = _scale(bases)
    with np.errstate(under="ignore"):
        return (D if big is None else D / big) / np.sqrt(scale)


SCALE_TOL = 1e-9
"""Relative tolerance within which two `basis_scale` values are one: a basis's and the one a
fit recorded (settings "discrepancy_scale"), or 1 (a normalised basis)."""


def basis_scale(bases: list[np.ndarray]) -> float:
    """The one number `_normalised` divides ``bases`` by: the largest row norm over them
    (their largest |value| times that of the bases divided by it, where the squares over- or
    underflow); ``D / basis_scale(bases)`` is `scaled_as` (the same float division where they
    do not, to an ulp where they do)."""
    big, scale = _scale(bases)
    root = float(np.sqrt(scale))
    return root if big is None else float(big) * root


def given_bases(kind) -> list[np.ndarray]:
    """A discrepancy basis given as an array or a list (per-experiment bases) as float64
    (l, p_v) arrays, a 1-D array as one column (unchecked: `discrepancy_bases` checks them)."""
    raw = [as_float(d, "discrepancy") for d in (kind if is_basis_list(kind) else [kind])]
    return [d[:, None] if d.ndim == 1 else d for d in raw]


def is_basis_list(kind) -> bool:
    """Whether a ``discrepancy`` argument is a list (or tuple) of per-experiment bases: one of
    its entries is 2-D (an array, or a list of rows); a 2-D array given as a list of rows has
    1-D entries."""
    if not isinstance(kind, (list, tuple)) or not kind:
        return False
    return any(getattr(d, "ndim", None) == 2 or _rows(d) for d in kind)


def _rows(value) -> bool:
    """Whether ``value`` is a non-empty list (or tuple) of rows (lists, tuples or arrays)."""
    return (
        isinstance(value, (list, tuple))
        and bool(value)
        and isinstance(value[0], (list, tuple, np.ndarray))
    )


def discrepancy_kind(kind) -> str | None:
    """The recorded name of a ``discrepancy`` argument: None, "constant", "linear", "list"
    (per-experiment bases, `discrepancy_bases`) or "given" (one array)."""
    if kind is None or isinstance(kind, str):
        return kind
    return "list" if is_basis_list(kind) else "given"


def describe_discrepancy(kind) -> str:
    """A ``discrepancy`` argument for a message: its name, an array's shape or a list's
    shapes (not their values)."""
    if kind is None or isinstance(kind, str):
        return repr(kind)
    if is_basis_list(kind):
        shapes = ", ".join(str(np.shape(d)) if _rectangular(d) else "ragged" for d in kind[:4])
        more = ", ..." if len(kind) > 4 else ""
        return f"a list of {len(kind)} bases of shapes [{shapes}{more}]"
    return f"an array of shape {np.shape(kind) if _rectangular(kind) else 'ragged'}"


def _rectangular(value) -> bool:
    try:
        np.shape(value)
    except ValueError:  # a ragged nested list
        return False
    return True


def discrepancy_bases(kind, grids: list[np.ndarray]) -> tuple[np.ndarray, ...] | None:
    """The discrepancy bases D_j (l_j, p_v) of the experiments on ``grids`` (their index
    grids, l_j values each); None without a discrepancy.

    A named kind or one array: `discrepancy_basis` on each grid (each normalised on its own,
    max diag(D_j D_j^T) = 1). A list of one (l_j, p_v) array per experiment (SEPIA's
    ``create_D_basis(D_obs=[...])``, GPM/SA's per-experiment ``obsData(k).Dobs``, e.g. kernels
    on each experiment's own grid): checked (GPMSAError naming the experiment: count, rows,
    the same p_v, finite; not all of them zero) and normalised jointly, by one scale so that
    the largest diag(D_j D_j^T) over all experiments is 1: the same weights mean the same
    discrepancy in each. One experiment's basis may be zero, as a zero ``Dobs`` in GPM/SA:
    that experiment has no discrepancy (its weights' reduced data are unobserved directions,
    ``ObsProblem.n_null``, and its delta is 0). SEPIA also divides every experiment's D by one
    scale, taken from the first experiment's (or D_sim's); the largest over all of them is
    GPM/SA's convention (max diag(D D^T) = 1) for the stacked bases, and the two agree where
    experiment 0 reaches that largest value (a hand-built "constant" or "linear" list: the
    string kinds' bases).
    """
    if not is_basis_list(kind):
        lengths = [n_points(g) for g in grids]
        if kind is not None and not isinstance(kind, str) and len(set(lengths)) > 1:
            shape = (f"of shape {kind.shape}" if isinstance(kind, np.ndarray)
                     else f"(a {type(kind).__name__})")  # fmt: skip
            shown = ", ".join(map(str, lengths[:8])) + (", ..." if len(lengths) > 8 else "")
            raise GPMSAError(
                f"discrepancy: one basis {shape} is for the index grid every experiment "
                f"shares, but the experiments' grids have [{shown}] values: give a list of one "
                "(l_j, p_v) array per experiment, rows on its own index grid"
            )
        return None if kind is None else tuple(discrepancy_basis(kind, g) for g in grids)
    if len(kind) != len(grids):
        raise GPMSAError(
            f"discrepancy: a list of {len(kind)} bases for {len(grids)} experiments: give one "
            "(l_j, p_v) array per experiment, rows on its own index grid"
        )
    bases = []
    for j, (d, g) in enumerate(zip(kind, grids, strict=True)):
        what = f"discrepancy[{j}] (experiment {j}'s basis)"
        D, n = as_float(d, what), n_points(g)
        if D.ndim != 2 or D.shape[0] != n:
            hint = "; SEPIA stores D as (p_v, l_obs): pass its transpose" if (
                D.ndim == 2 and D.shape[1] == n) else ""  # fmt: skip
            raise GPMSAError(
                f"{what} must be ({n}, p_v): one row per value of experiment {j}'s index "
                f"grid ({n}), columns the basis vectors; got shape {D.shape}{hint}"
            )
        if D.shape[1] < 1:
            raise GPMSAError(f"{what} has no columns: give at least one basis vector")
        if bases and D.shape[1] != bases[0].shape[1]:
            raise GPMSAError(
                f"{what} has {D.shape[1]} column(s) but discrepancy[0] has "
                f"{bases[0].shape[1]}: every experiment's basis needs the same p_v basis "
                "vectors (columns), one weight each"
            )
        if not np.all(np.isfinite(D)):
            raise GPMSAError(f"{what} must be finite")
        bases.append(D)
    zero = (
        "discrepancy bases are all zeros, every experiment's: give at least one experiment "
        "a nonzero basis, or discrepancy=None"
    )
    return tuple(_normalised(bases, zero))


DIGEST_STEP = 2.0**-24
"""`basis_digest` rounds the normalised bases (max row norm 1) to multiples of this, so that
a multiple of a basis, whose normalisation differs from the basis's by an ulp or two, is the
same basis (one element in about 1e8 lands within an ulp of a rounding point)."""


def basis_digest(bases, groups=None) -> str | None:
    """SHA-256 of the normalised discrepancy bases of a reduction (``ObsProblem.D``: one array
    per experiment, rounded to DIGEST_STEP, with their shapes) and of their precision groups
    (``ObsProblem.v_groups``; None, one group, adds nothing); None without a discrepancy. A
    joint fit and ``gpmsa.calibrate`` record it, so that ``gpmsa.full_prediction`` refuses
    another basis or grouping."""
    if bases is None:
        return None
    h = hashlib.sha256()
    if groups is not None:
        h.update(f"groups:{list(groups)}".encode())
    for k, D in enumerate(bases):
        arr = np.ascontiguousarray(np.rint(np.asarray(D, dtype=np.float64) / DIGEST_STEP), "<i8")
        h.update(f"{k}:{arr.shape}".encode())
        h.update(arr.tobytes())
    return h.hexdigest()


REORDER_LIMIT = 8_192
"""Most signed column permutations of a discrepancy basis that `reordered_basis` hashes (~0.1 s;
its search is exhaustive within it: the signs and orders of 5 columns in one group, or of more
in several, else the signs alone of up to 13 columns in their given order)."""


def reordered_basis(digest: str, groups, bases, new_groups) -> bool:
    """Whether ``bases`` (``ObsProblem.D``, normalised) with precision groups ``new_groups`` are,
    up to the signs and order of their columns (each keeping its group), the bases of
    ``digest`` (`basis_digest`) whose groups were ``groups`` (None: one): the same model, each
    discrepancy weight's sign or position changed. False where they are not, or where more
    than ``REORDER_LIMIT`` candidates (orders consistent with the groups, times 2^p_v signs)
    would have to be hashed (beyond it, the columns' signs alone)."""
    if bases is None or digest is None or (groups is None) != (new_groups is None):
        return False
    ints = [np.rint(np.asarray(D, dtype=np.float64) / DIGEST_STEP).astype("<i8") for D in bases]
    p_v = ints[0].shape[1]
    old = [0] * p_v if groups is None else [int(g) for g in groups]
    new = [0] * p_v if new_groups is None else [int(g) for g in new_groups]
    if sorted(old) != sorted(new):
        return False
    head = b"" if groups is None else f"groups:{old}".encode()
    for order in _orders(old, new):
        for signs in itertools.product((1, -1), repeat=p_v):
            h = hashlib.sha256(head)
            for k, arr in enumerate(ints):
                h.update(f"{k}:{arr.shape}".encode())
                h.update(np.ascontiguousarray(arr[:, order] * np.array(signs, "<i8")).tobytes())
            if h.hexdigest() == digest:
                return True
    return False


def _orders(old: list[int], new: list[int]) -> list[list[int]]:
    """The orders of the columns of ``new`` (their groups) that give each of ``old``'s columns
    one of its group, all of them within ``REORDER_LIMIT`` with their signs, else the given
    order alone (where the groups agree and 2^p_v signs are within it)."""
    labels, p_v = sorted(set(old)), len(old)
    if math.prod(math.factorial(old.count(g)) for g in labels) * 2**p_v > REORDER_LIMIT:
        return [list(range(p_v))] if old == new and 2**p_v <= REORDER_LIMIT else []
    orders = []
    for choice in itertools.product(*(itertools.permutations(
            [i for i, g in enumerate(new) if g == lab]) for lab in labels)):  # fmt: skip
        slots = dict(zip(labels, map(iter, choice), strict=True))
        orders.append([next(slots[g]) for g in old])
    return orders
