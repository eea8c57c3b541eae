"""Sobol sensitivity indices of the emulator (GPM/SA's gSens, SEPIA's sensitivity).

Method: for each posterior draw of the emulator parameters, the indices of the emulator's
posterior-mean surface are computed exactly by integrating the Gaussian correlation in closed form
(the approach of Oakley & O'Hagan 2004, as GPM/SA's gSens does; no Monte Carlo). The inputs
z = (x, t) are independent and uniform on a box (by default the training domain). On the unit
scale the mean of basis component j is

    f_j(z) = sum_i c_ji prod_k exp(-beta_kj (z_k - z_ik)^2),   c_j = Sigma_W_j^-1 w_j / lamUz_j,

so every conditional expectation E[f_j | z_u] and every product moment E[E[f_j | z_u]
E[f_j' | z_u]] is a sum over pairs of runs of products of one-dimensional Gaussian integrals
(error functions). With V^u_jj' = Cov(E[f_j | z_u], E[f_j' | z_u]) the output element l on the
simulation grid (y_l = y_mean_l + y_sd sum_j K_lj f_j) has

    V_u(l) = K_l V^u K_l^T,   main effect S_k = V_{k}(l) / V(l),   total effect
    ST_k = 1 - V_{~k}(l) / V(l)   (~k: every varied input but k; Saltelli's definitions).

The same is reported per basis component (V^u_jj) and for the variance summed over the output grid
(trace(K^T K V^u), the aggregated index of a functional output, GPM/SA's multivariate gSens).
The spread over draws shows how well the emulator pins the indices down. An output element whose
variance over the box is below 1e-12 of the largest has undefined indices (NaN).

Opt-in (SEPIA's ``varlist`` and ``jelist`` of pairs, ``ngrid``): for pairs u = {k, l} the
closed joint index S_{kl} = V_{k,l} / V and the two-factor interaction index
S_kl = (V_{k,l} - V_k - V_l) / V (the second-order Sobol index), from the same sums with two
inputs' pair integrals; the main-effect functions E[y_l | z_k = g] on an even grid g over z_k's
range, and the joint-effect functions E[y_l | z_k = g, z_k' = h] on a grid of grids: with the
other inputs integrated out, each is a sum over the runs of Gaussians in the gridded inputs (no
Monte Carlo either). Like the indices, they are the emulator mean's, per posterior draw.

Groups of any size (SEPIA's ``jelist``, opt-in ``groups=``): the closed joint index
V_G / V of a group G of varied inputs, the pair's sum with the group's pair integrals
multiplied (a group of two is the pair's ``joint``, bit for bit in the same order).

The GP's own variance about the effect functions (SEPIA's ``mef_v``, opt-in
``effect_variance=True``): per draw, M(g) = E_{z_~u}[w_j(z) | z_u = g] is a linear functional
of the GP given the runs' weights, Gaussian with the curve above as its mean and the variance

    prod_{n not in u} DD_jn / lamUz_j - a_j(g)^T Sigma_W_j^-1 a_j(g)  (+ the GLS term),
    a_j(g) = int r_j(z) dz_~u = prod_{k in u} R_k(g_k, z_ik) prod_{n not in u} I1_jn / lamUz_j,

the posterior covariance integrated twice over the other inputs: DD_jn, the kernel's mean
over two independent points of input n (sqrt(pi) erf(x) / x - (1 - exp(-x^2)) / x^2, x =
sqrt(beta) width; a double average over a categorical input's levels), and the runs' share by
their single means I1 (a sum over runs, a triangular solve per grid point); with a mean basis
the coefficients' term g^T (H^T Sigma^-1 H)^-1 g at gbar = h(zbar) - H^T Sigma^-1 a (h linear
in the inputs: its mean is h at their mean). The components are independent: the output's
variance is y_sd^2 sum_j K_lj^2 of theirs. The smooth GP (no nugget or residual, which
average out over a continuum of z).

Categorical inputs and a mean basis (docs/categorical-and-constraints.md), exactly too: a
categorical input k varies uniformly over its training levels (or those ``bounds`` lists; its
kernel is exp(-beta_kj / 4 * 1[z_k != z_ik])), so each of its one-dimensional integrals is an
average over the levels and each pair integral a double average, and its effect functions are
given at its levels. A named mean basis ("constant", "linear") adds h(z)^T b_j (b_j: the GLS
coefficients, as ``Emulator.predict``) to f_j: additive in the inputs, it shifts the means and
adds to V^u_jj' the terms b_jk b_j'k Var z_k + b_j'k Cov(g_j, z_k) + b_jk Cov(g_j', z_k) for k
in u (g_j: the GP part above; Cov(E[g_j | z_u], z_k) = Cov(g_j, z_k) for k in u), the
covariances a sum over the runs of the Gaussian's first moment on the box (exp and erf terms,
``_centred_gauss``) or over the levels. A callable mean basis is refused.

Numerics: each one-dimensional integral over a narrow range (a box of width 1e-6 of the
domain, say) is computed by Gauss-Legendre quadrature rather than as a difference of error
functions, which would cancel and give indices wrong by percents; the variances are differences
of second moments, whose rounding (about 1e-11 of the variance) could still put an index of 0
or 1 just outside [0, 1], so the indices are clipped to [0, 1].
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import solve_triangular
from scipy.special import erf, erfc

from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import GPMSAError
from gpmsa.limits import check_memory
from gpmsa.model.correlation import CATEGORICAL_DISTANCE, correlation
from gpmsa.model.data import as_real, check_count, check_flag, check_level, repr_name
from gpmsa.model.transforms import snap_to_unit
from gpmsa.predictive._common import draws_text, factors, gpmsa_model_only, param_sets, unit_inputs

_SQRT_PI_2 = 0.5 * np.sqrt(np.pi)
ZERO_VARIANCE = 1e-12
NARROW = 0.5
"""sqrt(gamma) (b - a) below which a Gaussian integral is done by quadrature (``_mean_gauss``)."""
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(12)


@dataclass(frozen=True, eq=False)
class Sensitivity:
    """Sobol main- and total-effect indices of the emulator mean, per posterior draw.

    Attributes:
        names: (d,) the varied inputs (x then t names, those not in ``fixed``).
        bounds: name -> (lo, hi) native range of each varied input (uniform on it); for a
            categorical input the tuple of its levels varied over (each equally likely).
        fixed: name -> native value of each input held fixed.
        draw_index: (S,) the emulator draws used (-1: the point estimate).
        grid: (l_sim,) the output grid (or index points (l_sim, d)).
        main, total: (S, l_sim, d) indices of each output element.
        main_pc, total_pc: (S, p_u, d) indices of each basis component's weight.
        main_aggregated, total_aggregated: (S, d) indices of the output's variance summed over
            its grid (one number per input for a functional output; = main/total for l_sim 1).
        variance: (S, l_sim) variance of the emulator mean over the box, native units^2.
        mean: (S, l_sim) its mean over the box, native units.
        units: name -> unit of each varied input; y_names, y_units: (l_sim,) the outputs';
            index_names, index_units: the output index's labels (``SimData(index_names=,
            index_units=)``; None: none given).
        pairs: (P,) the pairs of varied inputs asked for (``sensitivity(pairs=)``; () if none).
        joint, interaction: (S, l_sim, P) closed joint index V_{k,l} / V and interaction index
            (V_{k,l} - V_k - V_l) / V of each pair (SEPIA's ``sje``, ``sie``); None without
            pairs. ``joint_pc``, ``interaction_pc`` (S, p_u, P) per basis component,
            ``joint_aggregated``, ``interaction_aggregated`` (S, P) over the output grid.
        effect_grid: (G, d) native values of each varied input (column k: G evenly spaced
            points over its range; a categorical input's levels) where ``main_effect`` is
            given, NaN below a column's points (G: the most levels where an input has more
            than ``main_effect_grid``); None if not asked for.
        main_effect: (S, G, l_sim, d) main-effect functions E[y | z_k = effect_grid[:, k]] of
            the emulator mean (the other inputs integrated over the box), native output units
            (SEPIA's ``mef``; NaN where the grid is); None if not asked for.
        joint_grid: (G2, d) native grid of each varied input for ``joint_effect`` (as
            ``effect_grid``); None if not asked for.
        joint_effect: (S, G2, G2, l_sim, P) joint-effect functions E[y | z_k = joint_grid[a, k],
            z_k' = joint_grid[b, k']] of each pair (k, k') (SEPIA's ``jef``); None if not asked
            for.
        groups: (n_groups,) the groups of varied inputs asked for (``sensitivity(groups=)``;
            () if none).
        group_joint: (S, l_sim, n_groups) closed joint index V_G / V of each group G (the
            variance of E[y | z_G]; SEPIA's ``sje`` of a ``jelist`` group of any size); None
            without groups. ``group_joint_pc`` (S, p_u, n_groups) per basis component,
            ``group_joint_aggregated`` (S, n_groups) over the output grid.
        main_effect_variance: (S, G, l_sim, d) the GP's own posterior variance of each
            main-effect function at its grid points (SEPIA's ``mef_v``): per draw, the variance
            of E_{z_~k}[eta(z)] given the runs (the smooth emulator: no nugget or residual),
            native output units^2; None unless ``effect_variance`` and ``main_effect_grid``.
        joint_effect_variance: (S, G2, G2, l_sim, P) the same of each joint-effect function
            (SEPIA's ``jef_v``); None unless ``effect_variance`` and ``joint_effect_grid``.
        categorical: the varied inputs that are categorical (their ``bounds`` entry: the levels
            varied over; their effect functions are given at those levels only).
    """

    names: tuple[str, ...]
    bounds: dict[str, tuple[float, float]]
    fixed: dict[str, float]
    draw_index: np.ndarray
    grid: np.ndarray
    main: np.ndarray
    total: np.ndarray
    main_pc: np.ndarray
    total_pc: np.ndarray
    main_aggregated: np.ndarray
    total_aggregated: np.ndarray
    variance: np.ndarray
    mean: np.ndarray = field(repr=False)
    units: dict[str, str] = field(default_factory=dict, repr=False)
    y_names: tuple[str, ...] = field(default=(), repr=False)
    y_units: tuple[str, ...] = field(default=(), repr=False)
    index_names: tuple[str, ...] | None = field(default=None, repr=False)
    index_units: tuple[str, ...] | None = field(default=None, repr=False)
    pairs: tuple[tuple[str, str], ...] = ()
    joint: np.ndarray | None = field(default=None, repr=False)
    interaction: np.ndarray | None = field(default=None, repr=False)
    joint_pc: np.ndarray | None = field(default=None, repr=False)
    interaction_pc: np.ndarray | None = field(default=None, repr=False)
    joint_aggregated: np.ndarray | None = field(default=None, repr=False)
    interaction_aggregated: np.ndarray | None = field(default=None, repr=False)
    effect_grid: np.ndarray | None = field(default=None, repr=False)
    main_effect: np.ndarray | None = field(default=None, repr=False)
    joint_grid: np.ndarray | None = field(default=None, repr=False)
    joint_effect: np.ndarray | None = field(default=None, repr=False)
    groups: tuple[tuple[str, ...], ...] = ()
    group_joint: np.ndarray | None = field(default=None, repr=False)
    group_joint_pc: np.ndarray | None = field(default=None, repr=False)
    group_joint_aggregated: np.ndarray | None = field(default=None, repr=False)
    main_effect_variance: np.ndarray | None = field(default=None, repr=False)
    joint_effect_variance: np.ndarray | None = field(default=None, repr=False)
    categorical: tuple[str, ...] = field(default=(), repr=False)

    def summary(self, level: float = 0.9) -> dict[str, dict[str, float]]:
        """Per input: the aggregated main and total indices, their mean, sd and central
        interval of probability ``level`` over the draws."""
        level = check_level(level)
        kinds = (("main", self.main_aggregated), ("total", self.total_aggregated))
        return {name: _spread(kinds, k, level) for k, name in enumerate(self.names)}

    def pair_summary(self, level: float = 0.9) -> dict[tuple[str, str], dict[str, float]]:
        """Per pair of ``pairs``: the aggregated joint and interaction indices, their mean, sd
        and central interval of probability ``level`` over the draws (as ``summary``)."""
        level = check_level(level)
        if self.joint_aggregated is None:
            raise GPMSAError("these indices have no pairs: call sensitivity(..., pairs=[(a, b)]) "
                             "or pairs='all'")  # fmt: skip
        kinds = (("joint", self.joint_aggregated), ("interaction", self.interaction_aggregated))
        return {pair: _spread(kinds, p, level) for p, pair in enumerate(self.pairs)}

    def group_summary(self, level: float = 0.9) -> dict[tuple[str, ...], dict[str, float]]:
        """Per group of ``groups``: the aggregated closed joint index, its mean, sd and central
        interval of probability ``level`` over the draws (``joint``, ``joint_sd``, ...)."""
        level = check_level(level)
        if self.group_joint_aggregated is None:
            raise GPMSAError("these indices have no groups: call sensitivity(..., "
                             "groups=[(a, b, c)])")  # fmt: skip
        kinds = (("joint", self.group_joint_aggregated),)
        return {group: _spread(kinds, g, level) for g, group in enumerate(self.groups)}

    def main_effect_summary(self, level: float = 0.9) -> dict[str, dict[str, np.ndarray]]:
        """Per varied input: its grid ``"grid"`` (G,) and the main-effect function's mean,
        sd and central interval of probability ``level`` over the draws, ``"mean"``, ``"sd"``,
        ``"lo"``, ``"hi"`` (G, l_sim), native output units. With ``main_effect_variance``
        also ``"gp_sd"``, the root mean over draws of the GP's variance about the curve, and
        ``"total_sd"``, the sd of the mixture over draws (law of total variance: the mean GP
        variance plus the variance of the curves over draws, ddof 0)."""
        level = check_level(level)
        if self.main_effect is None:
            raise GPMSAError("these indices have no main-effect functions: call "
                             "sensitivity(..., main_effect_grid=G)")  # fmt: skip
        q = [(1 - level) / 2, (1 + level) / 2]
        out = {}
        for k, name in enumerate(self.names):
            cur = self.main_effect[..., k]
            lo, hi = np.quantile(cur, q, axis=0)
            sd = np.std(cur, axis=0, ddof=1) if cur.shape[0] > 1 else np.zeros(cur.shape[1:])
            out[name] = {"grid": self.effect_grid[:, k], "mean": cur.mean(axis=0), "sd": sd,
                         "lo": lo, "hi": hi}  # fmt: skip
            if self.main_effect_variance is not None:
                gp = self.main_effect_variance[..., k].mean(axis=0)
                out[name]["gp_sd"] = np.sqrt(gp)
                out[name]["total_sd"] = np.sqrt(gp + np.var(cur, axis=0))
        return out

    def __repr__(self) -> str:
        d, shown = len(self.names), 4
        total = np.mean(self.total_aggregated, axis=0) if d else ()
        effects = ", ".join(f"{repr_name(n)}={v:.2f}"
                            for n, v in zip(self.names[:shown], total, strict=False))  # fmt: skip
        more = f", +{d - shown} more" if d > shown else ""
        l = np.shape(self.grid)[0]
        return (f"Sensitivity({d} inputs, {len(self.fixed)} fixed, {l} outputs, "
                f"{draws_text(self.draw_index)}, total effect: {effects}{more})")  # fmt: skip


def _spread(kinds, k: int, level: float) -> dict[str, float]:
    """Mean, sd and central interval of probability ``level`` over the draws of column ``k``
    of each (name, (S, n) array) in ``kinds``, keyed name, name_sd, name_lo, name_hi."""
    q = [(1 - level) / 2, (1 + level) / 2]
    row = {}
    for kind, arr in kinds:
        col = arr[:, k]
        lo, hi = np.quantile(col, q)
        sd = float(np.std(col, ddof=1)) if col.size > 1 else 0.0
        row.update({kind: float(col.mean()), f"{kind}_sd": sd,
                    f"{kind}_lo": float(lo), f"{kind}_hi": float(hi)})  # fmt: skip
    return row


def _mean_gauss(gamma: float, c: np.ndarray, a: float, b: float) -> np.ndarray:
    """Mean of exp(-gamma (z - c)^2) over z ~ U[a, b] (a < b), elementwise over c.

    By the error functions, their difference taken in the tail where both arguments lie
    (erfc) so that it keeps its relative accuracy; on a narrow interval (sqrt(gamma) (b - a) <
    ``NARROW``), where that difference would cancel (the interval's width is lost in the
    rounding of erf), by Gauss-Legendre quadrature, exact to rounding there.
    """
    s = np.sqrt(gamma)
    if s * (b - a) < NARROW:
        mid, half = 0.5 * (a + b), 0.5 * (b - a)
        out = np.zeros(np.shape(c))
        for node, weight in zip(_GL_NODES, _GL_WEIGHTS, strict=True):
            out += 0.5 * weight * np.exp(-gamma * (mid + half * node - c) ** 2)
        return out
    lo, hi = s * (a - c), s * (b - c)
    # reflect a range below 0 into the upper tail: erfc(-hi) - erfc(-lo) = erfc(lo') - erfc(hi')
    below = hi < 0
    lo, hi = np.where(below, -hi, lo), np.where(below, -lo, hi)
    tail = lo > 0  # both ends in the upper tail: erfc; the range straddles 0: erf
    diff = np.empty(np.shape(lo))
    diff[tail] = erfc(lo[tail]) - erfc(hi[tail])
    mid = ~tail
    diff[mid] = erf(hi[mid]) - erf(lo[mid])
    return _SQRT_PI_2 * diff / (s * (b - a))


def _pair_integral(al: float, be: float, p: np.ndarray, q: np.ndarray, a: float, b: float):
    """(m, m) means of exp(-al (z - p_i)^2 - be (z - q_i')^2) over z ~ U[a, b]."""
    g = al + be
    P, Q = p[:, None], q[None, :]
    return np.exp(-(al * be / g) * (P - Q) ** 2) * _mean_gauss(g, (al * P + be * Q) / g, a, b)


def _centred_gauss(gamma: float, c: np.ndarray, a: float, b: float) -> np.ndarray:
    """Mean of (z - (a + b) / 2) exp(-gamma (z - c)^2) over z ~ U[a, b], elementwise over c:
    the covariance of z with the Gaussian (a mean basis's linear term against the GP part).
    (c - mid) times ``_mean_gauss`` plus the difference of the two end values over 2 gamma
    (b - a); on a narrow interval (as ``_mean_gauss``) by Gauss-Legendre quadrature of the
    centred integrand, which the closed form would cancel."""
    mid, half = 0.5 * (a + b), 0.5 * (b - a)
    if np.sqrt(gamma) * (b - a) < NARROW:
        out = np.zeros(np.shape(c))
        for node, weight in zip(_GL_NODES, _GL_WEIGHTS, strict=True):
            out += 0.5 * weight * half * node * np.exp(-gamma * (mid + half * node - c) ** 2)
        return out
    ends = np.exp(-gamma * (a - c) ** 2) - np.exp(-gamma * (b - c) ** 2)
    return (c - mid) * _mean_gauss(gamma, c, a, b) + ends / (2.0 * gamma * (b - a))


def _kernel(beta: float, grid: np.ndarray, c: np.ndarray, cat: bool) -> np.ndarray:
    """(G, m) correlations of the grid values g with the runs' c in one input (the library's
    ``correlation``: exp(-beta (g - c_i)^2), or for a categorical input exp(-beta / 4 *
    1[g != c_i])); a NaN grid value (padding) gives a NaN row."""
    out = correlation(grid[:, None], c[:, None], np.array([beta]), np.array([cat]))
    out[np.isnan(grid)] = np.nan
    return out


def _single_means(zt, beta, varied, lo, hi, levels=None) -> np.ndarray:
    """I1[j, n]: (m,) means of exp(-beta_kj (z_k - z_ik)^2) over the varied input k =
    varied[n]'s range, for each basis component j: (p_u, d, m). A categorical input
    (``levels[n]``: its unit-scale level codes, each equally likely): the average over them
    of its kernel, a finite sum."""
    I1 = np.empty((beta.shape[1], len(varied), zt.shape[0]))
    for j in range(beta.shape[1]):
        for n, k in enumerate(varied):
            if levels is not None and levels[n] is not None:
                I1[j, n] = np.mean(_kernel(beta[k, j], levels[n], zt[:, k], True), axis=0)
            else:
                I1[j, n] = _mean_gauss(beta[k, j], zt[:, k], lo[n], hi[n])
    return I1


def _input_pair_integral(zt, beta, k, j, jj, lo, hi, lev) -> np.ndarray:
    """(m, m) means over input k (its box, or its levels ``lev``) of the product of component
    j's and jj's kernels at runs i and i'."""
    if lev is None:
        return _pair_integral(beta[k, j], beta[k, jj], zt[:, k], zt[:, k], lo, hi)
    Ej = _kernel(beta[k, j], lev, zt[:, k], True)
    Ejj = Ej if jj == j else _kernel(beta[k, jj], lev, zt[:, k], True)
    return (Ej.T @ Ejj) / lev.size


def _component_moments(zt, coef, beta, varied, lo, hi, I1, pairs=(), levels=None, groups=()):
    """Per pair (j, j'): the covariances V^u for u = every varied input, each single input,
    each complement, each pair (a, b) of ``pairs`` and each group of ``groups`` (positions in
    ``varied``). Returns mu (p_u,), Vall (p_u, p_u), Vmain (d, p_u, p_u), Vcomp (d, p_u, p_u),
    Vpair (P, p_u, p_u), Vgroup (n_groups, p_u, p_u). ``levels``: as ``_single_means``'."""
    levels = [None] * len(varied) if levels is None else levels
    p_u = coef.shape[0]
    d = len(varied)
    P1 = np.prod(I1, axis=1)  # (p_u, m)
    mu = np.sum(coef * P1, axis=1)  # (p_u,)
    Vall = np.empty((p_u, p_u))
    Vmain = np.empty((d, p_u, p_u))
    Vcomp = np.empty((d, p_u, p_u))
    Vpair = np.empty((len(pairs), p_u, p_u))
    Vgroup = np.empty((len(groups), p_u, p_u))
    for j in range(p_u):
        for jj in range(j, p_u):
            I2 = [_input_pair_integral(zt, beta, k, j, jj, lo[n], hi[n], levels[n])
                  for n, k in enumerate(varied)]  # fmt: skip
            prefix = [np.ones_like(I2[0])]
            for M in I2:
                prefix.append(prefix[-1] * M)
            suffix = [np.ones_like(I2[0])]
            for M in reversed(I2):
                suffix.append(suffix[-1] * M)
            suffix = suffix[::-1]  # suffix[n] = product of I2[n:]
            base = mu[j] * mu[jj]
            Vall[j, jj] = coef[j] @ prefix[d] @ coef[jj] - base
            for n in range(d):
                rest_j = np.prod(np.delete(I1[j], n, axis=0), axis=0)
                rest_jj = np.prod(np.delete(I1[jj], n, axis=0), axis=0)
                Vmain[n, j, jj] = (coef[j] * rest_j) @ I2[n] @ (coef[jj] * rest_jj) - base
                comp = prefix[n] * suffix[n + 1]
                Vcomp[n, j, jj] = (coef[j] * I1[j, n]) @ comp @ (coef[jj] * I1[jj, n]) - base
            for p, (a, b) in enumerate(pairs):
                rest_j = np.prod(np.delete(I1[j], (a, b), axis=0), axis=0)
                rest_jj = np.prod(np.delete(I1[jj], (a, b), axis=0), axis=0)
                Vpair[p, j, jj] = (coef[j] * rest_j) @ (I2[a] * I2[b]) @ (coef[jj] * rest_jj) - base
            for g, group in enumerate(groups):  # as a pair's, the group's pair integrals multiplied
                rest_j = np.prod(np.delete(I1[j], group, axis=0), axis=0)
                rest_jj = np.prod(np.delete(I1[jj], group, axis=0), axis=0)
                inner = I2[group[0]] * I2[group[1]]
                for n in group[2:]:
                    inner = inner * I2[n]
                Vgroup[g, j, jj] = (coef[j] * rest_j) @ inner @ (coef[jj] * rest_jj) - base
            Vall[jj, j] = Vall[j, jj]
            Vmain[:, jj, j] = Vmain[:, j, jj]
            Vcomp[:, jj, j] = Vcomp[:, j, jj]
            Vpair[:, jj, j] = Vpair[:, j, jj]
            Vgroup[:, jj, j] = Vgroup[:, j, jj]
    return mu, Vall, Vmain, Vcomp, Vpair, Vgroup


def _main_effects(zt, coef, beta, varied, I1, grid, cat=None) -> np.ndarray:
    """(p_u, G, d) E[f_j | z_k = grid[:, n]] (k = varied[n]; unit scale, standardised), the
    other varied inputs integrated out (their I1). ``cat[n]``: input n is categorical (its
    column of ``grid`` holds its level codes, NaN-padded: NaN rows out)."""
    p_u, d = coef.shape[0], len(varied)
    cat = [False] * d if cat is None else cat
    out = np.empty((p_u, grid.shape[0], d))
    for j in range(p_u):
        for n, k in enumerate(varied):
            rest = np.prod(np.delete(I1[j], n, axis=0), axis=0)
            out[j, :, n] = _kernel(beta[k, j], grid[:, n], zt[:, k], cat[n]) @ (coef[j] * rest)
    return out


def _joint_effects(zt, coef, beta, varied, I1, grid, pairs, cat=None) -> np.ndarray:
    """(p_u, G2, G2, P) E[f_j | z_k = grid[a_idx, a], z_k' = grid[b_idx, b]] for each pair
    (a, b) of positions in ``varied`` (unit scale, standardised; ``cat`` as
    ``_main_effects``')."""
    p_u = coef.shape[0]
    cat = [False] * len(varied) if cat is None else cat
    out = np.empty((p_u, grid.shape[0], grid.shape[0], len(pairs)))
    for j in range(p_u):
        for p, (a, b) in enumerate(pairs):
            ka, kb = varied[a], varied[b]
            rest = coef[j] * np.prod(np.delete(I1[j], (a, b), axis=0), axis=0)
            Ga = _kernel(beta[ka, j], grid[:, a], zt[:, ka], cat[a])
            Gb = _kernel(beta[kb, j], grid[:, b], zt[:, kb], cat[b])
            out[j, :, :, p] = (Ga * rest) @ Gb.T
    return out


def _double_mean(beta: float, a: float, b: float) -> float:
    """Mean of exp(-beta (z - z')^2) over z, z' independent U[a, b]: 2 int_0^1 (1 - u)
    exp(-x^2 u^2) du = sqrt(pi) erf(x) / x - (1 - exp(-x^2)) / x^2 with x = sqrt(beta) (b - a)
    (the terms tend to 2 and 1 as x -> 0: no cancellation); its series 1 - x^2 / 6 + x^4 / 30
    below x = 1e-3, where x^2 could underflow."""
    x = float(np.sqrt(beta) * (b - a))
    if x < 1e-3:
        return 1.0 - x * x / 6.0 + x**4 / 30.0
    return float(np.sqrt(np.pi) * erf(x) / x + np.expm1(-x * x) / (x * x))


def _double_means(beta, varied, lo, hi, levels) -> np.ndarray:
    """DD[j, n]: (p_u, d) means of component j's kernel in the varied input k = varied[n] over
    two independent points of its range (``_double_mean``), or of its levels (a double
    average of the categorical kernel): the GP prior's covariance integrated twice."""
    DD = np.empty((beta.shape[1], len(varied)))
    for j in range(beta.shape[1]):
        for n, k in enumerate(varied):
            if levels is not None and levels[n] is not None:
                DD[j, n] = np.mean(_kernel(beta[k, j], levels[n], levels[n], True))
            else:
                DD[j, n] = _double_mean(beta[k, j], lo[n], hi[n])
    return DD


def _basis_at(basis, z_bar: np.ndarray, varied, cols, points):
    """A mean basis's h (N, k) at the unit-scale points with inputs ``cols`` (positions in
    ``varied``) at ``points`` and every other input at ``z_bar`` (a varied one's mean over the
    box, a fixed one's value): h's mean over the other inputs, h being linear in them. None
    without a basis."""
    if basis is None:
        return None
    z = np.repeat(z_bar[None, :], points[0].shape[0], axis=0)
    for c, pt in zip(cols, points, strict=True):
        z[:, varied[c]] = pt
    return basis.matrix(z)


def _times_fixed_kernels(arr, fix_u: dict, levels_all, beta, zt) -> np.ndarray:
    """``arr`` (p_u, m) times each fixed input's kernel between its value and the runs (per
    component; the categorical kernel for a categorical input), one input after another."""
    for k, u in fix_u.items():
        if levels_all[k] is not None:
            dist = CATEGORICAL_DISTANCE * (u != zt[None, :, k])
            arr = arr * np.exp(-beta[k][:, None] * dist)
        else:
            arr = arr * np.exp(-beta[k][:, None] * (u - zt[None, :, k]) ** 2)
    return arr


def _effect_variances(zt, beta, lam, fac, varied, I1, DD, fixf, cols, points, cat, hbar=None):
    """(p_u, N) the GP posterior variance of E[w_j(z) | z_cols = points] (the other varied
    inputs integrated over the box; unit scale, standardised; the smooth GP: no nugget) for
    each component j, at N points (``points``: per position in ``cols`` (N,) unit-scale
    values; a NaN gives NaN):

        prod_{n not in cols} DD[j, n] / lamUz_j - |L_j^-1 a|^2  (+ gbar^T Q_j^-1 gbar),
        a = fixf_j rest_j prod_{c in cols} R_c(points_c, zt_c) / lamUz_j   (m, N),

    the double integral of the posterior covariance over the other inputs: the prior's kernel
    integrated twice (``DD``), the runs' share by their single means (``I1``, rest_j: those of
    the inputs not in cols; fixf_j: the fixed inputs' kernels) and, with a mean basis, the
    coefficients' share at the basis's mean ``hbar`` (N, k) (gbar = hbar^T - A^T L^-1 a).
    ``fac``: per component (L, alpha, gls or None)."""
    p_u, N = beta.shape[1], points[0].shape[0]
    ok = np.all([np.isfinite(pt) for pt in points], axis=0)
    out = np.full((p_u, N), np.nan)
    for j, f in enumerate(fac):
        L, gls = f[0], f[2] if len(f) > 2 else None
        rest = np.prod(np.delete(I1[j], cols, axis=0), axis=0) * fixf[j]
        A = np.repeat((rest / lam[j])[:, None], int(ok.sum()), axis=1)
        for c, pt in zip(cols, points, strict=True):
            A *= _kernel(beta[varied[c], j], pt[ok], zt[:, varied[c]], cat[c]).T
        B = solve_triangular(L, A, lower=True)
        v = np.prod(np.delete(DD[j], cols)) / lam[j] - np.sum(B * B, axis=0)
        if gls is not None:
            v = v + gls.variance(hbar[ok], B)
        out[j, ok] = np.maximum(v, 0.0)
    return out


@dataclass(frozen=True, eq=False)
class _Trend:
    """A named mean basis's part h(z)^T b_j of each component's mean on the box (unit scale,
    standardised): ``const`` (p_u,) its mean over the box, ``slope`` (p_u, d) its coefficient
    of each varied input (0 for "constant"), ``centre``, ``var`` (d,) each varied input's mean
    and variance over the box (uniform, or over its levels)."""

    const: np.ndarray
    slope: np.ndarray
    centre: np.ndarray
    var: np.ndarray

    @classmethod
    def of(cls, coefs, kind: str, varied, fix_u: dict, lo, hi, levels) -> _Trend:
        """From the GLS coefficients ``coefs`` (p_u, k) of a mean basis ``kind``."""
        centre = np.array([0.5 * (a + b) if lv is None else float(np.mean(lv))
                           for a, b, lv in zip(lo, hi, levels, strict=True)])  # fmt: skip
        var = np.array([(b - a) ** 2 / 12.0 if lv is None else float(np.var(lv))
                        for a, b, lv in zip(lo, hi, levels, strict=True)])  # fmt: skip
        const = coefs[:, 0].copy()
        slope = np.zeros((coefs.shape[0], len(varied)))
        if kind == "linear":  # h = [1, z_1, ..., z_{p+q}]
            slope = coefs[:, 1:][:, varied]
            const += slope @ centre
            for k, u in fix_u.items():
                const += coefs[:, 1 + k] * u
        return cls(const, slope, centre, var)

    def covariances(self, zt, coef, beta, varied, lo, hi, I1, levels) -> np.ndarray:
        """D (d, p_u, p_u): the trend's share of Cov(E[f_j | z_u], E[f_j' | z_u]) from each
        varied input n in u: b_j'n Cov(g_j, z_n) + b_jn Cov(g_j', z_n) + b_jn b_j'n Var z_n,
        where g_j is the GP part (Cov(E[g_j | z_u], z_n) = Cov(g_j, z_n) for n in u), a sum
        over the runs of a centred first moment (``_centred_gauss``, or over the levels)."""
        p_u, d = coef.shape[0], len(varied)
        C = np.zeros((p_u, d))  # Cov(g_j, z_n)
        for j in range(p_u):
            for n, k in enumerate(varied):
                if not self.slope[:, n].any():
                    continue
                rest = np.prod(np.delete(I1[j], n, axis=0), axis=0)
                if levels[n] is None:
                    T = _centred_gauss(beta[k, j], zt[:, k], lo[n], hi[n])
                else:
                    E = _kernel(beta[k, j], levels[n], zt[:, k], True)
                    T = np.mean((levels[n] - self.centre[n])[:, None] * E, axis=0)
                C[j, n] = (coef[j] * rest) @ T
        b = self.slope
        return (np.einsum("jn,kn->njk", C, b) + np.einsum("jn,kn->njk", b, C)
                + np.einsum("jn,kn,n->njk", b, b, self.var))  # fmt: skip


def _memory_estimate(
    m: int,
    d: int,
    p_u: int,
    S: int,
    l_sim: int,
    n_pairs: int = 0,
    n_grid: int = 0,
    n_joint: int = 0,
    n_groups: int = 0,
    effect_variance: bool = False,
) -> float:
    """Bytes that ``sensitivity`` needs at once: per draw the factors of Sigma_W (about 2 p_u
    + 2 arrays m x m) and ``_component_moments``' pair integrals with their prefix and suffix
    products (about 4 d + 6 of them; the peaks measured for m = 200, d <= 6, p_u <= 4 stayed
    below this), and the indices kept over the S draws. With ``n_pairs`` pairs: two m x m
    arrays more (a pair's product and its matrix-vector product's temporaries) and 6 indices
    per pair, output element and component per draw; with a main-effect grid of ``n_grid``
    points: its (n_grid, m) Gaussians and the curves (S, n_grid, l_sim, d) with their
    per-draw pieces; with a joint grid of ``n_joint`` points: two (n_joint, m) Gaussians and
    the surfaces (S, n_joint^2, l_sim, n_pairs) with theirs. With ``n_groups`` groups: as
    pairs, two m x m arrays more and 3 indices per group, output element and component per
    draw. With ``effect_variance``: the curves and surfaces once more, and the (m, G) and
    (m, G2^2) kernel products with their triangular solves (3 arrays each)."""
    return 8.0 * (
        m * m * (4.0 * d + 8.0 + 2.0 * p_u + (2.0 if n_pairs or n_groups else 0.0))
        + S * (2.0 * d * (l_sim + p_u + 1) + 2.0 * l_sim)
        + 2.0 * S * n_pairs * (l_sim + p_u + 1)
        + S * n_groups * (l_sim + p_u + 1)
        + n_grid * (2.0 * m + (S + 2.0) * l_sim * d + p_u * d)
        + n_joint * (3.0 * m + n_joint * n_pairs * ((S + 2.0) * l_sim + p_u))
        + (
            n_grid * (3.0 * m + (S + 2.0) * l_sim * d + p_u * d)
            + n_joint * n_joint * (3.0 * m + n_pairs * ((S + 2.0) * l_sim + p_u))
            if effect_variance
            else 0.0
        )
    )


def _ratio(num: np.ndarray, den: np.ndarray, scale: float) -> np.ndarray:
    """The variance share num / den clipped to [0, 1] (the rounding left in the differences
    of second moments, about 1e-11 of the variance, can put a share of 0 or 1 just outside);
    NaN where den is below ``ZERO_VARIANCE`` * scale (an index is undefined there)."""
    ok = den > ZERO_VARIANCE * scale
    return np.where(ok, np.clip(num / np.where(ok, den, 1.0), 0.0, 1.0), np.nan)


def _level_set(value, levels: tuple[int, ...], name: str) -> tuple[int, ...]:
    """A categorical input's ``bounds`` entry: the sorted training levels it lists (at least
    2, each once); GPMSAError naming the input otherwise."""
    if isinstance(value, str) or not isinstance(value, list | tuple | set | frozenset | np.ndarray):
        raise GPMSAError(f"bounds[{name!r}]: {name} is categorical; give the levels to vary over "
                         f"(a list of at least 2 of {list(levels)}), got {value!r}")  # fmt: skip
    out = []
    for v in value:
        v = as_real(v, f"bounds[{name!r}] level")
        if v not in levels:
            raise GPMSAError(f"bounds[{name!r}] lists level {v:g}, not a training level of the "
                             f"categorical input {name} (levels {list(levels)})")  # fmt: skip
        if int(v) in out:
            raise GPMSAError(f"bounds[{name!r}] lists level {v:g} twice")
        out.append(int(v))
    if len(out) < 2:
        raise GPMSAError(f"bounds[{name!r}] must list at least 2 levels of {list(levels)}, got "
                         f"{value!r} (hold one level with fixed={{{name!r}: level}})")  # fmt: skip
    return tuple(sorted(out))


def _effect_grids(n: int, rows: int, lo_n, hi_n, lo_u, hi_u, lev_n, lev_u):
    """(native, unit) grids (rows, d) of the effect functions: n evenly spaced points over each
    continuous input's range, a categorical input's levels; NaN below (rows = max(n, the most
    levels))."""
    native, unit = np.full((rows, len(lev_n)), np.nan), np.full((rows, len(lev_n)), np.nan)
    native[:n], unit[:n] = np.linspace(lo_n, hi_n, n), np.linspace(lo_u, hi_u, n)
    for c, (lev, u) in enumerate(zip(lev_n, lev_u, strict=True)):
        if lev is not None:
            native[:, c], unit[:, c] = np.nan, np.nan
            native[: len(lev), c], unit[: len(lev), c] = lev, u
    return native, unit


def _name_dict(value, what: str) -> dict:
    """``value`` (None or a dict keyed by input names) as a dict; GPMSAError otherwise."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise GPMSAError(f"{what} must be None or a dict input name -> value, got {value!r}")
    return dict(value)


def _pair_positions(pairs, names: list[str], fixed: dict) -> list[tuple[int, int]]:
    """``pairs`` ("all", or pairs of varied input names) as positions in ``names``;
    GPMSAError naming the problem (a name unknown or fixed, one input twice, a pair twice)."""
    if isinstance(pairs, str):
        if pairs != "all":
            raise GPMSAError(f"pairs must be 'all' or a list of pairs of input names, got "
                             f"{pairs!r}")  # fmt: skip
        if len(names) < 2:
            raise GPMSAError(f"pairs='all' needs at least 2 varied inputs; {tuple(names)} vary")
        return list(itertools.combinations(range(len(names)), 2))
    if not isinstance(pairs, list | tuple) or not pairs:
        raise GPMSAError(f"pairs must be 'all' or a non-empty list of pairs of input names, "
                         f"e.g. [('a', 'b')], got {pairs!r}")  # fmt: skip
    out, seen = [], set()
    for pair in pairs:
        if isinstance(pair, str) or not isinstance(pair, list | tuple) or len(pair) != 2:
            raise GPMSAError(f"each of pairs must be a pair of input names (a, b), got {pair!r} "
                             f"(one pair: pairs=[(a, b)])")  # fmt: skip
        _check_varied(pair, names, fixed, "pairs")
        if pair[0] == pair[1]:
            raise GPMSAError(f"pairs names one input twice in {tuple(pair)}; a pair is two inputs")
        key = frozenset(pair)
        if key in seen:
            raise GPMSAError(f"pairs lists the pair {tuple(pair)} twice")
        seen.add(key)
        out.append((names.index(pair[0]), names.index(pair[1])))
    return out


def _check_varied(inputs, names: list[str], fixed: dict, arg: str) -> None:
    """GPMSAError unless each of ``inputs`` (of argument ``arg``: "pairs", "groups") names a
    varied input of ``names`` (one held by ``fixed`` or unknown named)."""
    for name in inputs:
        if name in fixed:
            raise GPMSAError(f"{arg} names {name!r}, an input held fixed; the varied inputs are "
                             f"{tuple(names)}")  # fmt: skip
        if not isinstance(name, str) or name not in names:
            raise GPMSAError(f"{arg} names an unknown input {name!r}; the varied inputs are "
                             f"{tuple(names)}")  # fmt: skip


def _group_positions(groups, names: list[str], fixed: dict) -> list[tuple[int, ...]]:
    """``groups`` (a list of groups of at least 2 varied input names) as tuples of positions in
    ``names``; GPMSAError naming the problem (a name unknown or fixed, an input twice in a
    group, a group listed twice in any order, a string where a group belongs)."""
    if not isinstance(groups, list | tuple) or not groups:
        raise GPMSAError(f"groups must be a non-empty list of groups of input names, e.g. "
                         f"[('a', 'b', 'c')], got {groups!r}")  # fmt: skip
    out, seen = [], set()
    for group in groups:
        if isinstance(group, str) or not isinstance(group, list | tuple) or len(group) < 2:
            raise GPMSAError(f"each of groups must be a tuple of at least 2 input names, got "
                             f"{group!r} (one group: groups=[('a', 'b', 'c')]; one input's "
                             f"index is main)")  # fmt: skip
        _check_varied(group, names, fixed, "groups")
        if len(set(group)) != len(group):
            raise GPMSAError(f"groups names an input twice in {tuple(group)}")
        key = frozenset(group)
        if key in seen:
            raise GPMSAError(f"groups lists the group {tuple(group)} twice")
        seen.add(key)
        out.append(tuple(names.index(name) for name in group))
    return out


@underflow_as_zero
def sensitivity(
    emulator,
    *,
    bounds: dict | None = None,
    fixed: dict | None = None,
    draws: bool = True,
    n_draws: int | None = 100,
    pairs: str | list | None = None,
    main_effect_grid: int | None = None,
    joint_effect_grid: int | None = None,
    groups: list | None = None,
    effect_variance: bool = False,
    progress: bool = False,
) -> Sensitivity:
    """Sobol main- and total-effect indices of the emulator's mean, over posterior draws.

    Args:
        emulator: a fitted gpmsa.Emulator.
        bounds: name -> (lo, hi), native units: the uniform range of an input (default: the
            emulator's training domain). Beyond the domain: a warning; more than
            ``EXTRAPOLATION_MARGIN`` (10 %) of its width beyond: GPMSAError. A categorical
            input: a list of at least 2 of its training levels, each equally likely (default:
            every training level; ``[0, 2]`` means levels 0 and 2, not a range).
        fixed: name -> native value of inputs held fixed (not varied; e.g. a known input at its
            operating point; a categorical input at one of its training levels).
        draws: indices for each retained posterior draw (True) or the point estimate only.
        n_draws: at most this many draws, evenly spaced (None: all retained draws).
        pairs: pairs of varied inputs, [("a", "b"), ...], or "all": their closed joint and
            two-factor interaction indices (``joint``, ``interaction``; SEPIA's ``jelist``
            and ``varlist`` of pairs).
            None (default): none.
        main_effect_grid: G >= 2 points per varied input, evenly spaced over its range (a
            categorical input: its levels): the main-effect functions E[y | z_k] there
            (``main_effect``, ``effect_grid``; SEPIA's ``ngrid``). None (default): none.
        joint_effect_grid: G2 >= 2 points per input of each pair: the joint-effect functions
            E[y | z_k, z_k'] on the G2 x G2 grid (``joint_effect``, ``joint_grid``); needs
            ``pairs``. None (default): none.
        groups: groups of at least 2 varied inputs, [("a", "b", "c"), ...]: the closed joint
            index V_G / V of each (``group_joint``, with ``_pc`` and ``_aggregated``;
            ``group_summary()``; SEPIA's ``jelist`` of any size; a group of two is the pair's
            ``joint``). None (default): none.
        effect_variance: also the GP's own posterior variance about each main-effect and
            joint-effect function, per draw (``main_effect_variance``,
            ``joint_effect_variance``; SEPIA's ``mef_v``, ``jef_v``); needs
            ``main_effect_grid`` or ``joint_effect_grid``. False (default): not computed.
        progress: show a tqdm bar over the draws on stderr ("sensitivity"; each draw
            integrates the runs' kernels pairwise: about 40 s for 264 runs, 8 components and
            100 draws); none at the point estimate (``draws=False``).

    Returns:
        Sensitivity with indices per draw, per output element, per basis component and
        aggregated over the output grid (and, when asked for, per pair and the effect
        functions per draw).

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(40, 1)), rng.uniform(size=(40, 2))
        >>> y = x + 0.3 * t[:, :1] + 0.0 * t[:, 1:]           # no effect of t1
        >>> data = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["a", "b"])
        >>> emu = gpmsa.fit(data, n_iter=60, tune=False, seed=0)
        >>> sens = gpmsa.sensitivity(emu, n_draws=10)
        >>> sens.names, sens.main.shape        # (draws, outputs, inputs)
        (('x', 'a', 'b'), (10, 1, 3))
        >>> s = sens.summary()
        >>> s["x"]["main"] > 0.8 and s["b"]["total"] < 0.05
        True
        >>> sens = gpmsa.sensitivity(emu, n_draws=10, pairs="all", main_effect_grid=5)
        >>> sens.pairs, sens.interaction.shape, sens.main_effect.shape   # (S, G, l_sim, d)
        ((('x', 'a'), ('x', 'b'), ('a', 'b')), (10, 1, 3), (10, 5, 1, 3))
    """
    gpmsa_model_only(emulator, "sensitivity", callable_basis=False)
    std = emulator.standardizer
    levels_all = tuple(emulator.levels)
    names = tuple(emulator.x_names) + tuple(emulator.t_names)
    lo_all = np.concatenate([std.x_min, std.t_min])
    hi_all = np.concatenate([std.x_max, std.t_max])
    draws, progress = check_flag(draws, "draws"), check_flag(progress, "progress")
    bounds, fixed = _name_dict(bounds, "bounds"), _name_dict(fixed, "fixed")
    for what, given in (("bounds", bounds), ("fixed", fixed)):
        unknown = sorted(set(given) - set(names), key=str)
        if unknown:
            raise GPMSAError(f"{what} names unknown inputs {unknown}; the inputs are {names}")
    both = sorted(set(bounds) & set(fixed))
    if both:
        raise GPMSAError(f"inputs {both} are both in bounds and in fixed")
    varied = [k for k, n in enumerate(names) if n not in fixed]
    if not varied:
        raise GPMSAError("every input is fixed; nothing to vary")
    lo_n, hi_n, box, lev_n = [], [], {}, []
    for k in varied:
        name = names[k]
        if levels_all[k] is not None:  # categorical: the levels varied over, equally likely
            lev = _level_set(bounds.get(name, levels_all[k]), levels_all[k], name)
            lo_n.append(float(lev[0]))
            hi_n.append(float(lev[-1]))
            box[name] = lev
            lev_n.append(lev)
            continue
        lev_n.append(None)
        pair = bounds.get(name, (lo_all[k], hi_all[k]))
        if not isinstance(pair, (list, tuple, np.ndarray)) or len(pair) != 2:
            raise GPMSAError(f"bounds[{name!r}] must be (lo, hi), got {pair!r}")
        a, b = (as_real(v, f"bounds[{name!r}]") for v in pair)
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise GPMSAError(f"bounds[{name!r}] must be finite with lo < hi, got ({a}, {b})")
        lo_n.append(a)
        hi_n.append(b)
        box[name] = (a, b)
    k_names = [names[k] for k in varied]
    pair_pos = [] if pairs is None else _pair_positions(pairs, k_names, fixed)
    group_pos = [] if groups is None else _group_positions(groups, k_names, fixed)
    n_grid = 0 if main_effect_grid is None else check_count(main_effect_grid, "main_effect_grid", 2)
    n_joint = 0
    if joint_effect_grid is not None:
        n_joint = check_count(joint_effect_grid, "joint_effect_grid", 2)
        if not pair_pos:
            raise GPMSAError("joint_effect_grid needs pairs (whose joint-effect functions to "
                             "compute): pass pairs=[(a, b)] or pairs='all'")  # fmt: skip
    effect_variance = check_flag(effect_variance, "effect_variance")
    if effect_variance and not (n_grid or n_joint):
        raise GPMSAError("effect_variance=True needs main_effect_grid or joint_effect_grid (the "
                         "effect functions whose GP variance to compute)")  # fmt: skip
    _, ends = unit_inputs([lo_n, hi_n], k_names, lo_all[varied], hi_all[varied], "bounds")
    lo_u, hi_u = ends[0], ends[1]
    # a categorical input's unit-scale level codes (as the standardiser maps the design)
    lev_u = [None if lev is None else snap_to_unit((np.asarray(lev, dtype=float) - lo_all[k])
                                                   / (hi_all[k] - lo_all[k]))
             for lev, k in zip(lev_n, varied, strict=True)]  # fmt: skip
    cat = [lev is not None for lev in lev_n]
    zt = emulator.zt.copy()
    fix_u = {}
    fixed = {name: as_real(value, f"fixed[{name!r}]") for name, value in fixed.items()}
    for name, value in fixed.items():
        k = names.index(name)
        if levels_all[k] is not None and value not in levels_all[k]:
            raise GPMSAError(f"fixed[{name!r}] = {value:g}: {name} is categorical; fix it at one "
                             f"of its training levels {list(levels_all[k])}")  # fmt: skip
        _, u = unit_inputs(
            [[value]], [name], lo_all[k : k + 1], hi_all[k : k + 1], f"fixed[{name!r}]"
        )
        fix_u[k] = float(u[0, 0])
    idx, sets = param_sets(emulator, draws, n_draws, "sensitivity")
    S, l_sim, p_u, d = len(sets), emulator.l_sim, emulator.p_u, len(varied)
    P, n_groups = len(pair_pos), len(group_pos)
    n_lev = max([lev.size for lev in lev_u if lev is not None], default=0)
    rows, rows_joint = max(n_grid, n_lev) if n_grid else 0, max(n_joint, n_lev) if n_joint else 0
    extra = "".join([f", {P} pairs" if P else "", f", {n_groups} groups" if n_groups else "",
                     f", main effects on {n_grid} points" if n_grid else "",
                     f", joint effects on {n_joint}^2 points" if n_joint else "",
                     " with their GP variance" if effect_variance else ""])  # fmt: skip
    check_memory(_memory_estimate(emulator.m, d, p_u, S, l_sim, P, rows, rows_joint, n_groups,
                                  effect_variance),
                 f"sensitivity() of an emulator of {emulator.m} runs x {p_u} basis components "
                 f"over {d} varied inputs{extra} (about {4 * d + 8 + 2 * p_u} arrays of "
                 f"{emulator.m} x {emulator.m} at once)")  # fmt: skip
    KtK = emulator.K.T @ emulator.K
    K = emulator.K
    out = {k: np.empty((S, l_sim, d)) for k in ("main", "total")}
    out_pc = {k: np.empty((S, p_u, d)) for k in ("main", "total")}
    out_agg = {k: np.empty((S, d)) for k in ("main", "total")}
    variance = np.empty((S, l_sim))
    mean = np.empty((S, l_sim))
    out_pair = {k: np.empty((S, l_sim, P)) for k in ("joint", "interaction")} if P else {}
    out_pair_pc = {k: np.empty((S, p_u, P)) for k in ("joint", "interaction")} if P else {}
    out_pair_agg = {k: np.empty((S, P)) for k in ("joint", "interaction")} if P else {}
    a_pos, b_pos = [a for a, _ in pair_pos], [b for _, b in pair_pos]
    out_group = np.empty((S, l_sim, n_groups)) if n_groups else None
    out_group_pc = np.empty((S, p_u, n_groups)) if n_groups else None
    out_group_agg = np.empty((S, n_groups)) if n_groups else None
    y_mean, y_sd = np.asarray(std.y_mean, dtype=float), std.y_sd
    sd_col = np.reshape(y_sd, (-1, 1))  # along the output axis of the effects (l, ...)
    effect_grid = main_effect = joint_grid = joint_effect = None
    main_var = joint_var = None
    if n_grid:
        effect_grid, grid_u = _effect_grids(n_grid, rows, lo_n, hi_n, lo_u, hi_u, lev_n, lev_u)
        main_effect = np.empty((S, rows, l_sim, d))
        main_var = np.empty((S, rows, l_sim, d)) if effect_variance else None
    if n_joint:
        joint_grid, joint_u = _effect_grids(n_joint, rows_joint, lo_n, hi_n, lo_u, hi_u, lev_n,
                                            lev_u)  # fmt: skip
        joint_effect = np.empty((S, rows_joint, rows_joint, l_sim, P))
        joint_var = np.empty((S, rows_joint, rows_joint, l_sim, P)) if effect_variance else None
    basis = emulator.mean_basis
    special = basis is not None or any(lv is not None for lv in levels_all)
    lev_arg = lev_u if any(cat) else None
    if effect_variance:  # the mean basis's h at each grid point, the other inputs at their mean
        centre = np.array([0.5 * (a + b) if lv is None else float(np.mean(lv))
                           for a, b, lv in zip(lo_u, hi_u, lev_u, strict=True)])  # fmt: skip
        z_bar = np.empty(len(names))
        z_bar[varied] = centre
        for k, u in fix_u.items():
            z_bar[k] = u
    with one_thread(), progress_bar(progress and draws, S, "sensitivity") as bar:
        for i, prm in enumerate(sets):
            beta = prm["betaU"]
            trend = None
            if special:  # the emulator's own factors: the categorical kernel, the GLS mean
                fac = emulator._factor(prm)
                coef = np.array([alpha / prm["lamUz"][j] for j, (_, alpha, _) in
                                 enumerate(fac)])  # fmt: skip
                if basis is not None:
                    trend = _Trend.of(np.array([g.coef for _, _, g in fac]), basis.kind, varied,
                                      fix_u, lo_u, hi_u, lev_u)  # fmt: skip
            else:
                fac = factors(emulator, prm)
                coef = np.array([alpha / prm["lamUz"][j] for j, (_, alpha) in
                                 enumerate(fac)])  # fmt: skip
            coef = _times_fixed_kernels(coef, fix_u, levels_all, beta, zt)
            I1 = _single_means(zt, beta, varied, lo_u, hi_u, lev_arg)
            mu, Vall, Vmain, Vcomp, Vpair, Vgroup = _component_moments(
                zt, coef, beta, varied, lo_u, hi_u, I1, pair_pos, lev_arg, group_pos
            )
            if trend is not None:  # the mean basis's part, additive in the inputs
                D = trend.covariances(zt, coef, beta, varied, lo_u, hi_u, I1, lev_u)
                mu = mu + trend.const
                Vall = Vall + D.sum(axis=0)
                Vcomp = Vcomp + (D.sum(axis=0) - D)
                Vmain = Vmain + D
                Vpair = Vpair + D[a_pos] + D[b_pos]
                for g, group in enumerate(group_pos):
                    Vgroup[g] = Vgroup[g] + D[list(group)].sum(axis=0)
            v_l = np.einsum("lj,jk,lk->l", K, Vall, K)
            scale = max(float(v_l.max()), 1e-300)
            main_l = np.einsum("lj,njk,lk->ln", K, Vmain, K)
            comp_l = np.einsum("lj,njk,lk->ln", K, Vcomp, K)
            out["main"][i] = _ratio(main_l, v_l[:, None], scale)
            out["total"][i] = 1.0 - _ratio(comp_l, v_l[:, None], scale)
            v_pc = np.diag(Vall)
            scale_pc = max(float(v_pc.max()), 1e-300)
            out_pc["main"][i] = _ratio(np.diagonal(Vmain, axis1=1, axis2=2).T, v_pc[:, None],
                                       scale_pc)  # fmt: skip
            out_pc["total"][i] = 1.0 - _ratio(np.diagonal(Vcomp, axis1=1, axis2=2).T,
                                              v_pc[:, None], scale_pc)  # fmt: skip
            v_sum = float(np.sum(KtK * Vall))
            scale_sum = max(v_sum, 1e-300)
            out_agg["main"][i] = _ratio(np.einsum("jk,njk->n", KtK, Vmain), v_sum, scale_sum)
            out_agg["total"][i] = 1.0 - _ratio(np.einsum("jk,njk->n", KtK, Vcomp), v_sum,
                                               scale_sum)  # fmt: skip
            variance[i] = v_l * std.y_sd**2
            mean[i] = K @ mu * std.y_sd + std.y_mean
            if P:
                # V_{k,l} and its interaction part V_{k,l} - V_k - V_l, per output element,
                # component and summed over the grid, each over the variance as above
                Vint = Vpair - Vmain[a_pos] - Vmain[b_pos]
                for kind, Vu in (("joint", Vpair), ("interaction", Vint)):
                    out_pair[kind][i] = _ratio(np.einsum("lj,njk,lk->ln", K, Vu, K),
                                               v_l[:, None], scale)  # fmt: skip
                    out_pair_pc[kind][i] = _ratio(np.diagonal(Vu, axis1=1, axis2=2).T,
                                                  v_pc[:, None], scale_pc)  # fmt: skip
                    out_pair_agg[kind][i] = _ratio(np.einsum("jk,njk->n", KtK, Vu), v_sum,
                                                   scale_sum)  # fmt: skip
            if n_groups:
                out_group[i] = _ratio(np.einsum("lj,njk,lk->ln", K, Vgroup, K), v_l[:, None],
                                      scale)  # fmt: skip
                out_group_pc[i] = _ratio(np.diagonal(Vgroup, axis1=1, axis2=2).T, v_pc[:, None],
                                         scale_pc)  # fmt: skip
                out_group_agg[i] = _ratio(np.einsum("jk,njk->n", KtK, Vgroup), v_sum, scale_sum)
            if effect_variance:
                ones = np.ones((p_u, zt.shape[0]))  # the fixed inputs' kernels, as coef's
                fixf = _times_fixed_kernels(ones, fix_u, levels_all, beta, zt)
                DD = _double_means(beta, varied, lo_u, hi_u, lev_arg)
                shared = (zt, beta, prm["lamUz"], fac, varied, I1, DD, fixf)
                K2 = K * K
                if n_grid:
                    V = np.empty((p_u, rows, d))
                    for n in range(d):
                        pts = [grid_u[:, n]]
                        hbar = _basis_at(basis, z_bar, varied, (n,), pts)
                        V[..., n] = _effect_variances(*shared, (n,), pts, cat, hbar)
                    main_var[i] = sd_col**2 * np.einsum("lj,jgn->gln", K2, V)
                if n_joint:
                    V = np.empty((p_u, rows_joint, rows_joint, P))
                    for p, (a, b) in enumerate(pair_pos):
                        ga, gb = np.meshgrid(joint_u[:, a], joint_u[:, b], indexing="ij")
                        pts = [ga.ravel(), gb.ravel()]
                        hbar = _basis_at(basis, z_bar, varied, (a, b), pts)
                        V[..., p] = _effect_variances(*shared, (a, b), pts, cat,
                                                      hbar).reshape(V.shape[:3])  # fmt: skip
                    joint_var[i] = sd_col**2 * np.einsum("lj,jabp->ablp", K2, V)
            if n_grid:
                E = _main_effects(zt, coef, beta, varied, I1, grid_u, cat)  # (p_u, G, d)
                if trend is not None:
                    E = (
                        E
                        + trend.const[:, None, None]
                        + trend.slope[:, None, :] * (grid_u - trend.centre)[None]
                    )
                main_effect[i] = y_mean[None, :, None] + sd_col * np.einsum("lj,jgn->gln", K, E)
            if n_joint:
                E = _joint_effects(zt, coef, beta, varied, I1, joint_u, pair_pos, cat)
                if trend is not None:
                    lin = trend.slope[:, None, :] * (joint_u - trend.centre)[None]  # (p_u, G2, d)
                    E = (E + trend.const[:, None, None, None] + lin[:, :, None, a_pos]
                         + lin[:, None, :, b_pos])  # fmt: skip
                joint_effect[i] = y_mean[:, None] + sd_col * np.einsum("lj,jabp->ablp", K, E)
            bar.update(1)
    return Sensitivity(
        names=tuple(k_names), bounds=box,
        fixed={k: float(v) for k, v in fixed.items()}, draw_index=idx, grid=std.grid,
        main=out["main"], total=out["total"], main_pc=out_pc["main"], total_pc=out_pc["total"],
        main_aggregated=out_agg["main"], total_aggregated=out_agg["total"],
        variance=variance, mean=mean,
        units={n: u for n, u in zip(names, (*emulator.x_units, *emulator.t_units), strict=True)
               if n in box},
        y_names=tuple(emulator.y_names), y_units=tuple(emulator.y_units),
        index_names=emulator.index_names, index_units=emulator.index_units,
        pairs=tuple((k_names[a], k_names[b]) for a, b in pair_pos),
        joint=out_pair.get("joint"), interaction=out_pair.get("interaction"),
        joint_pc=out_pair_pc.get("joint"), interaction_pc=out_pair_pc.get("interaction"),
        joint_aggregated=out_pair_agg.get("joint"),
        interaction_aggregated=out_pair_agg.get("interaction"),
        effect_grid=effect_grid, main_effect=main_effect, joint_grid=joint_grid,
        joint_effect=joint_effect,
        groups=tuple(tuple(k_names[n] for n in group) for group in group_pos),
        group_joint=out_group, group_joint_pc=out_group_pc, group_joint_aggregated=out_group_agg,
        main_effect_variance=main_var, joint_effect_variance=joint_var,
        categorical=tuple(n for n, lev in zip(k_names, lev_n, strict=True) if lev is not None),
    )  # fmt: skip
