"""Kronecker-separable simulation designs (SEPIA's ``xt_sim_sep``): the runs are the Cartesian
product of K factor designs, each over its own group of inputs.

Rows in Kronecker order (factor 0 varies slowest, the last fastest: run i = (i_0, ..., i_{K-1})
in C order) make the product correlation over the runs R = R_0 (x) ... (x) R_{K-1}, R_k the
correlation among factor k's m_k points over its inputs. With the eigendecompositions
R_k = Q_k diag(e_k) Q_k^T, each component's covariance of the PCA weights

    Sigma_W = R / lamUz + nug I = Q diag(e / lamUz + nug) Q^T,   Q = (x)_k Q_k, e = (x)_k e_k,

gives the log-likelihood, Sigma_W^-1 w and the predictive in O(sum m_k^3 + m sum m_k) instead
of O(m^3) (``nug`` = 1 / (lam_sim lamWOs) + 1 / lamWs). The design is still stored run by run;
``Separable`` only records the grouping. See docs/internals.md, "Separable designs".
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import reduce

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.correlation import correlation

MAX_DENSE_RUNS = 5000
"""A separable emulator with more runs than this refuses the operations that would build its
dense m x m Sigma_W (calibration, cross-validation, full and joint prediction, sensitivity):
about 200 MB and an O(m^3) Cholesky per component at this size. ``predict``, ``predict_mean``
and ``loo`` never build it. Raise it (``gpmsa.model.kronecker.MAX_DENSE_RUNS = ...``) where the
machine has the memory and the time."""


@dataclass(frozen=True)
class Separable:
    """The factor structure of a separable design: ``groups``, the input columns (indices into
    [x, t]) of each factor, slowest-varying first; ``sizes``, the points of each factor
    (their product is the number of runs)."""

    groups: tuple[tuple[int, ...], ...]
    sizes: tuple[int, ...]

    @property
    def m(self) -> int:
        """Number of runs (the product of the factor sizes)."""
        return math.prod(self.sizes)

    def factor_designs(self, zt: np.ndarray) -> list[np.ndarray]:
        """Each factor's design (m_k, len(group)), read off the full design ``zt`` (m, p + q)."""
        out, stride = [], self.m
        for cols, n in zip(self.groups, self.sizes, strict=True):
            stride //= n
            out.append(np.ascontiguousarray(zt[: n * stride : stride][:, list(cols)]))
        return out

    def factor_of_column(self) -> np.ndarray:
        """(p + q,) the factor of each input column (the file's ``kron_factor`` array)."""
        out = np.empty(sum(len(g) for g in self.groups))
        for k, cols in enumerate(self.groups):
            out[list(cols)] = k
        return out


def parse_groups(separable, names: tuple[str, ...]) -> tuple[tuple[int, ...], ...] | None:
    """``SimData(separable=)`` as column groups over [x, t] (``names``: x_names + t_names):
    None (not separable), True (every input its own factor, in column order), or a sequence of
    factors, slowest-varying first, each an input (name or index) or a sequence of inputs.
    GPMSAError unless the factors are at least two and partition the inputs."""
    if separable is None or separable is False:
        return None
    d = len(names)
    if separable is True:
        groups = tuple((k,) for k in range(d))
    else:
        if isinstance(separable, str | bytes) or not _iterable(separable):
            raise GPMSAError(
                f"separable must be None, True or a sequence of factors (each an input name or "
                f"index, or a sequence of them), got {separable!r:.80}"
            )
        groups = []
        for g in separable:
            one = isinstance(g, str | bytes | int | np.integer) or not _iterable(g)
            items = [g] if one else list(g)  # one input, named by _column if it is none
            groups.append(tuple(_column(v, names) for v in items))
        groups = tuple(groups)
    flat = [k for g in groups for k in g]
    if len(groups) < 2 or any(not g for g in groups) or sorted(flat) != list(range(d)):
        raise GPMSAError(
            f"separable must split the {d} inputs {list(names)} into at least two non-empty "
            f"factors, each input in exactly one; got {[[names[k] for k in g] for g in groups]}"
        )
    return groups


def _iterable(value) -> bool:
    """Whether ``value`` iterates (a 0-d array has ``__iter__`` but refuses iteration)."""
    return hasattr(value, "__iter__") and not (isinstance(value, np.ndarray) and value.ndim == 0)


def _column(value, names: tuple[str, ...]) -> int:
    if isinstance(value, str):
        if value not in names:
            raise GPMSAError(f"separable: {value!r} is not an input (inputs {list(names)})")
        return names.index(value)
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise GPMSAError(f"separable: an input is a name or an index, got {value!r:.80}")
    if not 0 <= int(value) < len(names):
        raise GPMSAError(f"separable: input index {value} outside 0..{len(names) - 1}")
    return int(value)


def structure(zt: np.ndarray, groups, names: tuple[str, ...]) -> Separable:
    """The ``Separable`` of design ``zt`` (m, p + q) with factor column ``groups`` (slowest
    first); GPMSAError naming the first run that breaks the product or its order, and the
    factors' order where the runs are the product in another one."""
    m = zt.shape[0]
    sizes = tuple(int(np.unique(zt[:, list(g)], axis=0).shape[0]) for g in groups)
    label = [f"[{', '.join(names[k] for k in g)}]" for g in groups]
    if math.prod(sizes) != m:
        raise GPMSAError(
            f"separable: the design is not the product of its factors: "
            f"{' x '.join(f'{n} {lb}' for n, lb in zip(sizes, label, strict=True))} distinct "
            f"points make {math.prod(sizes)}, but there are {m} runs"
            + _rounding_hint(zt, groups, sizes, label)
        )
    sep = Separable(tuple(tuple(g) for g in groups), sizes)
    broken = _order_break(zt, sep)
    if broken is not None:
        k, i, expected = broken
        cols = list(groups[k])
        hint = ""
        for order in itertools.islice(itertools.permutations(range(len(groups))), 1, 720):
            if _order_break(zt, Separable(tuple(sep.groups[j] for j in order),
                                          tuple(sizes[j] for j in order))) is None:  # fmt: skip
                named = [[names[c] for c in sep.groups[j]] for j in order]
                hint = (
                    f"; these runs are that product with the factors in the order "
                    f"{' x '.join(label[j] for j in order)}: give separable={named}"
                )
                break
        raise GPMSAError(
            f"separable: run {i} has {label[k]} = {zt[i, cols].tolist()}, but the "
            f"Kronecker order gives {expected.tolist()}: the runs must be the product "
            f"of the factors {' x '.join(label)} in C order (the first factor varying "
            f"slowest, the last fastest, each factor's points in one order throughout){hint}"
        )
    return sep


def _rounding_hint(zt: np.ndarray, groups, sizes: tuple[int, ...], label: list[str]) -> str:
    """A note naming the factors with distinct points that agree to 1e-9 of their column's
    span ("" for none): a grid computed run by run whose values differ by rounding."""
    near = []
    for g, n, lb in zip(groups, sizes, label, strict=True):
        z = zt[:, list(g)]
        span = np.ptp(z, axis=0)
        unit = np.round((z - z.min(axis=0)) / np.where(span > 0, span, 1.0), 9)
        if np.unique(unit, axis=0).shape[0] < n:
            near.append(lb)
    if not near:
        return ""
    return (
        f" ({', '.join(near)}: points that agree to 1e-9 of the range count as distinct; give "
        "each factor's points as the same numbers in every run)"
    )


def _order_break(zt: np.ndarray, sep: Separable) -> tuple[int, int, np.ndarray] | None:
    """None where the rows of ``zt`` are ``sep``'s factors in Kronecker order, else (the
    factor, the first run that breaks it, what that run should hold)."""
    m, stride = zt.shape[0], zt.shape[0]
    for k, (cols, F) in enumerate(zip(sep.groups, sep.factor_designs(zt), strict=True)):
        stride //= sep.sizes[k]
        expected = np.tile(np.repeat(F, stride, axis=0), (m // (sep.sizes[k] * stride), 1))
        bad = np.flatnonzero(np.any(zt[:, list(cols)] != expected, axis=1))
        if bad.size:
            return k, int(bad[0]), expected[int(bad[0])]
    return None


def refuse(what: str) -> None:
    """GPMSAError: ``what`` is not supported with a separable design."""
    raise GPMSAError(
        f"a separable design (SimData(separable=...)) supports a simulation-only fit on the "
        f"numpy backend with the zero-mean GP; {what} is not supported with it (drop "
        "separable= to fit the same model densely)"
    )


def check_dense(emulator, what: str) -> None:
    """GPMSAError where ``emulator`` is separable with more than ``MAX_DENSE_RUNS`` runs: ``what``
    would build its dense m x m Sigma_W."""
    if getattr(emulator, "separable", None) is not None and emulator.m > MAX_DENSE_RUNS:
        raise GPMSAError(
            f"{what} builds the dense {emulator.m} x {emulator.m} Sigma_W of this separable "
            f"emulator ({emulator.m} runs, above gpmsa.model.kronecker.MAX_DENSE_RUNS = "
            f"{MAX_DENSE_RUNS}); predict, predict_mean and loo use the Kronecker structure. "
            "Raise MAX_DENSE_RUNS where the machine has the memory and time"
        )


def fit_nbytes(sep: Separable, p_u: int) -> float:
    """Bytes of the Kronecker likelihood's state: per component its factors' eigenvectors and
    a few m-vectors."""
    return 8.0 * p_u * 2 * (sum(n * n for n in sep.sizes) + 4 * sep.m)


# --- Kronecker algebra --------------------------------------------------------------------------
def kron_matvec(mats: list[np.ndarray], x: np.ndarray) -> np.ndarray:
    """((x)_k mats[k]) @ x for x (m,) or (m, r), without forming the product."""
    extra = x.shape[1:]
    t = x.reshape(*[a.shape[1] for a in mats], *extra)
    for k, a in enumerate(mats):
        t = np.moveaxis(np.tensordot(a, t, axes=([1], [k])), 0, k)
    return t.reshape(-1, *extra)


def kron_vector(vectors: list[np.ndarray]) -> np.ndarray:
    """(x)_k vectors[k] (the m products, C order)."""
    return reduce(np.multiply.outer, vectors).reshape(-1)


def _part(cat, cols) -> np.ndarray | None:
    """The categorical mask of columns ``cols`` (None: none categorical)."""
    return None if cat is None else cat[list(cols)]


def factor_eigen(F: np.ndarray, beta: np.ndarray, cat) -> tuple[np.ndarray, np.ndarray]:
    """(eigenvalues e_k, eigenvectors Q_k) of factor design F's correlation R_k(beta)."""
    e, Q = np.linalg.eigh(correlation(F, None, beta, cat))
    return e, Q


def weights_loglik(lam: np.ndarray, wt: np.ndarray, scale: float, nug: float) -> float:
    """-log det(Sigma_W) / 2 - w^T Sigma_W^-1 w / 2 from the eigenvalues ``lam`` of R, the
    rotated weights ``wt`` = Q^T w, 1 / lamUz (``scale``) and the nugget; -inf if not PD."""
    d = lam * scale + nug
    if not d.min() > 0.0:
        return -np.inf
    return -0.5 * float(np.sum(np.log(d))) - 0.5 * float(np.dot(wt * wt, 1.0 / d))


class KronFactor:
    """One component's Sigma_W at given parameters: eigenvectors ``Q`` (per factor), eigenvalues
    of Sigma_W ``d`` (m,), and ``alpha`` = Sigma_W^-1 w (m,)."""

    def __init__(self, designs, groups, cat, beta, scale: float, nug: float, w: np.ndarray):
        eig = [factor_eigen(F, beta[list(g)], _part(cat, g))
               for F, g in zip(designs, groups, strict=True)]  # fmt: skip
        self.Q = [Q for _, Q in eig]
        self.d = kron_vector([e for e, _ in eig]) * scale + nug
        if not self.d.min() > 0.0:
            raise GPMSAError("Sigma_W is not positive definite at these parameters")
        self.alpha = kron_matvec(self.Q, kron_matvec([Q.T for Q in self.Q], w) / self.d)

    def precision_diagonal(self) -> np.ndarray:
        """diag(Sigma_W^-1) (m,) = ((x)_k Q_k o Q_k) (1 / d)."""
        return kron_matvec([Q * Q for Q in self.Q], 1.0 / self.d)


class KroneckerLikelihood:
    """``IncrementalLikelihood``'s interface (``params``, ``loglik``, ``propose``, ``accept``)
    for a simulation-only separable problem: per component the factors' eigendecompositions
    and w rotated into their basis. A betaU proposal redoes one factor's eigendecomposition
    (O(m_k^3 + m sum m_k)); lamUz, lamWs, lamWOs proposals are O(m)."""

    def __init__(self, problem, params: dict[str, np.ndarray]):
        if problem.obs is not None or problem.mean_basis is not None:
            refuse("observations or a mean_basis")
        sep = problem.separable
        self.problem = problem
        self.groups = sep.groups
        self.designs = sep.factor_designs(problem.zt)
        self.cat = problem.categorical
        self.factor_of = [int(k) for k in sep.factor_of_column()]  # input column -> factor
        self.params = {k: np.array(v, dtype=np.float64) for k, v in params.items()}
        beta = self.params["betaU"]
        # per component: (eigenvalues per factor, eigenvectors per factor, lam (m,), wt (m,))
        self.comps = [self._component(beta[:, j], j) for j in range(problem.p_u)]
        self.llw = [self._llw(c, j, self.params) for j, c in enumerate(self.comps)]
        self.loglik = float(sum(self.llw))
        self._pending = None

    def _eigen(self, k: int, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Factor ``k``'s eigendecomposition at one component's ``beta`` (p + q,)."""
        g = self.groups[k]
        return factor_eigen(self.designs[k], beta[list(g)], _part(self.cat, g))

    def _component(self, beta: np.ndarray, j: int, old=None, only: int | None = None) -> tuple:
        """Component ``j``'s (eigenvalues per factor, eigenvectors per factor, lam (m,), wt
        (m,)) at ``beta``: every factor anew, or ``old``'s with factor ``only`` redone."""
        if old is None:
            eig = [self._eigen(k, beta) for k in range(len(self.groups))]
            es, Qs = [e for e, _ in eig], [Q for _, Q in eig]
        else:
            es, Qs = list(old[0]), list(old[1])
            es[only], Qs[only] = self._eigen(only, beta)
        return es, Qs, kron_vector(es), kron_matvec([Q.T for Q in Qs], self.problem.w[:, j])

    def _llw(self, c: tuple, j: int, prm: dict) -> float:
        nug = 1.0 / (self.problem.lam_sim[j] * prm["lamWOs"][0]) + 1.0 / prm["lamWs"][j]
        return weights_loglik(c[2], c[3], 1.0 / prm["lamUz"][j], nug)

    def propose(self, name: str, idx: tuple[int, ...], value: float) -> float:
        """Log-likelihood with element ``idx`` of ``name`` set to ``value`` (pending accept)."""
        prm = dict(self.params)
        arr = prm[name].copy()
        arr[idx] = value
        prm[name] = arr
        comps = {}
        if name == "betaU":
            k, j = idx
            comps[j] = self._component(arr[:, j], j, self.comps[j], self.factor_of[k])
        llw = list(self.llw)
        js = range(len(self.comps)) if name == "lamWOs" else [idx[-1]]
        for j in js:
            llw[j] = self._llw(comps.get(j, self.comps[j]), j, prm)
        ll = float(sum(llw))
        self._pending = (prm, comps, llw, ll)
        return ll

    def accept(self) -> None:
        """Commit the last proposal."""
        prm, comps, llw, ll = self._pending
        for j, c in comps.items():
            self.comps[j] = c
        self.params, self.llw, self.loglik = prm, llw, ll
        self._pending = None


# --- the emulator's predictive ------------------------------------------------------------------
def emulator_factors(emulator, params: dict) -> list[KronFactor]:
    """Per component the ``KronFactor`` of a separable emulator at ``params``."""
    sep = emulator.separable
    designs = sep.factor_designs(emulator.zt)
    cat = emulator.categorical_mask
    out = []
    for j in range(emulator.p_u):
        nug = 1.0 / (emulator.lam_sim[j] * params["lamWOs"][0]) + 1.0 / params["lamWs"][j]
        out.append(KronFactor(designs, sep.groups, cat, params["betaU"][:, j],
                              1.0 / params["lamUz"][j], nug, emulator.w[:, j]))  # fmt: skip
    return out


def _contract(rows: list[np.ndarray], tensor: np.ndarray) -> np.ndarray:
    """sum_i prod_k rows[k][n, i_k] tensor[i] for every point n: (N,), rows[k] (N, m_k)."""
    t = rows[0] @ tensor.reshape(rows[0].shape[1], -1)  # (N, rest)
    for r in rows[1:]:
        t = np.einsum("ni,nir->nr", r, t.reshape(t.shape[0], r.shape[1], -1))
    return t[:, 0]


def predict_std(emulator, z: np.ndarray, params, factors, resid: bool, *, var: bool = True):
    """``Emulator._predict_std`` of a separable emulator: the standardised mean and variance
    (N, l_sim) at unit-scale z, with each point's correlation to the runs as the product of
    its correlations to the factors' points (O(N (m + sum m_k^2)) per component)."""
    sep = emulator.separable
    designs = sep.factor_designs(emulator.zt)
    cat = emulator.categorical_mask
    mean = np.zeros((z.shape[0], emulator.l_sim))
    out = np.zeros((z.shape[0], emulator.l_sim)) if var else None
    for j, fac in enumerate(factors):
        beta, lam = params["betaU"][:, j], params["lamUz"][j]
        rows = [correlation(z[:, list(g)], F, beta[list(g)], _part(cat, g))
                for F, g in zip(designs, sep.groups, strict=True)]  # fmt: skip
        mw = _contract(rows, fac.alpha) / lam
        mean += np.outer(mw, emulator.K[:, j])
        if var:
            rot = [(r @ Q) ** 2 for r, Q in zip(rows, fac.Q, strict=True)]
            vw = 1.0 / lam - _contract(rot, 1.0 / fac.d) / (lam * lam)
            if resid:
                vw = vw + 1.0 / params["lamWs"][j]
            out += np.outer(vw, emulator.K[:, j] ** 2)
    if var and resid:
        out += 1.0 / params["lamWOs"][0]
    return mean, out
