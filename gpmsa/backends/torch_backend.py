"""torch backend: GPM/SA's log-posterior and Metropolis-within-Gibbs with many chains batched.

Every tensor carries a leading chain axis C; one scalar Metropolis update moves that element in all
chains at once. Proposals, bounds, sweep order, the nugget-ridge moves and step-size tuning are
those of the numpy reference (``gpmsa.mcmc.sampler``, ``gpmsa.mcmc.ridge``,
``gpmsa.mcmc.tuning``); chain c starts where the numpy chain c would (``gpmsa.mcmc.starts``:
dispersed for several chains), and the chains share one set of widths, tuned on acceptance
counts pooled over chains in ``tune_stages`` stages, each after ``warmup`` sweeps from where the
last stage left the chains. ``chain_groups`` > 1 then samples the chains in batches of consecutive
chains in worker processes (``gpmsa.mcmc.parallel``), to use every CPU core or a cluster.
Each chain caches its correlation matrices (packed lower triangle). Sigma_W is factored per chain
by LAPACK on the CPU (in cache, no copies; ``factor_``, ``_factor_scaled``) and by batched
``torch.linalg.cholesky_ex`` elsewhere. Float64 by default; ``device="cuda"`` runs on a GPU when
present.

The correlation R = exp(-sum_k beta_k d_k^2) is GPyTorch's ARD ``RBFKernel`` with lengthscale
l_k = 1/sqrt(2 beta_k) (tested equal); the sampler computes it from squared differences
precomputed once, as one matrix product and one in-place exp per proposal, instead of calling the
kernel module, whose lengthscale would have to be reset through its constraint transform at
every proposal. See docs/performance.md for measured speeds.
"""

from __future__ import annotations

import math
import os
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import torch
from scipy.linalg import cho_solve, lapack
from threadpoolctl import threadpool_limits

from gpmsa._progress import progress_bar
from gpmsa.backends import check_sample_args
from gpmsa.errors import ChainError, GPMSAError
from gpmsa.limits import check_memory
from gpmsa.mcmc import level_moves, ridge, starts, tempering, tuning
from gpmsa.mcmc.parallel import in_this_process, n_workers, run_chains
from gpmsa.mcmc.sampler import (
    PRECISION_PARAMS,
    RHO_PARAMS,
    Chains,
    check_draws_memory,
    check_hot_copies,
    check_ridge,
    check_step_widths,
    draws_nbytes,
    elements,
    proportional_step_choice,
    wrong_result,
)
from gpmsa.model.correlation import CATEGORICAL_DISTANCE, sq_diffs
from gpmsa.model.data import check_count, check_flag
from gpmsa.model.likelihood import held_log_prior, lower_cholesky
from gpmsa.model.priors import Priors
from gpmsa.model.problem import Problem

Tensor = torch.Tensor
_POTRF = {torch.float64: lapack.dpotrf, torch.float32: lapack.spotrf}
SIM_PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")
WARMUP = 100
"""Default sweeps before each pooled step-size tuning (not recorded)."""
TUNE_STAGES = 3
"""Default number of (warm-up, pooled tuning) stages: each tunes where the last one led."""
"""Parameters that change Sigma_W (their proposals refactor it)."""


@dataclass(frozen=True)
class ModelTensors:
    """The fixed data of one problem as tensors (unit / standardised units).

    ``d_sim`` (p+q, m, m): squared differences of the simulation inputs [x, t] per column;
    ``t_sim`` (m, q); ``w`` (p_u, m) weights, one row per basis component; ``lam_sim`` (p_u,).
    Observation side (None for the simulation-only model): ``d_obs`` (p, n, n) and ``d_cross``
    (p, n, m) squared differences of the known inputs (obs-obs, obs-sim); ``z`` (N,) the stacked
    reduced data, N = n * n_blocks; ``sig_obs`` (N, N) its covariance per unit lamOs;
    ``u_blocks`` the n-block of each basis component, ``v_blocks`` the n-blocks that receive the
    discrepancy covariance (GPM/SA's order, see ``gpmsa.model.problem.ObsProblem``) and
    ``v_groups`` the precision group of each (a column of betaV, an element of lamVz; empty:
    all in group 0); ``n_null`` the reduced data's unobserved directions
    (``ObsProblem.n_null``).
    Packed lower triangle (a factorisation reads only that): ``rows`` the row blocks (a, b)
    (rows a..b-1, columns 0..b-1), ``d_packed`` (p+q, P) d_sim over them, ``packed_index`` (P,)
    their flat positions in an m x m matrix.
    Extensions (``Problem.extensions``; docs/categorical-and-constraints.md): a categorical input's
    d_sim, d_obs and d_cross hold ``CATEGORICAL_DISTANCE`` between different levels (0 within
    one) and ``theta_cat`` (q,) marks the categorical calibration parameters (None: none);
    ``h_sim`` (m, k) the mean basis on the design (None: zero mean), ``x_obs`` (n, p) the
    observations' unit inputs where the mean basis reads them.
    """

    p: int
    q: int
    d_sim: Tensor
    t_sim: Tensor
    w: Tensor
    lam_sim: Tensor
    d_obs: Tensor | None = None
    d_cross: Tensor | None = None
    z: Tensor | None = None
    sig_obs: Tensor | None = None
    u_blocks: tuple[int, ...] = ()
    v_blocks: tuple[int, ...] = ()
    v_groups: tuple[int, ...] = ()
    n_null: int = 0
    rows: tuple[tuple[int, int], ...] = ()
    d_packed: Tensor | None = None
    packed_index: Tensor | None = None
    theta_cat: Tensor | None = None
    h_sim: Tensor | None = None
    x_obs: Tensor | None = None

    @property
    def has_obs(self) -> bool:
        """Whether the observation-side term enters the likelihood."""
        return self.z is not None

    @classmethod
    def from_problem(cls, problem: Problem, dtype: torch.dtype, device) -> ModelTensors:
        """Tensors of ``problem`` on ``device``."""

        def t(a: np.ndarray) -> Tensor:  # a copy: the emulator's arrays are read-only
            return torch.tensor(np.ascontiguousarray(a), dtype=dtype, device=device)

        zt = problem.zt
        cat = problem.categorical
        x_cat = None if cat is None else cat[: problem.p]
        kw = {}
        if problem.mean_basis is not None:
            kw["h_sim"] = t(problem.mean_basis.matrix(zt))
        obs = problem.obs
        if obs is not None:
            u_blocks = (0,) if obs.scalar_out else tuple(obs.p_v + j for j in range(problem.p_u))
            groups = obs.block_groups if "betaV" in problem.init else ()
            if cat is not None and cat[problem.p :].any():
                kw["theta_cat"] = torch.as_tensor(cat[problem.p :], device=device)
            if problem.mean_basis is not None:
                kw["x_obs"] = t(obs.x)
            kw |= {
                "d_obs": t(_sq_diffs(obs.x, obs.x, x_cat)),
                "d_cross": t(_sq_diffs(obs.x, problem.x_sim, x_cat)),
                "z": t(obs.z),
                "sig_obs": t(obs.sig_obs),
                "u_blocks": u_blocks,
                "v_blocks": tuple(range(len(groups))),
                "v_groups": groups,
                "n_null": obs.n_null,
            }
        d_sim = _sq_diffs(zt, zt, cat)
        rows = row_blocks(problem.m)
        index = np.concatenate([(np.arange(a, b)[:, None] * problem.m + np.arange(b)).ravel()
                                for a, b in rows])  # fmt: skip
        return cls(
            p=problem.p, q=problem.q, d_sim=t(d_sim), t_sim=t(problem.t_sim),
            w=t(problem.w.T), lam_sim=t(problem.lam_sim), rows=rows,
            d_packed=t(np.concatenate([d_sim[:, a:b, :b].reshape(d_sim.shape[0], -1)
                                       for a, b in rows], axis=1)),
            packed_index=torch.as_tensor(index, device=device), **kw,
        )  # fmt: skip


N_BLOCKS = 12
"""Row blocks of the packed lower triangle (12: 54 % of the matrix for m = 198)."""


def row_blocks(m: int, n_blocks: int = N_BLOCKS) -> tuple[tuple[int, int], ...]:
    """Row blocks (a, b) covering rows 0..m-1 evenly; block (a, b) keeps columns 0..b-1."""
    edges = np.unique(np.linspace(0, m, min(n_blocks, m) + 1).round().astype(int))
    return tuple((int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True))


def pairwise_sq(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared differences per column: a (na, k), b (nb, k) -> (k, na, nb)."""
    return (a.T[:, :, None] - b.T[:, None, :]) ** 2


def _sq_diffs(a: np.ndarray, b: np.ndarray, categorical: np.ndarray | None) -> np.ndarray:
    """`pairwise_sq`, a categorical column (``categorical``: boolean mask, None: none) giving
    ``CATEGORICAL_DISTANCE`` between different levels, as the numpy likelihood's."""
    if categorical is None or not categorical.any():
        return pairwise_sq(a, b)
    return sq_diffs(a, b, categorical)


def scaled_correlation(beta: Tensor, d: Tensor, lam: Tensor) -> Tensor:
    """R / lam = exp(-sum_k beta_k d_k - log lam) in one matrix product and one in-place exp.

    beta (C, k, J), d (k, a, b), lam (C, J) -> (C, J, a, b).
    """
    c, k, j = beta.shape
    bias = -torch.log(lam).reshape(c * j, 1)
    expo = torch.addmm(bias, beta.transpose(1, 2).reshape(c * j, k), d.flatten(1), alpha=-1.0)
    return expo.exp_().reshape(c, j, *d.shape[1:])


def _add_diagonal(mat: Tensor, values: Tensor) -> Tensor:
    """mat + diag(values) over the last two axes; in place unless autograd is recording (pyro)."""
    if torch.is_grad_enabled():
        return mat + torch.diag_embed(values.expand(mat.shape[:-1]))
    mat.diagonal(dim1=-2, dim2=-1).add_(values)
    return mat


def _gaussian_loglik(chol: Tensor, info: Tensor, resid: Tensor) -> tuple[Tensor, Tensor]:
    """-sum log diag(chol) - |chol^-1 r|^2 / 2 over the last axes; -inf where info != 0.

    chol (..., k, k), info (...), resid (..., k) -> (loglik (...), chol^-1 r (..., k)).
    """
    alpha = torch.linalg.solve_triangular(chol, resid.unsqueeze(-1), upper=False).squeeze(-1)
    logdet = torch.log(torch.diagonal(chol, dim1=-2, dim2=-1)).sum(-1)
    ll = -logdet - 0.5 * (alpha**2).sum(-1)
    bad = (info != 0) | ~torch.isfinite(ll)
    return torch.where(bad, torch.full_like(ll, -torch.inf), ll), alpha


def factor_(sig: Tensor) -> tuple[Tensor, Tensor]:
    """Lower Cholesky factors of the matrices sig (..., m, m): (factor, info (...), 0 = success).

    On the CPU, in place through LAPACK ``potrf``, one call per matrix on a zero-copy view: the
    factor overwrites sig's lower triangle and the upper triangle keeps Sigma (every later use
    reads the lower triangle only). torch's batched ``cholesky_ex`` costs 1.8x as much here
    (it copies each matrix and zeroes its upper triangle; docs/performance.md). Elsewhere (a
    GPU), or under autograd, ``torch.linalg.cholesky_ex``.
    """
    if sig.device.type != "cpu" or sig.requires_grad or sig.dtype not in _POTRF:
        return torch.linalg.cholesky_ex(sig)
    sig = sig.contiguous()
    m = sig.shape[-1]
    mats = sig.view(-1, m, m).numpy()
    potrf = _POTRF[sig.dtype]
    info = np.zeros(mats.shape[0], dtype=np.int32)
    for i, a in enumerate(mats):  # a.T is a's upper triangle in Fortran order: no copy
        info[i] = potrf(a.T, lower=0, clean=0, overwrite_a=1)[1]
    return sig, torch.from_numpy(info).view(sig.shape[:-2])


def sim_factor(
    d_sim: Tensor, w: Tensor, lam_sim: Tensor, betaU: Tensor, lamUz: Tensor, lamWs: Tensor,
    lamWOs: Tensor,
) -> tuple[Tensor, Tensor, Tensor]:  # fmt: skip
    """Sigma_W_j = R_j / lamUz_j + (1/(LamSim_j lamWOs) + 1/lamWs_j) I for components j.

    d_sim (p+q, m, m), w (J, m), lam_sim (J,), betaU (C, p+q, J), lamUz, lamWs (C, J), lamWOs
    (C, 1). Returns chol (C, J, m, m), alpha = chol^-1 w_j (C, J, m) and the per-component
    log N(w_j; 0, Sigma_W_j) without constants (C, J), -inf where not positive definite.
    """
    sig = scaled_correlation(betaU, d_sim, lamUz)
    return _factor_sigma(sig, w, lam_sim, lamWs, lamWOs)


def _on_lapack(t: Tensor) -> bool:
    """Whether the per-chain LAPACK path applies (a CPU tensor of float64/float32, no autograd)."""
    return t.device.type == "cpu" and t.dtype in _POTRF and not t.requires_grad


def correlation_packed(beta: Tensor, data: ModelTensors, out: Tensor) -> Tensor:
    """R = exp(-sum_k beta_k d_k) on the packed lower triangle, written into ``out`` (C, J, P,
    contiguous): one matrix product and one in-place exp; beta (C, k, J)."""
    c, k, j = beta.shape
    flat = out.view(c * j, -1)
    torch.mm(-beta.transpose(1, 2).reshape(c * j, k), data.d_packed, out=flat)
    return flat.exp_().view(out.shape)


def unpack(packed: Tensor, data: ModelTensors) -> Tensor:
    """The (..., m, m) matrices whose lower triangle is ``packed`` (..., P); upper part zero."""
    m = data.d_sim.shape[-1]
    full = packed.new_zeros((*packed.shape[:-1], m * m))
    full[..., data.packed_index] = packed
    return full.view(*packed.shape[:-1], m, m)


def _factor_scaled(
    corr: Tensor, scale: Tensor, data: ModelTensors, comps: slice, lamWs: Tensor,
    lamWOs: Tensor, out: Tensor | None = None, scratch: np.ndarray | None = None,
    only: Tensor | None = None,
) -> tuple[Tensor | None, Tensor, Tensor, Tensor | None]:  # fmt: skip
    """``sim_factor`` of components ``comps`` from their packed correlation corr (C, J, P) and
    scale = 1/lamUz (C, J); with a mean basis (``data.h_sim``) its coefficients integrated out
    as `gls` (the fourth item, coef (C, J, k); None without one).

    On the CPU, chain by chain and component by component: Sigma = corr * scale + nugget I is
    built (lower triangle) in one m x m buffer, factored there by LAPACK and solved against w
    while it is in cache (a batch of 64 chains x 198 x 198 is 20 MB: whole-batch passes each go
    through memory). The factors go to ``out`` (C, J, m, m) when given, else only the ``scratch``
    buffer is used and no factor is returned (None); then ``only`` (C,) bool, when given, limits
    the work to those chains (the others get -inf: proposals the prior refuses). Elsewhere (a
    GPU): batched torch ops.
    """
    w, lam_sim = data.w[comps], data.lam_sim[comps]
    if not _on_lapack(corr):
        sig = unpack(corr * scale[..., None], data)
        chol, alpha, ll = _factor_sigma(sig, w, lam_sim, lamWs, lamWOs)
        coef = None
        if data.h_sim is not None:
            alpha, ll, coef = gls(chol, alpha, ll, data.h_sim)
        if out is not None:
            out.copy_(chol)
        return chol, alpha, ll, coef
    nugget = (1.0 / (lam_sim * lamWOs) + 1.0 / lamWs).numpy()
    c_n, j_n, _ = corr.shape
    m = data.d_sim.shape[-1]
    cr, sc, wn = corr.numpy(), scale.numpy(), w.numpy()  # a component's slice: not copied
    o = None if out is None else out.numpy()
    if o is None and (scratch is None or scratch.shape != (m, m) or scratch.dtype != cr.dtype):
        scratch = np.empty((m, m), dtype=cr.dtype)
    offsets = np.cumsum([0] + [(b - a) * b for a, b in data.rows]).tolist()
    tmp = np.empty(cr.shape[-1], dtype=cr.dtype)  # the scaled packed rows: one contiguous pass
    blocks = [(a, b, tmp[o0:o1].reshape(b - a, b)) for (a, b), o0, o1 in
              zip(data.rows, offsets[:-1], offsets[1:], strict=True)]  # fmt: skip
    potrf = _POTRF[corr.dtype]
    trtrs = lapack.dtrtrs if corr.dtype == torch.float64 else lapack.strtrs
    alpha = np.zeros((c_n, j_n, m), dtype=cr.dtype)
    ll = np.full((c_n, j_n), -np.inf)
    h = None if data.h_sim is None else np.asfortranarray(data.h_sim.numpy())
    coef = None if h is None else np.zeros((c_n, j_n, h.shape[1]), dtype=cr.dtype)

    def views(a_: np.ndarray) -> tuple[np.ndarray, list, np.ndarray]:
        """a_'s transpose (LAPACK's view), its row blocks and its diagonal."""
        return a_.T, [(a_[a:b, :b], rows) for a, b, rows in blocks], a_.reshape(-1)[:: m + 1]

    fixed = None if o is not None else views(scratch)  # one buffer: views made once
    todo = range(c_n) if only is None or o is not None else torch.nonzero(only).flatten().tolist()
    for c in todo:
        for j in range(j_n):
            lapack_view, dst, diag = fixed or views(o[c, j])
            np.multiply(cr[c, j], sc[c, j], out=tmp)  # half the time of 12 strided multiplies
            for d, rows in dst:
                d[...] = rows
            diag += nugget[c, j]
            if potrf(lapack_view, lower=0, clean=0, overwrite_a=1)[1] != 0:
                continue
            v, _ = trtrs(lapack_view, wn[j], lower=0, trans=1)
            if h is None:
                alpha[c, j] = v
                ll[c, j] = -np.log(diag).sum() - 0.5 * (v @ v)
                continue
            # restricted likelihood, as the numpy likelihood's (IncrementalLikelihood._factor)
            a_h, _ = trtrs(lapack_view, h, lower=0, trans=1)
            lq = lower_cholesky(a_h.T @ a_h)
            if lq is None:
                continue
            coef[c, j] = cf = cho_solve((lq, True), a_h.T @ v)
            alpha[c, j] = v = v - a_h @ cf
            val = -float(np.sum(np.log(diag)))
            val -= float(np.sum(np.log(np.diagonal(lq))))
            ll[c, j] = val - 0.5 * float(v @ v)
    return (out, torch.from_numpy(alpha), torch.from_numpy(ll).to(corr.dtype),
            None if coef is None else torch.from_numpy(coef))  # fmt: skip


def _factor_sigma(
    sig: Tensor, w: Tensor, lam_sim: Tensor, lamWs: Tensor, lamWOs: Tensor
) -> tuple[Tensor, Tensor, Tensor]:
    """``sim_factor`` from sig = R_j / lamUz_j (C, J, m, m; overwritten on the CPU)."""
    nugget = 1.0 / (lam_sim * lamWOs) + 1.0 / lamWs
    sig = _add_diagonal(sig, nugget.unsqueeze(-1))
    chol, info = factor_(sig)
    ll, alpha = _gaussian_loglik(chol, info, w.expand(chol.shape[:-1]))
    return chol, alpha, ll


def gls(chol: Tensor, alpha: Tensor, ll: Tensor, h: Tensor) -> tuple[Tensor, Tensor, Tensor]:
    """A mean basis's coefficients integrated out (``gpmsa.model.mean_basis``: the restricted
    likelihood, as the numpy likelihood's): from ``sim_factor``'s chol (C, J, m, m), alpha =
    chol^-1 w (C, J, m) and ll (C, J), and h (m, k) the basis on the design, returns
    (chol^-1 (w - h coef), -sum log diag chol - sum log diag chol(A^T A) - |chol^-1 (w - h
    coef)|^2 / 2, coef (C, J, k)) with A = chol^-1 h and coef = (A^T A)^-1 A^T alpha (GLS);
    -inf where ll is, or A^T A is not positive definite."""
    a = torch.linalg.solve_triangular(chol, h.expand(*chol.shape[:-2], *h.shape), upper=False)
    a_t = a.transpose(-1, -2)
    lq, info = torch.linalg.cholesky_ex(a_t @ a)
    coef = torch.cholesky_solve(a_t @ alpha.unsqueeze(-1), lq).squeeze(-1)
    resid = alpha - (a @ coef.unsqueeze(-1)).squeeze(-1)
    val = -torch.log(torch.diagonal(chol, dim1=-2, dim2=-1)).sum(-1)
    val = val - torch.log(torch.diagonal(lq, dim1=-2, dim2=-1)).sum(-1) - 0.5 * (resid**2).sum(-1)
    bad = (info != 0) | ~torch.isfinite(ll) | ~torch.isfinite(val)
    return resid, torch.where(bad, torch.full_like(val, -torch.inf), val), coef


def mean_rows(problem: Problem, data: ModelTensors, theta: Tensor) -> Tensor:
    """The mean basis h([x_obs, theta]) (C, n, k) at each chain's theta (C, q): "constant" and
    "linear" by tensor ops (differentiable), a callable on each chain's (n, p + q) numpy array
    (``MeanBasis.matrix``, as the numpy likelihood calls it)."""
    mb, x = problem.mean_basis, data.x_obs
    c, n = theta.shape[0], x.shape[0]
    if mb.kind == "constant":
        return theta.new_ones((c, n, 1))
    if mb.kind == "linear":
        return torch.cat([theta.new_ones((c, n, 1)), x.expand(c, -1, -1),
                          theta.unsqueeze(1).expand(-1, n, -1)], -1)  # fmt: skip
    x_np, th = problem.obs.x, theta.detach().cpu().numpy().astype(np.float64)
    rows = [mb.matrix(np.hstack([x_np, np.tile(t_c, (n, 1))])) for t_c in th]
    return torch.as_tensor(np.stack(rows), dtype=theta.dtype, device=theta.device)


def obs_loglik(data: ModelTensors, chol: Tensor, alpha: Tensor, prm: dict[str, Tensor],
               coef: Tensor | None = None, h_obs: Tensor | None = None) -> Tensor:  # fmt: skip
    """log N(z; [0; S_UW S_W^-1 w], blockdiag(S_V, S_U - S_UW S_W^-1 S_WU) + S_obs / lamOs).

    chol (C, p_u, m, m), alpha (C, p_u, m) from ``sim_factor`` (a leading 1 instead of C: one
    Sigma_W shared by all chains); prm: theta (C, q), betaU (C, p+q, p_u), lamUz, lamWs (C, p_u),
    lamOs (C, 1), and betaV (C, p, G), lamVz (C, G) when there is a discrepancy of G precision
    groups. With a mean basis: coef (C, p_u, k) from `gls` (alpha its chol^-1 (w - h coef))
    and h_obs (C, n, k) from `mean_rows`, the u blocks' mean adding h_obs coef.
    Returns (C,): `obs_combine` of every component's `obs_parts`.
    """
    mean_u, cond = obs_parts(data, chol, alpha, prm)
    return obs_combine(data, mean_u, cond, prm, coef, h_obs)


def obs_parts(data: ModelTensors, chol: Tensor, alpha: Tensor, prm: dict[str, Tensor],
              comps: slice = slice(None)) -> tuple[Tensor, Tensor]:  # fmt: skip
    """The observation terms of basis components ``comps`` (J of them): each one's u-block mean
    S_UW_j S_W_j^-1 w_j (C, J, n) and conditional covariance S_U_j - S_UW_j S_W_j^-1 S_WU_j +
    I / lamWs_j (C, J, n, n). chol (C, J, m, m), alpha (C, J, m): those components' Sigma_W
    factors (`obs_loglik`; a leading 1: shared); prm: as `obs_loglik`'s, all components.

    Component j's terms depend on theta and j's parameters and factor only: `BatchState` keeps
    them, and a proposal that moves one component recomputes that component's. The correlations
    (S_UW, S_U) are computed for every component and then cut to ``comps`` (they cost little next
    to the solves): the same operations on the same shapes give the same bits whichever
    components are asked for (a product or an exp over a slice may round differently).
    """
    p = data.p
    betaU, lamUz = prm["betaU"], prm["lamUz"]
    b_x, b_t = betaU[:, :p], betaU[:, p:]
    dt = (prm["theta"].unsqueeze(-1) - data.t_sim.T) ** 2  # (C, q, m)
    if data.theta_cat is not None:  # a categorical theta: 1/4 between levels
        differ = (prm["theta"].unsqueeze(-1) != data.t_sim.T).to(dt.dtype)
        dt = torch.where(data.theta_cat[:, None], CATEGORICAL_DISTANCE * differ, dt)
    expo = torch.einsum("ckj,kab->cjab", b_x, data.d_cross)
    expo = expo + torch.einsum("ckj,ckm->cjm", b_t, dt).unsqueeze(-2)
    s_uw = (torch.exp(-expo) / lamUz[..., None, None])[:, comps]  # (C, J, n, m)
    c, p_u, n, m = s_uw.shape
    if chol.shape[0] == 1 and c > 1:  # one Sigma_W for all chains: one solve, C n right sides
        rhs = s_uw.permute(1, 3, 0, 2).reshape(p_u, m, c * n)
        a = torch.linalg.solve_triangular(chol[0], rhs, upper=False)
        a = a.reshape(p_u, m, c, n).permute(2, 0, 1, 3)
    else:
        a = torch.linalg.solve_triangular(chol, s_uw.transpose(-1, -2), upper=False)
    mean_u = (a * alpha.unsqueeze(-1)).sum(-2)  # (C, J, n)
    cond = scaled_correlation(b_x, data.d_obs, lamUz)[:, comps] - a.transpose(-1, -2) @ a
    return mean_u, _add_diagonal(cond, (1.0 / prm["lamWs"][:, comps]).unsqueeze(-1))


def obs_combine(data: ModelTensors, mean_u: Tensor, cond: Tensor, prm: dict[str, Tensor],
                coef: Tensor | None = None, h_obs: Tensor | None = None) -> Tensor:  # fmt: skip
    """`obs_loglik` (C,) from every component's `obs_parts` mean_u (C, p_u, n) and cond (C, p_u,
    n, n): the u blocks, the discrepancy's blocks and S_obs / lamOs assembled and factored."""
    n = data.d_obs.shape[-1]
    if coef is not None:  # the GLS mean at [x_obs, theta]
        coef = coef.expand(h_obs.shape[0], -1, -1)  # one shared Sigma_W: one coef
        mean_u = mean_u + torch.einsum("cnk,cjk->cjn", h_obs, coef)
    full = data.sig_obs / prm["lamOs"][..., None]  # (C, N, N)
    mean = torch.zeros_like(full[..., 0])
    for j, blk in enumerate(data.u_blocks):
        sl = slice(blk * n, (blk + 1) * n)
        full[:, sl, sl] += cond[:, j]
        mean[:, sl] = mean_u[:, j]
    if data.v_blocks:
        s_v = scaled_correlation(prm["betaV"], data.d_obs, prm["lamVz"])  # (C, G, n, n)
        groups = data.v_groups or (0,) * len(data.v_blocks)  # none given: one group
        for blk, g in zip(data.v_blocks, groups, strict=True):
            full[:, blk * n : (blk + 1) * n, blk * n : (blk + 1) * n] += s_v[:, g]
    chol_z, info = torch.linalg.cholesky_ex(full)
    ll, _ = _gaussian_loglik(chol_z, info, data.z - mean)
    if data.n_null:  # ObsProblem.null_term
        ll = ll - 0.5 * data.n_null * torch.log(prm["lamOs"][:, 0])
    return ll


def log_prior_elements(priors: Priors, name: str, x: Tensor, element=None) -> Tensor:
    """GPM/SA log prior of each element of ``x`` (any shape); -inf outside the bounds.

    ``element``: x holds that element (index in a 1-D parameter) of ``name`` in every chain;
    None: x holds whole parameters, along its last axis (lamVz or betaV with per-group priors:
    group g's prior on x[..., g]; theta with per-element priors: element k's on x[..., k]);
    for theta also an index list: x[..., i] holds theta element ``element[i]``.
    """
    inf = torch.full_like(x, -torch.inf)
    if name == "theta":
        if isinstance(element, int | np.integer):
            mean, sd = priors.theta_prior(int(element))
        else:  # floats where one prior is shared; per-element: tensors along the last axis
            mean, sd = priors.theta_moments(x.shape[-1] if element is None else None, element)
            if isinstance(mean, np.ndarray):
                mean, sd = x.new_tensor(mean), x.new_tensor(sd)
        val = -0.5 * ((x - mean) / sd) ** 2
        ok = (x > 0.0) & (x < 1.0)
    elif name in RHO_PARAMS:
        if element is None:  # betaV with per-group priors: group g's on x[..., g]
            a, b = priors.rho_arrays(name, x.shape[-1])
            a, b = (x.new_tensor(v) if isinstance(v, np.ndarray) else v for v in (a, b))
        else:
            a, b = priors.rho_prior(name, element)
        rho = torch.clamp(torch.exp(-0.25 * x), max=priors.rho_cap)
        val = (a - 1.0) * torch.log(rho) + (b - 1.0) * torch.log1p(-rho)
        ok = (x > 0.0) & torch.isfinite(x)
    elif name == "lamVz" and priors.per_group and element is None:
        a, b, lo, hi = (x.new_tensor(v) for v in priors.gamma_arrays("lamVz", x.shape[-1]))
        val = (a - 1.0) * torch.log(x) - b * x
        ok = (x > lo) & (x < hi)
    elif name in PRECISION_PARAMS:
        g = priors.precision_prior(name, element or 0)
        val = (g.a - 1.0) * torch.log(x) - g.b * x
        ok = (x > g.lower) & (x < g.upper)
    else:
        raise GPMSAError(f"unknown parameter name {name!r}")
    return torch.where(ok, val, inf)


def _seed_generator(seed, device) -> torch.Generator:
    """A torch Generator seeded from ``seed`` (int or None) via numpy's SeedSequence."""
    state = int(np.random.SeedSequence(seed).generate_state(1, dtype=np.uint64)[0])
    return torch.Generator(device=device).manual_seed(state & (2**63 - 1))


def _copy_rows(dst: Tensor, src: Tensor, rows: Tensor) -> None:
    """dst[rows] = src[rows] along the chain axis (per chain on the CPU: no gathered copy)."""
    if dst.device.type == "cpu":
        d, s_ = dst.numpy(), src.numpy()
        for r in rows.tolist():
            d[r] = s_[r]
    else:
        dst[rows] = src[rows]


class BatchState:
    """C chains of one problem: parameters, cached Sigma_W factors and the batched sweep.

    As the numpy sampler (``gpmsa.mcmc.sampler.ChainState``): a categorical theta element moves
    to another of its levels drawn uniformly (its prior uniform over them), after
    `learn_level_shifts` with the continuous sampled theta elements shifted between their
    conditional modes at the two levels (``gpmsa.mcmc.level_moves``); a theta proposal
    the theta constraint refuses is rejected before its likelihood (the constraint called per
    chain); with a mean basis the coefficients are integrated out (`gls`) and the observations'
    mean adds the GLS trend h([x_obs, theta]) coef (`mean_rows`, cached per chain).
    As the numpy sampler's ``IncrementalLikelihood``, a proposal recomputes only what it moves:
    each component's observation terms are cached per chain (``obs_mean``, ``obs_cond``:
    `obs_parts`), so a betaU, lamUz or lamWs proposal factors and re-solves its component alone,
    a lamOs, betaV or lamVz proposal only assembles the observations' covariance (`obs_combine`).
    ``beta``: None (plain chains), or (C,) the power 1/T of each row's likelihood in its
    acceptance (parallel tempering, `_tempered_tuning`, `_tempered_draws`: the rows are the
    chains' copies; the prior is not tempered).
    """

    beta: Tensor | None = None

    def __init__(self, problem: Problem, n_chains: int, dtype: torch.dtype, device,
                 start: dict[str, np.ndarray] | None = None, ridge_moves: int = 0):  # fmt: skip
        """``start``: name -> (C, *shape) starting values (default: ``problem.init`` for all);
        ``ridge_moves``: moves along the nugget ridge per sweep where they apply."""
        self.problem = problem
        self.ridge_moves = int(ridge_moves) if ridge.applies(problem) else 0
        self._buffers: dict[tuple[str, int], Tensor] = {}
        m = problem.m
        self._scratch = torch.empty((m, m), dtype=dtype, device="cpu").numpy()  # factors not kept
        self.data = ModelTensors.from_problem(problem, dtype, device)
        self.priors = problem.priors
        self.els = elements(problem)
        # the held elements' constant share of the whole-array priors in log_post
        self._held_lp = held_log_prior(problem, problem.init) if problem.fixed_elements else 0.0
        self.n_chains = n_chains
        levels = problem.theta_levels or [None] * problem.q
        self.levels = {k: torch.as_tensor(lv, dtype=dtype, device=device)
                       for k, lv in enumerate(levels) if lv is not None}  # fmt: skip
        # `learn_level_shifts`: categorical element -> offsets (C, its levels, shift_elements),
        # the continuous theta elements the joint level move shifts
        self.level_shifts: dict[int, Tensor] = {}
        self.shift_elements: list[int] = []
        self.constraint = problem.constraint if "theta" in problem.sampled else None
        if self.constraint is not None:
            for c in range(n_chains):
                theta = problem.init["theta"] if start is None else start["theta"][c]
                self.constraint.check_start(np.asarray(theta, dtype=np.float64),
                                            "the chain's start")  # fmt: skip
        if start is None:
            start = {k: np.broadcast_to(v, (n_chains, *v.shape)) for k, v in problem.init.items()}
        self.reset({
            k: torch.as_tensor(np.array(v), dtype=dtype, device=device) for k, v in start.items()
        })  # fmt: skip
        bad = torch.nonzero(~torch.isfinite(self.loglik)).squeeze(-1).tolist()
        if bad:
            raise ChainError(
                f"the starting values of chain(s) {bad} give a log-likelihood of "
                f"{self.loglik[bad[0]].item()} (Sigma not positive definite, or NaN data)", bad,
            )  # fmt: skip

    def _buffer(self, what: str, n_comp: int) -> Tensor:
        """A reused work tensor, (C, n_comp, P) packed correlations ("corr") or (C, n_comp, m, m)
        factors ("chol"): a fresh 20 MB tensor per proposal costs page faults."""
        key = (what, n_comp)
        if key not in self._buffers:
            m = self.data.d_sim.shape[-1]
            tail = (self.data.d_packed.shape[-1],) if what == "corr" else (m, m)
            self._buffers[key] = self.ll_w.new_empty((self.n_chains, n_comp, *tail))
        return self._buffers[key]

    def reset(self, params: dict[str, Tensor]) -> None:
        """Set every chain's parameters (name -> (C, *shape)) and recompute all cached terms."""
        self.params = params
        d = self.data
        shared = all(k in self.problem.fixed for k in SIM_PARAMS)  # calibration: one Sigma_W
        prm = {k: params[k][:1] if shared else params[k] for k in SIM_PARAMS}
        self.coef = None
        if shared:  # one Sigma_W, factored once
            self.corr = None
            sig = scaled_correlation(prm["betaU"], d.d_sim, prm["lamUz"])
            self.chol, self.alpha, self.ll_w = _factor_sigma(
                sig, d.w, d.lam_sim, prm["lamWs"], prm["lamWOs"]
            )
            if d.h_sim is not None:
                self.alpha, self.ll_w, self.coef = gls(self.chol, self.alpha, self.ll_w, d.h_sim)
        else:  # R_j per chain, packed and cached: a precision proposal only rescales it
            n, p_u, m = self.n_chains, d.w.shape[0], d.d_sim.shape[-1]
            corr = prm["betaU"].new_empty((n, p_u, d.d_packed.shape[-1]))
            self.corr = correlation_packed(prm["betaU"], d, corr)
            chol = prm["betaU"].new_empty((n, p_u, m, m)) if d.has_obs else None
            self.chol, self.alpha, self.ll_w, self.coef = _factor_scaled(
                self.corr, 1.0 / prm["lamUz"], d, slice(None), prm["lamWs"], prm["lamWOs"],
                out=chol, scratch=self._scratch,
            )  # fmt: skip
        if shared:
            self.ll_w = self.ll_w.expand(self.n_chains, -1).clone()
        if not d.has_obs:
            self.chol = self.alpha = self.coef = None  # not needed without observations
        self.h_obs = None
        if d.has_obs and self.coef is not None:
            self.h_obs = mean_rows(self.problem, d, params["theta"])
        # each component's observation terms (`obs_parts`), per row: a proposal that moves one
        # component recomputes that component's only
        self.obs_mean = self.obs_cond = None
        if d.has_obs:
            self.obs_mean, self.obs_cond = obs_parts(d, self.chol, self.alpha, params)
        self.ll_obs = self._obs(params, slice(None), None, self.coef, self.h_obs)

    @property
    def loglik(self) -> Tensor:
        """Current log-likelihood (C,)."""
        return self.ll_w.sum(-1) + self.ll_obs

    def exchange(self, a: Tensor, b: Tensor) -> None:
        """Rows ``a`` and ``b`` (index tensors of equal length) exchange their states: the
        parameters and every cached term (correlations, Sigma_W factors, likelihood terms,
        mean rows, observation terms); one Sigma_W shared by all rows (calibration) stays."""
        cached = [self.ll_w, self.ll_obs, self.corr, self.h_obs, self.obs_mean, self.obs_cond]
        if self.chol is not None and self.chol.shape[0] == self.n_chains:  # per row
            cached += [self.chol, self.alpha, self.coef]
        for t in (*self.params.values(), *cached):
            if t is not None:
                t[a], t[b] = t[b], t[a]  # both gathered (copies) before either is written

    def log_post(self) -> Tensor:
        """Current log posterior (C,): likelihood + priors of the sampled parameters."""
        lp = self.loglik
        for name in self.problem.sampled:
            x = self.params[name]
            each = log_prior_elements(self.priors, name, x)
            if name == "theta" and self.data.theta_cat is not None:  # uniform over its levels
                each = torch.where(self.data.theta_cat, torch.zeros_like(each), each)
            lp = lp + each.reshape(x.shape[0], -1).sum(-1)
        return lp - self._held_lp if self.problem.fixed_elements else lp

    def _obs(self, prm: dict[str, Tensor], comps: slice, parts: tuple[Tensor, Tensor] | None,
             coef: Tensor | None = None, h_obs: Tensor | None = None) -> Tensor:  # fmt: skip
        """Observation term (C,) at ``prm`` (zeros without obs): the cached component terms
        (``obs_mean``, ``obs_cond``), those of components ``comps`` replaced by ``parts`` (the
        proposal's `obs_parts`; None: none changed)."""
        if not self.data.has_obs:
            return self.ll_w.new_zeros(prm["betaU"].shape[0])
        mean_u, cond = self.obs_mean, self.obs_cond
        if parts is not None and comps == slice(None):
            mean_u, cond = parts
        elif parts is not None:
            mean_u, cond = mean_u.clone(), cond.clone()
            mean_u[:, comps], cond[:, comps] = parts
        return obs_combine(self.data, mean_u, cond, prm, coef, h_obs)

    def _allowed(self, idx: tuple[int, ...], cand: Tensor, valid: Tensor,
                 theta: Tensor | None = None) -> Tensor:  # fmt: skip
        """``valid`` less the chains whose theta with element ``idx`` at ``cand`` (C,) the theta
        constraint refuses (called per chain, as the numpy sampler calls it); ``theta`` (C, q):
        the proposed theta in place of the current one (the joint level move's)."""
        theta = (self.params["theta"] if theta is None else theta).cpu().numpy().astype(np.float64)
        cands = cand.cpu().numpy().astype(np.float64)
        out = valid.clone()
        for c in torch.nonzero(valid).flatten().tolist():
            th = theta[c].copy()
            th[idx] = cands[c]
            out[c] = bool(self.constraint(th))
        return out

    def _level_move(self, k: int, x: Tensor, u0: Tensor) -> tuple[Tensor, Tensor]:
        """(candidates, valid) for categorical theta element k at x (C,): another of its levels
        drawn uniformly by u0 (C,), as the numpy sampler's ``others[int(u0 * others.size)]``
        (the other levels in order); invalid where it has one level."""
        lv = self.levels[k]
        n_other = lv.numel() - 1
        if n_other == 0:
            return x, torch.zeros_like(x, dtype=torch.bool)
        pos, _ = self._level_rows(k, x)
        pick = torch.floor(u0 * n_other).to(torch.long)
        pick = pick + (pick >= pos).to(torch.long)  # skip x's own level
        return lv[pick], torch.ones_like(x, dtype=torch.bool)

    def _level_rows(self, k: int, x: Tensor) -> tuple[Tensor, Tensor]:
        """(row, at_level) (C,) of categorical theta element k's values x (C,) among its levels
        (row = the number of levels where x is none of them)."""
        lv = self.levels[k]
        at = lv == x.unsqueeze(-1)  # (C, K): x's level
        found = at.any(-1)
        return torch.where(found, at.to(torch.long).argmax(-1), lv.numel()), found

    def learn_level_shifts(self, copies: int = 1) -> None:
        """Each categorical theta element's joint level move (``gpmsa.mcmc.level_moves``, as the
        numpy sampler's ``ChainState.learn_level_shifts``): per chain, the conditional modes of
        the continuous sampled theta elements at each of its levels, the other parameters at
        the chain's current values (``level_offsets`` on the chain's log posterior); none
        without observations, a categorical and a continuous sampled theta element.
        ``copies`` > 1 (parallel tempering, rows c * copies + k): learnt at each chain's T = 1
        row, every copy of the chain given them."""
        sampled = [idx[0] for n, idx in self.els if n == "theta"]
        cat = [k for k in sampled if k in self.levels and self.levels[k].numel() > 1]
        cont = [k for k in sampled if k not in self.levels]
        if not (cat and cont and self.data.has_obs):
            return
        self.shift_elements = cont
        theta = self.params["theta"][::copies].cpu().numpy().astype(np.float64)
        posts = [self._chain_log_post(c, cont) for c in range(0, self.n_chains, copies)]
        for k in cat:
            lv = self.levels[k].cpu().numpy().astype(np.float64)
            off = [level_moves.level_offsets(f, th, k, lv, cont)
                   for f, th in zip(posts, theta, strict=True)]  # fmt: skip
            self.level_shifts[k] = torch.as_tensor(np.repeat(np.stack(off), copies, axis=0),
                                                   dtype=self.ll_w.dtype,
                                                   device=self.ll_w.device)  # fmt: skip

    def _chain_log_post(self, c: int, cont: list[int]):
        """Chain c's log posterior as a function of its unit theta (q,) alone, up to a constant
        (the observation term and the priors of the continuous elements ``cont``; -inf outside
        their bounds or the constraint), the other parameters at their current values."""
        d, sl = self.data, slice(c, c + 1)

        def rows(t: Tensor | None) -> Tensor | None:  # one shared Sigma_W (calibration): as is
            return t if t is None or t.shape[0] == 1 else t[sl]

        prm = {k: v[sl] for k, v in self.params.items()}
        chol, alpha, coef = rows(self.chol), rows(self.alpha), rows(self.coef)
        like = self.ll_w.new_tensor

        def log_post(theta: np.ndarray) -> float:
            th = like(theta).unsqueeze(0)
            lp = log_prior_elements(self.priors, "theta", th[0, cont], cont).sum()
            if not torch.isfinite(lp) or (self.constraint is not None
                                          and not self.constraint(theta)):  # fmt: skip
                return -math.inf
            h_obs = None if self.h_obs is None else mean_rows(self.problem, d, th)
            return float(lp + obs_loglik(d, chol, alpha, {**prm, "theta": th}, coef, h_obs)[0])

        return log_post

    def _shifted(self, k: int, x: Tensor, cand: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        """The joint level move of categorical theta element k from x to cand (C,): (theta (C, q)
        with k at cand and the continuous elements shifted by o[cand] - o[x] (`level_shifts`),
        their log prior there, and at the current theta (C,)); -inf where x is no level."""
        cont, off = self.shift_elements, self.level_shifts[k]
        cur = self.params["theta"]
        row, found = self._level_rows(k, x)
        new_row, _ = self._level_rows(k, cand)
        chains = torch.arange(cur.shape[0], device=cur.device)
        row = torch.where(found, row, 0)
        theta = cur.clone()
        theta[:, k] = cand
        theta[:, cont] = cur[:, cont] + (off[chains, new_row] - off[chains, row])
        lp_new = log_prior_elements(self.priors, "theta", theta[:, cont], cont).sum(-1)
        lp_new = torch.where(found, lp_new, -torch.inf)
        return theta, lp_new, log_prior_elements(self.priors, "theta", cur[:, cont], cont).sum(-1)

    def update(self, name: str, idx: tuple[int, ...], width: float | Tensor, kind: int,
               prop_mh: bool, u: Tensor) -> Tensor:  # fmt: skip
        """One Metropolis step of element ``idx`` of ``name`` in every chain; u (2, C) uniforms;
        ``width``: the chains' step width, or each row's (C,).

        Returns the accepted mask (C,).
        """
        cur = self.params[name]
        x = cur[(slice(None), *idx)]
        step = u[0] - 0.5
        corr = torch.zeros_like(x)
        valid = torch.ones_like(x, dtype=torch.bool)
        level = name == "theta" and idx[0] in self.levels
        joint = None  # the joint level move's theta (C, q) and its continuous elements' priors
        if level:  # another level, uniformly (symmetric; the prior is uniform over them)
            cand, valid = self._level_move(idx[0], x, u[0])
            if idx[0] in self.level_shifts:  # with the continuous theta (level_moves)
                joint = self._shifted(idx[0], x, cand)
        elif kind == 1:  # beta on the rho scale
            r = torch.exp(-0.25 * x) + width * step
            valid = r > 0.0
            cand = -4.0 * torch.log(torch.where(valid, r, torch.ones_like(r)))
        elif kind == 2 and prop_mh:  # GPM/SA's untuned proportional step
            w0 = torch.clamp(x / 3.0, min=1.0)
            cand = x + w0 * 2.0 * step
            w1 = torch.clamp(cand / 3.0, min=1.0)
            valid = ~(x > cand + w1)
            corr = torch.log(w0 / w1)
        else:
            cand = x + width * step
        if level:
            lp_new = torch.zeros_like(x) if joint is None else joint[1]
        else:
            lp_new = log_prior_elements(self.priors, name, cand, idx[-1])
        valid &= torch.isfinite(lp_new)
        if name == "theta" and self.constraint is not None and valid.any():
            valid = self._allowed(idx, cand, valid, None if joint is None else joint[0])
        accepted = torch.zeros_like(valid)
        if not valid.any():
            return accepted
        cand = torch.where(valid, cand, x)
        # Every chain is evaluated (no gathers of cached matrices); invalid ones are masked.
        prm = dict(self.params)
        prm[name] = cur.clone()
        prm[name][(slice(None), *idx)] = cand
        if joint is not None:
            prm[name] = torch.where(valid.unsqueeze(-1), joint[0], cur)
        d = self.data
        ll_w, coef, h_obs = self.ll_w, self.coef, self.h_obs
        if name == "theta" and h_obs is not None:
            h_obs = mean_rows(self.problem, d, prm["theta"])
        comps, parts = slice(None), None  # components whose observation terms move, their new ones
        if name == "theta" and d.has_obs:
            parts = obs_parts(d, self.chol, self.alpha, prm)
        if name in SIM_PARAMS:
            whole = name == "lamWOs" or d.w.shape[0] == 1
            comps = slice(None) if whole else slice(idx[-1], idx[-1] + 1)
            j_c = d.w.shape[0] if whole else 1
            if name == "betaU":  # a new correlation matrix, into a reused buffer
                corr_c = correlation_packed(prm["betaU"][:, :, comps], d,
                                            self._buffer("corr", j_c))  # fmt: skip
            else:  # the cached one, rescaled
                corr_c = self.corr[:, comps]
            chol_c, alpha_c, ll_c, coef_c = _factor_scaled(
                corr_c, 1.0 / prm["lamUz"][:, comps], d, comps, prm["lamWs"][:, comps],
                prm["lamWOs"], out=self._buffer("chol", j_c) if d.has_obs else None,
                scratch=self._scratch, only=valid,
            )  # fmt: skip
            ll_w, coef = ll_c, coef_c
            if not whole:
                ll_w = self.ll_w.clone()
                ll_w[:, comps] = ll_c
                if d.has_obs and coef_c is not None:
                    coef = self.coef.clone()
                    coef[:, comps] = coef_c
            if d.has_obs:  # the moved components' observation terms only
                parts = obs_parts(d, chol_c, alpha_c, prm, comps)
        ll_obs = self._obs(prm, comps, parts, coef, h_obs)
        ll_new = ll_w.sum(-1) + ll_obs
        if level:
            lp_old = lp_new if joint is None else joint[2]
        else:
            lp_old = log_prior_elements(self.priors, name, x, idx[-1])
        d_ll = ll_new - self.loglik
        if self.beta is not None:  # tempered copies: each row's likelihood to its power 1/T
            d_ll = d_ll * self.beta
        ratio = d_ll + lp_new - lp_old + corr
        acc = (torch.log(u[1]) < ratio) & valid
        take = torch.nonzero(acc).squeeze(-1)
        accepted[take] = True
        if joint is None:
            cur[(take, *idx)] = cand[take]
        else:
            cur[take] = prm[name][take]
        self.ll_obs[take] = ll_obs[take]
        if parts is not None:
            self.obs_mean[take, comps] = parts[0][take]
            self.obs_cond[take, comps] = parts[1][take]
        if name in SIM_PARAMS:
            self.ll_w[take] = ll_w[take]
            if name == "betaU":
                _copy_rows(self.corr[:, comps], corr_c, take)
            if d.has_obs:
                _copy_rows(self.chol[:, comps], chol_c, take)
                self.alpha[take, comps] = alpha_c[take]
                if coef_c is not None:
                    self.coef[take, comps] = coef_c[take]
        if name == "theta" and h_obs is not None:
            self.h_obs[take] = h_obs[take]
        return accepted

    def sweep(self, widths: np.ndarray | Tensor, prop_mh: bool, gen: torch.Generator) -> Tensor:
        """One Metropolis-within-Gibbs sweep in GPM/SA's order, then ``ridge_moves`` moves along
        the nugget ridge (``gpmsa.mcmc.ridge``); returns accepted (n_el, C) of the sweep.
        ``widths``: (n_el,) shared by every chain, or a tensor (n_el, C) of each row's
        (tempered copies, each at its own widths)."""
        c = self.ll_w.shape[0]
        n_el = len(self.els)
        u = torch.rand((n_el + self.ridge_moves, 2, c), generator=gen, dtype=self.ll_w.dtype,
                       device=self.ll_w.device)  # fmt: skip
        out = torch.zeros((n_el, c), dtype=torch.bool, device=self.ll_w.device)
        per_row = isinstance(widths, Tensor)
        for i, (name, idx) in enumerate(self.els):
            kind = 1 if name in RHO_PARAMS else 2 if name in PRECISION_PARAMS else 0
            width = widths[i] if per_row else float(widths[i])
            out[i] = self.update(name, idx, width, kind, prop_mh, u[i])
        if self.ridge_moves:
            self.ridge_sweep(u[n_el:])
        return out

    def ridge_sweep(self, u: Tensor) -> None:
        """Moves along the nugget ridge in every chain, one per u[k] (2, C) (likelihood unchanged;
        the same move as the numpy sampler's ``ChainState.ridge_sweep``)."""
        pri, lam_sim = self.priors, self.data.lam_sim[0]
        ws, wos = self.params["lamWs"], self.params["lamWOs"]
        s, t = ws[:, 0].clone(), wos[:, 0].clone()
        lp_old = log_prior_elements(pri, "lamWs", s) + log_prior_elements(pri, "lamWOs", t)
        for k in range(u.shape[0]):
            n = 1.0 / (lam_sim * t) + 1.0 / s
            s2 = s * torch.exp(ridge.WIDTH * (u[k, 0] - 0.5))
            r = n - 1.0 / s2
            ok = r > 0.0
            t2 = 1.0 / (lam_sim * torch.where(ok, r, torch.ones_like(r)))
            lp_new = log_prior_elements(pri, "lamWs", s2) + log_prior_elements(pri, "lamWOs", t2)
            ok &= torch.isfinite(lp_new)
            ratio = lp_new - lp_old + 2.0 * torch.log(t2 / t) + torch.log(s2 / s)
            acc = ok & (torch.log(u[k, 1]) < ratio)
            s, t = torch.where(acc, s2, s), torch.where(acc, t2, t)
            lp_old = torch.where(acc, lp_new, lp_old)
        ws[:, 0], wos[:, 0] = s, t


MAX_THREADS = 1024
"""Most torch CPU threads (``num_threads``), or the machine's CPUs where it has more: torch's
OpenMP pool allocates per thread up front (10**9 aborted the process out of memory, 10**5
crashed it), and threads beyond the CPUs add nothing."""


@contextmanager
def torch_threads(num_threads: int | None):
    """Set torch's CPU thread count, and the BLAS libraries' (scipy's LAPACK factors on the CPU),
    inside the block (None: unchanged); restored afterwards. GPMSAError naming ``num_threads``
    for a count outside [1, ``MAX_THREADS``] (or the machine's CPUs, where more)."""
    if num_threads is not None:
        check_count(num_threads, "num_threads")
        most = max(MAX_THREADS, os.cpu_count() or 1)
        if num_threads > most:
            raise GPMSAError(
                f"num_threads must be an integer in [1, {most}], got {num_threads!r}: torch "
                f"would start that many CPU threads, and this machine has {os.cpu_count()} "
                "CPUs (more threads than CPUs add nothing)"
            )
    previous = torch.get_num_threads()
    if num_threads is None:
        yield
        return
    torch.set_num_threads(int(num_threads))
    try:
        with threadpool_limits(int(num_threads), user_api="blas"):  # scipy's LAPACK (factor_)
            yield
    finally:
        torch.set_num_threads(previous)


_DTYPES = {"float64": torch.float64, "float32": torch.float32}


def _dtype(dtype) -> torch.dtype:
    """``dtype`` ("float64", "float32" or that torch dtype) as a torch dtype; GPMSAError for
    anything else (a numpy dtype too: the fit records the name)."""
    if isinstance(dtype, torch.dtype) and dtype in _DTYPES.values():
        return dtype
    if isinstance(dtype, str) and dtype in _DTYPES:
        return _DTYPES[dtype]
    raise GPMSAError(f"dtype must be 'float64' or 'float32', got {dtype!r}")


def _device(device) -> torch.device:
    """``device`` as a torch.device (`_parsed_device`); GPMSAError for CUDA where torch sees
    none, or fewer than ``cuda:N`` needs."""
    dev = _parsed_device(device)
    if dev.type == "cuda" and not torch.cuda.is_available():
        hip = getattr(torch.version, "hip", None)  # a ROCm build: its GPUs go by "cuda" too
        why = (f"torch {torch.__version__} is built for CUDA {torch.version.cuda} but finds no "
               "GPU (driver, CUDA_VISIBLE_DEVICES)" if torch.version.cuda is not None
               else f"torch {torch.__version__} is built for ROCm (HIP {hip}) but finds no GPU "
               "(driver, HIP_VISIBLE_DEVICES)" if hip
               else f"this torch {torch.__version__} is a CPU build")  # fmt: skip
        raise GPMSAError(
            f"device={device!r} was asked for but torch sees no CUDA device ({why}); give "
            "device='cpu' (the default), or run where torch sees a GPU"
        )
    if dev.type == "cuda" and dev.index is not None and dev.index >= torch.cuda.device_count():
        raise GPMSAError(
            f"device={device!r} was asked for but torch sees {torch.cuda.device_count()} CUDA "
            f"device(s): cuda:0 to cuda:{torch.cuda.device_count() - 1}"
        )
    return dev


def _parsed_device(device) -> torch.device:
    """``device`` ("cpu", "cuda", "cuda:N" or such a torch.device) as a torch.device;
    GPMSAError for anything else."""
    dev = None
    if isinstance(device, torch.device):
        dev = device
    elif isinstance(device, str):
        try:
            dev = torch.device(device)
        except RuntimeError:
            dev = None
    if dev is None or dev.type not in ("cpu", "cuda"):
        raise GPMSAError(f"device must be 'cpu' or 'cuda' (or 'cuda:N'), got {device!r}")
    return dev


def sample(
    problem: Problem,
    *,
    n_iter: int,
    n_chains: int = 1,
    tune: bool = True,
    step_widths: dict[str, np.ndarray] | None = None,
    seed=None,
    progress: bool = False,
    tune_rounds: int | None = None,
    tune_levels: int = tuning.N_LEVELS,
    device="cpu",
    dtype="float64",
    num_threads: int | None = 1,
    init: str | dict = "auto",
    warmup: int | None = None,
    tune_stages: int = TUNE_STAGES,
    ridge_moves: int | None = None,
    chain_groups: int = 1,
    n_jobs: int | None = None,
    executor=None,
    proportional_steps: bool | None = None,
    temperatures=None,
    swap_every: int = 1,
    adapt_ladder: bool = False,
    hot_copies: dict | None = None,
) -> Chains:
    """Run ``n_chains`` chains batched in one tensor program: tuning, then ``n_iter`` sweeps.

    Starts: ``init`` ("auto": GPM/SA's initial values for one chain, dispersed ones for several,
    chain c as the numpy backend's chain c; a dict name -> (n_chains, *shape) gives them; see
    ``gpmsa.mcmc.starts``). Warm-up and tuning
    (``tune=True``): ``tune_stages`` (3) stages of ``warmup`` (100) sweeps followed by GPM/SA's
    tuning: ``tune_levels`` candidate widths per element, each level swept ``tune_rounds`` times
    by every chain, the acceptance counts pooled over the chains (the default ``tune_rounds`` =
    ceil(50 / n_chains) gives each level at least GPM/SA's 50 trials per element); each stage
    starts from the last one's widths, where the chains then are (tuned once from dispersed
    starts, the widths fit the transient, not the posterior). All chains share the widths.
    ``step_widths`` replace GPM/SA's initial widths (given per chain, as a numpy fit records
    them: each element's median over the chains, which share one set). ``ridge_moves``:
    nugget-ridge moves per sweep (``gpmsa.mcmc.ridge``). ``proportional_steps``: the
    precisions' steps in the warm-up and sampling sweeps, GPM/SA's proportional one (True) or
    uniform with their widths (False); None: ``not tune``, as the numpy backend's ``sample``.
    Draws hold every sweep after the warm-up (no burn-in removed).
    ``device``: "cpu" or "cuda"; ``dtype``: "float64" (default) or "float32" (torch's default
    dtype and device, as the caller set them, are not used).
    ``num_threads``: torch's CPU threads while sampling (default 1, as the numpy backend; on a
    busy machine more threads made every small tensor op wait for the thread pool); None keeps
    torch's setting; at most ``MAX_THREADS`` (or the machine's CPUs, where more).

    Several cores, or a cluster, on the CPU: ``chain_groups`` > 1 splits the chains, after the
    (pooled) tuning, into that many batches of consecutive chains, each sampled in a worker
    process with its own random stream (a child of ``seed``'s SeedSequence after the chains'):
    ``n_jobs`` processes (None or -1: every CPU, never more than the groups) or any
    ``concurrent.futures.Executor`` / dask ``Client`` as ``executor``. The draws depend on
    ``chain_groups`` and ``seed``, never on ``n_jobs`` or where the groups ran; each worker
    runs one thread (``num_threads`` must be 1); a failed group is retried as the numpy
    backend's chains are (``gpmsa.mcmc.parallel``), then ``ChainError`` names its chains.
    A theta constraint or a callable mean basis (callables of this process) keeps the groups
    in this process, one after another (an ``executor`` is refused), as the numpy backend's
    chains (``gpmsa.mcmc.parallel.in_this_process``).

    ``temperatures``: parallel tempering (``gpmsa.mcmc.tempering``, as the numpy backend's; None:
    off, the sampler above bit for bit): an integer n (the ladder 2**k) or a ladder from 1. The
    batch then holds n_chains x K rows, chain c's copy k at row c K + k, whose likelihood
    enters its acceptance to the power 1/T_k (priors untempered); each copy's widths are tuned
    at its temperature (acceptance pooled over the chains' copy k), the categorical level
    shifts learnt at T = 1 and shared by the chain's copies; after every warm-up sweep and
    every tuning level, and every ``swap_every`` draw sweeps, neighbours k, k + 1 (k = 0 .. K -
    2 in turn) exchange their rows' states with probability min(1, exp((1/T_k - 1/T_{k+1})
    (log L_{k+1} - log L_k))) (`_swap_rows`). The T = 1 rows' draws, log posteriors,
    acceptance and widths are kept; ``info`` records "temperatures", "swap_every" and
    "swap_rate" (n_chains, K - 1) over the draws' swap rounds. Tuning runs in one batch;
    ``chain_groups`` > 1 (or an ``executor``) then samples groups of whole chains, each with
    all its K copies (tempering within the group as in one batch), with the groups' streams
    as above; draws, acceptance and swap rates are assembled in chain order.

    ``adapt_ladder`` (with ``temperatures``, at least 3, and ``tune``; as the numpy backend's,
    ``gpmsa.mcmc.tempering.adapt_ladder``): after the first stage's warm-up, ``tune_rounds`` x
    ``tune_levels`` further sweeps of every row (GPM/SA's candidate widths in turn), a swap
    round after each, move each chain's interior temperatures towards equal swap rates
    (`_adapt_ladders`: per chain, from its own swaps, rows c K + k at their chain's ladder);
    each chain's ladder is then frozen for the widths' tuning and every draw (an exact MCMC),
    its groups (``chain_groups`` > 1) given their chains' ladders. ``info`` records
    "adapt_ladder" and "adapted_temperatures" (n_chains, K) ("temperatures": the starting
    ladder).

    A tempered run's ``info`` records "hot_states" and "hot_step_widths" (name -> (n_chains, K
    - 1, *shape), as the numpy backend's): each hot copy's last state (float64) and its widths
    (copy k's shared by the chains; NaN where not sampled). ``hot_copies`` ({"starts": ...,
    "widths": ...} of that form; ``sampler.check_hot_copies``) starts row c K + k at chain c's
    hot copy k, each copy's widths the median over the chains of its given ones (run as they
    are where ``tune`` is False: a continuation resuming every copy where it stopped).
    """
    check_sample_args(n_iter, n_chains, seed)
    tune, progress = check_flag(tune, "tune"), check_flag(progress, "progress")
    prop_mh = proportional_step_choice(proportional_steps, tune)
    ladders = tempering.chain_ladders(temperatures, int(n_chains))  # each chain's
    temps = None if ladders is None else ladders[0]
    swap_every = tempering.check_swap_every(swap_every, temps, int(n_iter))
    adapt = tempering.check_adapt(adapt_ladder, temps, tune)
    copies = 1 if temps is None else len(temps)
    if temps is not None and ladders.count(temps) < len(ladders):  # a ladder per chain
        if adapt:
            raise GPMSAError(
                "adapt_ladder=True with a ladder per chain (temperatures (n_chains, K)): the "
                "torch backend adapts from one ladder; give temperatures= one ladder"
            )
        temps = np.array(ladders)
    hot = check_hot_copies(hot_copies, problem, ladders, int(n_chains))
    check_draws_memory(problem, int(n_iter), int(n_chains))
    check_batch_memory(problem, int(n_iter), int(n_chains), _dtype(dtype), copies)
    where = _check_groups(chain_groups, n_jobs, executor, int(n_chains), device, num_threads)
    where["n_jobs"], where["executor"] = in_this_process(
        callables(problem), where["n_jobs"], where["executor"], where["groups"]
    )
    with torch_threads(num_threads):
        return _sample(problem, n_iter, int(n_chains), tune, step_widths, seed, progress,
                       tune_rounds, tune_levels, device, dtype, init, warmup,
                       tune_stages, check_ridge(ridge_moves, problem), where, prop_mh,
                       temps, swap_every, adapt, hot)  # fmt: skip


def callables(problem: Problem) -> list[str]:
    """The callables of this process ``problem`` holds (names for `in_this_process`): a theta
    constraint, a callable mean basis (``Problem.callables``)."""
    return problem.callables


def check_batch_memory(problem: Problem, n_iter: int, n_chains: int, dtype: torch.dtype,
                       copies: int = 1) -> None:  # fmt: skip
    """ResourceLimitError (before any chain is set up) when the draws (`check_draws_memory`) and
    the batch's per-chain terms exceed ``gpmsa.limits.MAX_MEMORY_BYTES``: per chain and basis
    component the packed correlation matrix and its proposal buffer, and with observations the
    Sigma_W factor and its buffer (m x m each), none where Sigma_W is fixed (one for all); with
    observations also (`obs_values`) each component's cached observation terms, a proposal's
    cross-correlations and the observations' N x N covariance with its factor, one per chain.
    ``copies``: rows per chain (parallel tempering: one per temperature)."""
    shared = all(k in problem.fixed for k in SIM_PARAMS)
    if shared and problem.obs is None:
        return
    m, size = problem.m, float(dtype.itemsize)
    packed = sum((b - a) * b for a, b in row_blocks(m))
    per_chain = (
        0 if shared else problem.p_u * (2 * packed + (2 * m * m if problem.obs is not None else 0))
    )
    per_obs = obs_values(problem)
    rows = n_chains * copies
    mats = "Sigma_W" if problem.p_u == 1 else "Sigma_W's"
    name = str(dtype).replace("torch.", "")
    temps = f" at {copies} temperatures" if copies > 1 else ""
    what = [] if shared else [f"caches {problem.p_u} {mats} of {m} x {m} ({name})"]
    if per_obs > per_chain:  # named where it is the larger part
        big = problem.obs.sig_obs.shape[0]
        what.append(f"factors the observations' {big} x {big} covariance ({name})")
    check_memory(
        draws_nbytes(problem, n_iter, n_chains) + size * rows * (per_chain + per_obs),
        f"torch sample(n_iter={n_iter}, n_chains={n_chains}){temps}, which "
        f"{' and '.join(what)} per chain{' and temperature' if copies > 1 else ''},",
    )


def obs_values(problem: Problem) -> int:
    """A batch row's observation terms in values (0 without observations): the cached terms of
    every component (`obs_parts`: p_u (n^2 + n)), a proposal's correlations and solves against
    the runs (2 p_u n (m + n)) and the observations' covariance with its factor (`obs_combine`:
    2 N^2, N = n (p_u + p_v))."""
    obs = problem.obs
    if obs is None:
        return 0
    n, p_u, big = obs.x.shape[0], problem.p_u, obs.sig_obs.shape[0]
    return p_u * (n * n + n) + 2 * p_u * n * (problem.m + n) + 2 * big * big


def check_n_jobs(n_jobs, chain_groups: int, n_chains: int | None = None) -> None:
    """GPMSAError for an ``n_jobs`` that `sample` refuses with ``chain_groups`` (an integer in
    [1, n_chains]): a bad one (`n_workers`), or any above 1 with one group (one batch); its
    advice fits ``n_chains`` where given (chain_groups is at most n_chains)."""
    n_workers(n_jobs, chain_groups)  # refuse a bad n_jobs up front
    if chain_groups == 1 and n_jobs is not None and n_jobs > 1:
        if isinstance(n_chains, bool) or not isinstance(n_chains, int | np.integer) or n_chains < 1:
            n_chains = None  # (not given, or a bad one, refused by name where it is read)
        groups = n_jobs if n_chains is None else max(1, min(n_jobs, int(n_chains)))
        if groups == 1:
            fix = (
                f"n_chains={n_chains} is one chain, which runs in one process: leave n_jobs "
                f"out, or give n_chains >= {n_jobs} and chain_groups={n_jobs} for {n_jobs} "
                "processes"
            )
        elif n_chains is None or n_chains > groups:
            fix = f"give chain_groups={groups} (or more) to sample in {groups} processes"
        else:
            fix = (
                f"give chain_groups={groups} to sample in {groups} processes (one per chain "
                f"of n_chains={n_chains})"
            )
        raise GPMSAError(
            f"n_jobs={n_jobs} with chain_groups=1: the torch backend samples its chains as one "
            f"batch; {fix}"
        )


def _check_groups(chain_groups, n_jobs, executor, n_chains: int, device, num_threads) -> dict:
    """``sample``'s placement of the sampling phase: {"groups", "n_jobs", "executor"}."""
    if (
        isinstance(chain_groups, bool)
        or not isinstance(chain_groups, (int, np.integer))
        or not (1 <= chain_groups <= n_chains)
    ):
        raise GPMSAError(
            f"chain_groups must be an integer in [1, n_chains={n_chains}], got {chain_groups!r}"
        )
    remote = chain_groups > 1 or executor is not None
    if remote and _parsed_device(device).type != "cpu":
        raise GPMSAError(
            f"chain_groups > 1 and executor= run CPU worker processes; device={device!r} samples "
            "all chains in one batch (give chain_groups=1 and no executor)"
        )
    if remote and num_threads != 1:
        raise GPMSAError(
            f"with chain_groups > 1 or an executor each group's process runs one thread: give "
            f"num_threads=1 (got {num_threads!r}); use more groups for more cores"
        )
    check_n_jobs(n_jobs, int(chain_groups), n_chains)
    return {"groups": int(chain_groups), "n_jobs": n_jobs, "executor": executor}


def _sample(problem, n_iter, n_chains, tune, step_widths, seed, progress, tune_rounds,
            tune_levels, device, dtype, init, warmup, tune_stages, n_ridge,
            where, prop_mh: bool, temps: tuple[float, ...] | None = None,
            swap_every: int = 1, adapt: bool = False,
            hot: list | None = None) -> Chains:  # fmt: skip
    """``sample`` without the thread setting (``prop_mh``: its ``proportional_steps``, decided;
    ``temps``: the ladder, checked, or None; ``adapt``: its ``adapt_ladder``, checked; ``hot``:
    its ``hot_copies``, checked: each chain's K - 1 hot copies' (start, widths), or None)."""
    dev, dt = _device(device), _dtype(dtype)
    warmup = (WARMUP if tune else 0) if warmup is None else check_count(warmup, "warmup", 0)
    tune_stages = check_count(tune_stages, "tune_stages")
    if tune_rounds is None:
        tune_rounds = math.ceil(tuning.N_BURN / n_chains)
    tune_rounds, tune_levels = tuning.check_tuning(tune_rounds, tune_levels)
    per_chain = check_step_widths(step_widths, problem, n_chains)  # the chains share widths:
    widths = {k: np.median([w[k] for w in per_chain], axis=0) for k in problem.init}  # median
    gen = _seed_generator(seed, dev)
    seeds = np.random.SeedSequence(seed).spawn(n_chains)  # chain c starts as the numpy chain c
    how, firsts = starts.chain_starts(problem, init, seeds)
    start = {k: np.stack([f[k] for f in firsts]) for k in problem.init}
    copies = 1 if temps is None else np.shape(temps)[-1]
    rows = start if temps is None else {k: np.repeat(v, copies, axis=0) for k, v in start.items()}
    for c, chain in enumerate(hot or []):  # row c K + k: chain c's hot copy k where it stopped
        for k, (at, _) in enumerate(chain, start=1):
            for n in rows:
                rows[n][c * copies + k] = at[n]
    state = BatchState(problem, int(n_chains) * copies, dt, dev, rows, n_ridge)
    els = state.els
    w = np.array([float(widths[n][idx]) for n, idx in els])
    ws0 = None if hot is None else np.stack([w, *(  # each hot copy's: its median over the chains
        [float(np.median([chain[k][1][n][idx] for chain in hot])) for n, idx in els]
        for k in range(copies - 1))])  # fmt: skip
    n_stages = tune_stages if tune else 1
    total = n_iter + n_stages * (warmup + (tune_rounds * tune_levels if tune else 0))
    total += tune_rounds * tune_levels if adapt else 0  # the ladder's adaptation
    names = problem.names
    in_process = where["groups"] == 1 and where["executor"] is None
    if not in_process:
        total -= n_iter  # the groups' sweeps: counted by run_chains' bar over the groups
    ws = rates = None  # tempered: each copy's widths (K, n_el); the swap rates (C, K - 1)
    ladders = temps  # tempered: the draws' ladder (K,), or with adapt each chain's (C, K)
    with torch.no_grad(), progress_bar(progress, total, "torch MCMC", "it", mininterval=0.1) as bar:
        if temps is not None:
            ws, ladders = _tempered_tuning(state, w, temps, prop_mh, gen, bar, warmup=warmup,
                                           n_stages=n_stages, tune=tune,
                                           tune_rounds=tune_rounds, tune_levels=tune_levels,
                                           adapt=adapt, ws=ws0)  # fmt: skip
            w = ws[0]
            if in_process:
                draws, log_post, accepted, rates, hot_states = _tempered_draws(
                    state, ws, ladders, swap_every, n_iter, prop_mh, gen, bar
                )
        elif tune:  # the widths tuned with the level moves (a categorical theta; no draws used)
            state.learn_level_shifts()
        for _stage in range(n_stages if temps is None else 0):  # (tempered: done above)
            bar.set_description("torch MCMC: warm-up and tuning" if tune else "torch MCMC: warm-up")
            for _ in range(warmup):  # leave the starts (then the last widths' region) first
                state.sweep(w, prop_mh, gen)
                bar.update(1)
            if not (tune and els):
                break
            cands = tuning.level_widths([n for n, _ in els], w, tune_levels)
            acc = torch.zeros((tune_levels, len(els)), dtype=torch.long, device=dev)
            for _ in range(tune_rounds):
                for lev in range(tune_levels):
                    acc[lev] += state.sweep(cands[lev], False, gen).sum(-1)
                bar.update(tune_levels)
            w = tuning.choose_widths(w, cands, acc.cpu().numpy(), tune_rounds * n_chains)
        if temps is None:
            state.learn_level_shifts()  # found anew, frozen before the draws (categorical theta)
        if in_process and temps is None:
            bar.set_description("torch MCMC: sampling")
            draws, log_post, accepted = _sweeps(state, w, n_iter, prop_mh, gen, bar)
    if not in_process:
        draws, log_post, accepted, rates, hot_states = _grouped_sweeps(
            state, w if temps is None else ws, n_iter, prop_mh, seeds[0], where,
            dtype=str(dt).replace("torch.", ""), progress=progress, temps=ladders,
            swap_every=swap_every,
        )  # fmt: skip
    tempered = {} if temps is None else {"temperatures": np.asarray(temps).tolist(),
                                         "swap_every": swap_every,
                                         "swap_rate": rates}  # fmt: skip
    if adapt:  # each chain's ladder, adapted in its tuning and frozen for its draws
        tempered.update(adapt_ladder=True, adapted_temperatures=np.asarray(ladders))
    if temps is not None:  # each hot copy's last state and widths (n_chains, K - 1, *shape)
        tempered.update(hot_states=hot_states, hot_step_widths=_hot_widths(problem, els, ws,
                                                                           n_chains))  # fmt: skip
    rate = {n: np.full((n_chains, *problem.init[n].shape), np.nan) for n in names}
    wid = {n: np.full((n_chains, *problem.init[n].shape), np.nan) for n in names}
    acc_np = accepted / n_iter
    for i, (n, idx) in enumerate(els):
        rate[n][(slice(None), *idx)] = acc_np[i]
        wid[n][(slice(None), *idx)] = w[i]
    return Chains(
        draws=draws,
        log_post=log_post,
        accept_rate=rate,
        step_widths=wid,
        info={"n_iter": int(n_iter), "n_chains": int(n_chains), "tune": tune,
              "tune_rounds": tune_rounds, "tune_levels": tune_levels, "seed": seed,
              "init": how, "warmup": int(warmup), "tune_stages": n_stages, "starts": start,
              "ridge_moves": state.ridge_moves, "chain_groups": where["groups"],
              "backend": "torch", "proportional_steps": prop_mh,
              "device": str(dev), "dtype": str(dt).replace("torch.", ""),
              **({} if not state.level_shifts else {"level_offsets": {  # the joint level move
                  "shifted": [int(j) for j in state.shift_elements],
                  "offsets": {int(k): v[::copies].cpu().numpy().astype(np.float64)
                              for k, v in state.level_shifts.items()}}}),
              **tempered},
    )  # fmt: skip


def _hot_widths(problem: Problem, els: list, ws: np.ndarray, n_chains: int) -> dict:
    """Each hot copy's widths of ``ws`` (K, n_el; copy k's shared by the chains) as name ->
    (n_chains, K - 1, *shape), NaN where not sampled (``info`` "hot_step_widths")."""
    out = {n: np.full((n_chains, len(ws) - 1, *problem.init[n].shape), np.nan)
           for n in problem.names}  # fmt: skip
    for i, (n, idx) in enumerate(els):
        out[n][(slice(None), slice(None), *idx)] = ws[1:, i]
    return out


def _swap_rows(state: BatchState, betas: tuple[float, ...] | Tensor, u: Tensor, accepted: Tensor,
               probs: Tensor | None = None) -> None:  # fmt: skip
    """One round of neighbour swaps in every chain of a tempered batch (rows c K + k, K copies):
    for k = 0 .. K - 2 in turn, copies k and k + 1 exchange their rows' states
    (``BatchState.exchange``) where log u[k] (C,) is below (beta_k - beta_{k+1}) (log L_{k+1} -
    log L_k), as ``gpmsa.mcmc.tempering.swap``; adds the accepted swaps to accepted (K - 1, C)
    and, given ``probs`` (K - 1, C), sets probs[k] to the proposals' acceptance probabilities.
    ``betas``: the ladder's 1/T_k (K,) shared by every chain, or each chain's (C, K) tensor
    (an adapted ladder, `_adapt_ladders`)."""
    per_chain = isinstance(betas, Tensor)
    n_temps = betas.shape[1] if per_chain else len(betas)
    for k in range(n_temps - 1):
        ll = state.loglik.view(-1, n_temps)
        d_beta = betas[:, k] - betas[:, k + 1] if per_chain else betas[k] - betas[k + 1]
        log_r = d_beta * (ll[:, k + 1] - ll[:, k])
        if probs is not None:
            probs[k] = torch.exp(torch.clamp(log_r, max=0.0))
        acc = torch.log(u[k]) < log_r
        if acc.any():
            rows = torch.nonzero(acc).squeeze(-1) * n_temps + k
            state.exchange(rows, rows + 1)
        accepted[k] += acc


def _temper(state: BatchState, temps) -> tuple[float, ...] | Tensor:
    """Set ``state.beta`` for rows c K + k at ``temps[k]`` (a ladder (K,) shared by every chain;
    returns 1/T_k) or at ``temps[c, k]`` (an array (C, K), each chain's; returns 1/T (C, K))."""
    if isinstance(temps, np.ndarray) and temps.ndim == 2:
        betas = state.ll_w.new_tensor(1.0 / temps)
        state.beta = betas.flatten()
        return betas
    betas = tuple(1.0 / t for t in temps)
    state.beta = state.ll_w.new_tensor(betas).repeat(state.n_chains // len(temps))
    return betas


def _copy_widths(state: BatchState, per_copy: np.ndarray) -> Tensor:
    """Each copy's widths (K, n_el) as each row's (n_el, C K) of a tempered batch."""
    n_temps = per_copy.shape[0]
    return state.ll_w.new_tensor(per_copy.T).repeat(1, state.n_chains // n_temps)


def _swap_round(state: BatchState, betas: tuple[float, ...] | Tensor, gen: torch.Generator,
                swaps: Tensor, probs: Tensor | None = None) -> None:  # fmt: skip
    """`_swap_rows` with uniforms (K - 1, C) drawn from ``gen``; counts into swaps (K - 1, C)."""
    u = torch.rand(swaps.shape, generator=gen, dtype=state.ll_w.dtype, device=state.ll_w.device)
    _swap_rows(state, betas, u, swaps, probs)


def _tempered_tuning(state: BatchState, w: np.ndarray, temps: tuple[float, ...], prop_mh: bool,
                     gen: torch.Generator, bar, *, warmup: int, n_stages: int, tune: bool,
                     tune_rounds: int, tune_levels: int, adapt: bool = False,
                     ws: np.ndarray | None = None) -> tuple:  # fmt: skip
    """``_sample``'s warm-up and tuning with parallel tempering (``sample``'s
    ``temperatures``): ``state`` holds C chains x K copies (row c K + k at temperature
    ``temps[k]``), every copy from the widths ``w`` (n_el,), or copy k from ``ws[k]`` (K, n_el;
    resumed hot copies). Each stage: ``warmup`` sweeps,
    then GPM/SA's tuning of each copy's widths at its temperature (acceptance pooled over the
    chains' copy k), a swap round (`_swap_rows`) after each sweep and each tuning level; then
    the level shifts learnt at T = 1. ``adapt`` (``sample``'s ``adapt_ladder``): after the
    first stage's warm-up, each chain's ladder adapted (`_adapt_ladders`) and frozen for the
    tuning that follows. Returns each copy's widths (K, n_el) and the draws' ladder, ``temps``
    or with ``adapt`` each chain's (C, K), for `_tempered_draws`."""
    n_temps, n_el = np.shape(temps)[-1], len(state.els)
    n_chains = state.n_chains // n_temps
    betas = _temper(state, temps)
    swaps = torch.zeros((n_temps - 1, n_chains), dtype=torch.long, device=state.ll_w.device)
    names = [n for n, _ in state.els]
    ws = np.tile(w, (n_temps, 1)) if ws is None else ws  # each copy's widths
    if tune:  # the widths tuned with the level moves (a categorical theta), learnt at T = 1
        state.learn_level_shifts(n_temps)
    for _stage in range(n_stages):
        bar.set_description(f"torch MCMC: warm-up{' and tuning' if tune else ''} ({n_temps} "
                            "temperatures)")  # fmt: skip
        per_row = _copy_widths(state, ws)
        for _ in range(warmup):
            state.sweep(per_row, prop_mh, gen)
            _swap_round(state, betas, gen, swaps)
            bar.update(1)
        if not (tune and n_el):
            break
        if adapt and _stage == 0:
            temps = _adapt_ladders(state, w, temps, gen, bar, tune_rounds, tune_levels)
            betas = _temper(state, temps)  # frozen from here: the tuning's and draws' ladders
            bar.set_description(f"torch MCMC: tuning ({n_temps} temperatures, adapted)")
        cands = [tuning.level_widths(names, ws[k], tune_levels) for k in range(n_temps)]
        levels = [_copy_widths(state, np.stack([c[lev] for c in cands]))
                  for lev in range(tune_levels)]  # fmt: skip
        acc = torch.zeros((tune_levels, n_el, n_temps), dtype=torch.long, device=swaps.device)
        for _ in range(tune_rounds):
            for lev in range(tune_levels):
                took = state.sweep(levels[lev], False, gen)  # (n_el, C K)
                acc[lev] += took.view(n_el, n_chains, n_temps).sum(1)
                _swap_round(state, betas, gen, swaps)
            bar.update(tune_levels)
        counts = acc.cpu().numpy()
        ws = np.stack([tuning.choose_widths(ws[k], cands[k], counts[..., k],
                                            tune_rounds * n_chains)
                       for k in range(n_temps)])  # fmt: skip
    state.learn_level_shifts(n_temps)  # anew at T = 1, shared by the copies, frozen
    if adapt and not isinstance(temps, np.ndarray):  # (no element to sweep: none adapted)
        temps = np.tile(np.asarray(temps, dtype=float), (n_chains, 1))
    return ws, temps


def _adapt_ladders(state: BatchState, w: np.ndarray, temps: tuple[float, ...], gen: torch.Generator,
                   bar, tune_rounds: int, tune_levels: int) -> np.ndarray:  # fmt: skip
    """The adaptive ladder (``gpmsa.mcmc.tempering.adapt_ladder``, the numpy backend's) of
    every chain of a tempered batch, its rows c K + k from the starting ladder ``temps`` (K,):
    ``tune_rounds`` x ``tune_levels`` sweeps of every row at GPM/SA's candidate widths of ``w``
    in turn (acceptances not kept), a swap round (`_swap_rows`) after each, after which each
    chain's log gaps move by its own pairs' acceptance probabilities (``tempering.adapt_gaps``)
    and its rows take its new ladder. Returns each chain's ladder kept (C, K; the mean of the
    second half's log gaps, ``tempering.kept_ladder``; the starting ladder where two of its rungs
    share one 1/T in the batch's dtype), ``state.beta`` set to it."""
    n_temps = len(temps)
    n_chains = state.n_chains // n_temps
    start = np.asarray(temps, dtype=float)
    top = float(start[-1])
    log_gap = np.tile(np.log(np.diff(start)), (n_chains, 1))
    mean_gap, n_mean = np.zeros_like(log_gap), 0
    cands = tuning.level_widths([n for n, _ in state.els], w, tune_levels)
    swaps = torch.zeros((n_temps - 1, n_chains), dtype=torch.long, device=state.ll_w.device)
    probs = state.ll_w.new_empty((n_temps - 1, n_chains))
    betas = _temper(state, np.tile(start, (n_chains, 1)))
    bar.set_description(f"torch MCMC: adapting the ladder ({n_temps} temperatures)")
    n_total = tune_rounds * tune_levels
    for n in range(n_total):
        lev = n % tune_levels
        state.sweep(cands[lev], False, gen)
        _swap_round(state, betas, gen, swaps, probs)
        a = probs.T.cpu().numpy().astype(np.float64)  # (C, K - 1)
        log_gap = tempering.adapt_gaps(log_gap, a, n, top)
        betas = _temper(state, tempering.gap_ladder(log_gap, top))
        if 2 * n >= n_total:  # the second half's mean (Polyak averaging)
            mean_gap += log_gap
            n_mean += 1
        if lev == tune_levels - 1:
            bar.update(tune_levels)
    ladders = tempering.kept_ladder(mean_gap / max(n_mean, 1), start)
    betas = _temper(state, ladders)
    merged = (betas[:, 1:] >= betas[:, :-1]).any(1).cpu().numpy()  # rungs one in the dtype
    if merged.any():  # (float32's 1/T merges rungs float64 keeps apart): the start stays
        ladders[merged] = start
        _temper(state, ladders)
    return ladders


def _tempered_draws(state: BatchState, ws: np.ndarray, temps, swap_every: int, n_iter: int,
                    prop_mh: bool, gen: torch.Generator, bar) -> tuple:  # fmt: skip
    """``n_iter`` sweeps of a tempered batch (rows c K + k at ``temps[k]``, or at ``temps[c,
    k]`` with each chain's ladder (C, K), an adapted one; each copy at its widths ``ws`` (K,
    n_el)), a swap round every ``swap_every``: `_sweeps`' draws, log posterior and accepted
    counts of the T = 1 rows, the swap rate (C, K - 1) of each neighbour pair over the swap
    rounds and the hot copies' last states name -> (C, K - 1, *shape) (float64). One batch's,
    or a chain group's (`_group_task`)."""
    n_temps = np.shape(temps)[-1]
    n_chains = state.n_chains // n_temps
    betas = _temper(state, temps)
    dt, dev = state.ll_w.dtype, state.ll_w.device
    bar.set_description(f"torch MCMC: sampling ({n_temps} temperatures)")
    problem, cold, per_row = state.problem, slice(None, None, n_temps), _copy_widths(state, ws)
    draws = {n: torch.empty((n_iter, n_chains, *problem.init[n].shape), dtype=dt, device=dev)
             for n in problem.names}  # fmt: skip
    log_post = torch.empty((n_iter, n_chains), dtype=dt, device=dev)
    accepted = torch.zeros((len(state.els), n_chains), dtype=torch.long, device=dev)
    swaps = torch.zeros((n_temps - 1, n_chains), dtype=torch.long, device=dev)
    for it in range(n_iter):
        accepted += state.sweep(per_row, prop_mh, gen)[:, cold]
        if it % swap_every == swap_every - 1:
            _swap_round(state, betas, gen, swaps)
        for n in problem.names:
            draws[n][it] = state.params[n][cold]
        log_post[it] = state.log_post()[cold]
        bar.update(1)
    rate = swaps.cpu().numpy().T / max(n_iter // swap_every, 1)
    hot = {n: v.cpu().numpy().astype(np.float64).reshape(n_chains, n_temps, *v.shape[1:])[:, 1:]
           for n, v in state.params.items()}  # fmt: skip
    return ({n: np.moveaxis(v.cpu().numpy(), 0, 1) for n, v in draws.items()},
            log_post.cpu().numpy().T, accepted.cpu().numpy(), rate, hot)  # fmt: skip


def _sweeps(
    state: BatchState, widths: np.ndarray, n_iter: int, prop_mh: bool, gen: torch.Generator, bar
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """``n_iter`` recorded sweeps of every chain of ``state``: draws name -> (C, n_iter, *shape),
    log posterior (C, n_iter) and accepted counts (n_el, C), as numpy arrays."""
    problem, c = state.problem, state.n_chains
    dt, dev = state.ll_w.dtype, state.ll_w.device
    draws = {n: torch.empty((n_iter, c, *problem.init[n].shape), dtype=dt, device=dev)
             for n in problem.names}  # fmt: skip
    log_post = torch.empty((n_iter, c), dtype=dt, device=dev)
    accepted = torch.zeros((len(state.els), c), dtype=torch.long, device=dev)
    for it in range(n_iter):
        accepted += state.sweep(widths, prop_mh, gen)
        for n in problem.names:
            draws[n][it] = state.params[n]
        log_post[it] = state.log_post()
        bar.update(1)
    return ({n: np.moveaxis(v.cpu().numpy(), 0, 1) for n, v in draws.items()},
            log_post.cpu().numpy().T, accepted.cpu().numpy())  # fmt: skip


def _group_task(problem: Problem, start: dict[str, np.ndarray], widths: np.ndarray, n_iter: int,
                prop_mh: bool, stream: int, dtype: str, ridge_moves: int, progress: bool = False,
                desc: str = "torch chains", level_shifts: tuple | None = None,
                temps=None, swap_every: int = 1) -> tuple:  # fmt: skip
    """One chain group's sweeps from plain data (run in a worker process, one thread);
    ``level_shifts``: the group's (``BatchState.shift_elements``, element -> offsets (C', K,
    n)) of the joint level move (None: none). ``temps``: parallel tempering (None: off; the
    ladder (K,), or its chains' adapted ladders (C', K));
    ``start`` then holds the group's chains' rows c K + k (every copy), ``widths`` each copy's
    (K, n_el), and the result adds the swap rates and hot copies' states (`_tempered_draws`)."""
    with torch_threads(1), torch.no_grad():
        n_rows = len(next(iter(start.values())))
        state = BatchState(problem, n_rows, _dtype(dtype), "cpu", start, ridge_moves)
        if level_shifts is not None:
            state.shift_elements = list(level_shifts[0])
            state.level_shifts = {k: torch.as_tensor(v, dtype=state.ll_w.dtype, device="cpu")
                                  for k, v in level_shifts[1].items()}  # fmt: skip
        gen = torch.Generator().manual_seed(stream)
        with progress_bar(progress, n_iter, desc, "it", mininterval=0.1) as bar:
            if temps is not None:
                return _tempered_draws(state, widths, temps, swap_every, n_iter, prop_mh, gen,
                                       bar)  # fmt: skip
            return _sweeps(state, widths, n_iter, prop_mh, gen, bar)


def _grouped_sweeps(state: BatchState, widths: np.ndarray, n_iter: int, prop_mh: bool,
                    first: np.random.SeedSequence, where: dict, *, dtype: str, progress: bool,
                    temps: tuple | None = None, swap_every: int = 1) -> tuple:  # fmt: skip
    """``_sweeps`` of consecutive chain groups in worker processes (``gpmsa.mcmc.parallel``);
    group g's stream is child n_chains + g of the seed's SeedSequence (``first`` is child 0).
    ``temps``: parallel tempering (``widths`` each copy's (K, n_el)): each group holds whole
    chains, rows c K + k of all K copies, and runs `_tempered_draws` (``temps`` (C, K), each
    chain's adapted ladder: each group given its chains'). Returns draws, log posterior,
    accepted counts, the swap rates (C, K - 1) and the hot copies' last states (name -> (C, K -
    1, *shape)); the last two None untempered."""
    copies = 1 if temps is None else np.shape(temps)[-1]
    per_chain = isinstance(temps, np.ndarray) and temps.ndim == 2
    c, k = state.n_chains // copies, where["groups"]
    bounds = np.linspace(0, c, k + 1).round().astype(int)
    tasks = []
    for g in range(k):
        lo, hi = int(bounds[g]) * copies, int(bounds[g + 1]) * copies  # the chains' rows
        seq = np.random.SeedSequence(first.entropy, spawn_key=(c + g,))
        tasks.append({
            "problem": state.problem, "widths": np.asarray(widths), "n_iter": int(n_iter),
            "start": {n: v[lo:hi].cpu().numpy().copy() for n, v in state.params.items()},
            "prop_mh": bool(prop_mh), "dtype": dtype, "ridge_moves": state.ridge_moves,
            "stream": int(seq.generate_state(1, dtype=np.uint64)[0]) & (2**63 - 1),
            "level_shifts": (tuple(state.shift_elements), {
                k: v[lo:hi].cpu().numpy().copy() for k, v in state.level_shifts.items()
            }) if state.level_shifts else None,
            **({} if temps is None else {
                "temps": temps[bounds[g]:bounds[g + 1]].copy() if per_chain else tuple(temps),
                "swap_every": int(swap_every)}),
        })  # fmt: skip
    shapes = {n: v.shape[1:] for n, v in state.params.items()}

    def check(g: int, result) -> str | None:
        size = int(bounds[g + 1] - bounds[g])
        expected = ({n: (size, int(n_iter), *v) for n, v in shapes.items()},
                    (size, int(n_iter)), (len(state.els), size))  # fmt: skip
        if temps is not None:
            expected = (*expected, (size, copies - 1),
                        {n: (size, copies - 1, *v) for n, v in shapes.items()})  # fmt: skip
        return wrong_result(result, expected, f"{size} chains x {n_iter} sweeps")

    try:
        runs = run_chains(_group_task, tasks, n_jobs=where["n_jobs"], executor=where["executor"],
                          progress=progress, desc="torch chain groups", what="chain group",
                          check=check)  # fmt: skip
    except ChainError as exc:
        g = exc.chains[0] if exc.chains else 0
        chains = tuple(range(int(bounds[g]), int(bounds[g + 1])))
        raise ChainError(f"chains {chains[0]}-{chains[-1]}: {exc}", chains) from exc
    draws = {n: np.concatenate([r[0][n] for r in runs]) for n in runs[0][0]}
    rates = None if temps is None else np.concatenate([r[3] for r in runs])
    hot = None if temps is None else {n: np.concatenate([r[4][n] for r in runs]) for n in shapes}
    return (draws, np.concatenate([r[1] for r in runs]), np.concatenate([r[2] for r in runs], 1),
            rates, hot)  # fmt: skip
