"""GPM/SA log-likelihood and log-posterior (numpy): a direct reference and an incremental form.

log L = log N(w; 0, Sigma_W) + log N(z; [0; Sigma_UW Sigma_W^-1 w], Sigma_VUgW + Sigma_obs/lamOs),
constants dropped (log N = -sum log diag chol - r^T Sigma^-1 r / 2). See docs/internals.md.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import cho_solve, lapack

from gpmsa.model.correlation import CATEGORICAL_DISTANCE, correlation, sq_diffs
from gpmsa.model.mean_basis import GLS
from gpmsa.model.problem import Problem


def lower_cholesky(S: np.ndarray) -> np.ndarray | None:
    """Lower Cholesky factor of symmetric S (upper triangle left as garbage), None if not PD.

    S is overwritten. S.T is passed so that LAPACK works on a Fortran-ordered view without a copy.
    """
    L, info = lapack.dpotrf(S.T, lower=1, clean=0, overwrite_a=1)
    return L if info == 0 else None


def _tri_solve(L: np.ndarray, b: np.ndarray) -> np.ndarray:
    """L^-1 b for a lower-triangular factor L (only its lower triangle is read)."""
    x, _ = lapack.dtrtrs(L, b, lower=1)
    return x


def _logdet_half(L: np.ndarray) -> float:
    return float(np.sum(np.log(np.diagonal(L))))


def log_prior(problem: Problem, params: dict[str, np.ndarray]) -> float:
    """Sum of the log priors of the sampled (non-fixed) parameters (a categorical theta element:
    uniform over its levels, ``Problem.theta_log_prior``); held elements
    (``problem.fixed_elements``) add nothing."""
    total = sum(problem.theta_log_prior(params[n]) if n == "theta"
                else problem.priors.log_prior(n, params[n]) for n in problem.sampled)  # fmt: skip
    return total - held_log_prior(problem, params) if problem.fixed_elements else total


def held_log_prior(problem: Problem, params: dict[str, np.ndarray]) -> float:
    """Sum of the element log priors of the held elements (``problem.fixed_elements``) at
    ``params``: the constant that the sampled parameters' whole-array priors count for them (a
    categorical theta element: 0, its uniform prior)."""
    levels = problem.theta_levels or [None] * problem.q
    total = 0.0
    for name, held in problem.fixed_elements.items():
        for idx in held:
            if name != "theta" or levels[idx[0]] is None:
                total += problem.priors.scalar_log_prior(name, idx[-1])(float(params[name][idx]))
    return total


def log_likelihood(problem: Problem, params: dict[str, np.ndarray]) -> float:
    """Reference GPM/SA log-likelihood at ``params`` (dense, recomputed from scratch)."""
    zt, w = problem.zt, problem.w
    m = problem.m
    bu, luz, lws, lwos = (params[k] for k in ("betaU", "lamUz", "lamWs", "lamWOs"))
    cat, mb = problem.categorical, problem.mean_basis
    H = None if mb is None else mb.matrix(zt)
    ll = 0.0
    chols, alphas, coefs = [], [], []
    for j in range(problem.p_u):
        S = correlation(zt, None, bu[:, j], cat) / luz[j]
        S[np.diag_indices(m)] += 1.0 / (problem.lam_sim[j] * lwos[0]) + 1.0 / lws[j]
        L = lower_cholesky(S)
        if L is None:
            return -np.inf
        a = _tri_solve(L, w[:, j])
        coef = None
        if H is not None:  # restricted likelihood: the mean coefficients integrated out
            g = GLS.of(np.tril(L), w[:, j], H)
            coef = g.coef
            a = a - g.A @ coef
            ll -= float(np.sum(np.log(np.diagonal(g.Q[0]))))
        ll += -_logdet_half(L) - 0.5 * float(a @ a)
        chols.append(L)
        alphas.append(a)
        coefs.append(coef)
    obs = problem.obs
    if obs is None:
        return ll
    n, p_v = obs.n, obs.p_v
    xt = np.hstack([obs.x, np.tile(params["theta"], (n, 1))])
    h_obs = None if mb is None else mb.matrix(xt)
    C = obs.sig_obs / params["lamOs"][0]
    mu = np.zeros(C.shape[0])
    for j in range(problem.p_u):
        sig_u = correlation(xt, None, bu[:, j], cat) / luz[j] + np.eye(n) / lws[j]
        B = _tri_solve(chols[j], correlation(xt, zt, bu[:, j], cat).T / luz[j])
        o = 0 if obs.scalar_out else n * (p_v + j)
        C[o : o + n, o : o + n] += sig_u - B.T @ B
        mu[o : o + n] = B.T @ alphas[j]
        if h_obs is not None:
            mu[o : o + n] += h_obs @ coefs[j]
    if p_v:
        x_cat = None if cat is None else cat[: problem.p]
        bv, lvz = params["betaV"], params["lamVz"]
        sig_v = [correlation(obs.x, None, bv[:, g], x_cat) / lvz[g] for g in range(obs.n_groups)]
        for i, g in enumerate(obs.block_groups):
            C[i * n : (i + 1) * n, i * n : (i + 1) * n] += sig_v[g]
    L = lower_cholesky(C)
    if L is None:
        return -np.inf
    r = _tri_solve(L, obs.z - mu)
    return ll - _logdet_half(L) - 0.5 * float(r @ r) + obs.null_term(float(params["lamOs"][0]))


def log_posterior(problem: Problem, params: dict[str, np.ndarray]) -> float:
    """log likelihood + log prior (the sampled parameters' priors)."""
    lp = log_prior(problem, params)
    return lp if lp == -np.inf else lp + log_likelihood(problem, params)


class _Packed:
    """The lower triangle of an m x m matrix as row blocks [i0:i1, :i1] stored contiguously.

    Elementwise work (exp, scaling) on the packed vector touches about half of the matrix.
    """

    def __init__(self, m: int, n_blocks: int):
        edges = np.unique(np.linspace(0, m, min(n_blocks, m) + 1).round().astype(int))
        self.blocks = [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]
        self.offsets = np.cumsum([0] + [(b - a) * b for a, b in self.blocks])
        self.size = int(self.offsets[-1])

    def pack(self, full: np.ndarray) -> np.ndarray:
        """Packed copy of ``full``'s lower blocks."""
        return np.concatenate([full[a:b, :b].ravel() for a, b in self.blocks])

    def views(self, flat: np.ndarray) -> list[np.ndarray]:
        """2-D views (b - a, b) into a packed vector, one per block."""
        return [
            flat[o : o + (b - a) * b].reshape(b - a, b)
            for o, (a, b) in zip(self.offsets[:-1], self.blocks, strict=True)
        ]

    def full_views(self, full: np.ndarray) -> list[np.ndarray]:
        """The matching block views into a full m x m matrix."""
        return [full[a:b, :b] for a, b in self.blocks]


class _Component:
    """Double-buffered state of basis component j: -G, R (packed), Sigma_W's Cholesky factor.

    ``ri`` indexes the current (-G, R) pair and ``si`` the current factor buffer; a proposal
    writes into the other buffer, and accepting it flips the index (no allocation per proposal).
    """

    def __init__(self, packed: _Packed, m: int, neg_g: np.ndarray):
        self.ng = [neg_g, np.empty_like(neg_g)]
        self.r = [np.exp(neg_g), np.empty_like(neg_g)]
        self.S = [np.zeros((m, m)), np.zeros((m, m))]
        self.S_views = [packed.full_views(a) for a in self.S]
        self.S_diag = [a.reshape(-1)[:: m + 1] for a in self.S]
        self.ri = 0
        self.si = 0
        self.ok = True
        self.L = self.alpha = self.llw = self.B = self.mu = self.cond = self.coef = None
        self.cxz = self.cxo = None


class IncrementalLikelihood:
    """The log-likelihood, updated for one changed element at a time (the sampler's hot path).

    Keeps per component j: -G_j = -sum_k beta_kj D_k and R_j = exp(-G_j) on the packed lower
    triangle, the Cholesky factor of Sigma_W_j, L^-1 w_j and the observation cross terms. A
    proposal recomputes only what the changed parameter touches (one m x m Cholesky for
    betaU/lamUz/lamWs, p_u for lamWOs, none for theta, lamOs, betaV, lamVz). ``propose``
    returns the candidate's log-likelihood; ``accept`` commits it.
    """

    N_BLOCKS = 12

    def __init__(self, problem: Problem, params: dict[str, np.ndarray]):
        self.problem = problem
        self.params = {k: np.array(v, dtype=np.float64) for k, v in params.items()}
        m = problem.m
        self.packed = _Packed(m, self.N_BLOCKS)
        cat = problem.categorical
        x_cat = None if cat is None else cat[: problem.p]
        D = sq_diffs(problem.zt, None, cat)
        self.D = [self.packed.pack(d) for d in D]
        mb = problem.mean_basis
        self.mean_basis = mb
        self.H = None if mb is None else np.asfortranarray(mb.matrix(problem.zt))
        self.tmp = np.empty(self.packed.size)
        self.tmp_views = self.packed.views(self.tmp)
        self.w_cols = [np.ascontiguousarray(problem.w[:, j]) for j in range(problem.p_u)]
        obs = problem.obs
        self.Dxz_t = None
        if obs is not None:
            self.p = problem.p
            n = obs.n
            self.Dxo = sq_diffs(obs.x, None, x_cat).reshape(self.p, n * n)
            self.Dxz_x = sq_diffs(obs.x, problem.x_sim, x_cat).reshape(self.p, n * problem.m)
            self.shape_nm = (n, problem.m)
            self.shape_nn = (n, n)
            self.t_sim_T = problem.t_sim.T.copy()
            t_cat = None if cat is None else cat[problem.p :]
            self.theta_cat = None if t_cat is None or not t_cat.any() else np.flatnonzero(t_cat)
            self.z = obs.z
            self.eye_n = np.eye(obs.n)
            self.Dxz_t = self._theta_dists(self.params["theta"])
        self.comps = []
        for j in range(problem.p_u):
            beta = self.params["betaU"][:, j]
            c = _Component(self.packed, m, -sum(b * d for b, d in zip(beta, self.D, strict=True)))
            self.comps.append(c)
            out = self._factor(c, j, c.ri, 0, self.params)
            if obs is not None:
                cross = (self._cross_z(beta, self.Dxz_t), self._cross_o(beta))
                out += self._obs_part(out, j, self.params, *cross)
            self._commit(c, out)
        self.sig_v = self._sig_v(self.params) if obs is not None and obs.p_v else None
        self.ll_vu = self._vu(self._obs_terms(), self.sig_v, self.params)
        self.loglik = float(sum(c.llw for c in self.comps)) + self.ll_vu
        self._pending = None

    # --- pieces -------------------------------------------------------------------------------
    def _factor(self, c: _Component, j: int, ri: int, si: int, prm: dict) -> tuple:
        """Factor Sigma_W_j from R buffer ``ri`` into S buffer ``si``: (ri, si, alpha, llw, L,
        coef); with a mean basis alpha = L^-1 (w - H coef) and coef the GLS coefficients (else
        alpha = L^-1 w, coef None)."""
        scale = 1.0 / prm["lamUz"][j]
        nug = 1.0 / (self.problem.lam_sim[j] * prm["lamWOs"][0]) + 1.0 / prm["lamWs"][j]
        np.multiply(c.r[ri], scale, out=self.tmp)
        for src, dst in zip(self.tmp_views, c.S_views[si], strict=True):
            dst[...] = src
        diag = c.S_diag[si]
        diag += nug
        # S holds Sigma_W in its lower triangle (C order) = the upper triangle of S.T (F order).
        L, info = lapack.dpotrf(c.S[si].T, lower=0, clean=0, overwrite_a=1)
        if info != 0:
            return (ri, si, None, -np.inf, None, None)
        alpha, _ = lapack.dtrtrs(L, self.w_cols[j], lower=0, trans=1)
        llw = -float(np.sum(np.log(diag)))
        coef = None
        if self.H is not None:  # restricted likelihood: the mean coefficients integrated out
            A, _ = lapack.dtrtrs(L, self.H, lower=0, trans=1)
            Lq = lower_cholesky(A.T @ A)
            if Lq is None:
                return (ri, si, None, -np.inf, None, None)
            coef = cho_solve((Lq, True), A.T @ alpha)
            alpha = alpha - A @ coef
            llw -= float(np.sum(np.log(np.diagonal(Lq))))
        llw -= 0.5 * float(alpha @ alpha)
        return (ri, si, alpha, llw, L, coef)

    def _theta_dists(self, theta: np.ndarray) -> np.ndarray:
        """(q, m) squared differences (categorical: 1/4 between levels) of theta from the design
        (the same for every observation row)."""
        d = np.square(theta[:, None] - self.t_sim_T)
        if self.theta_cat is not None:
            k = self.theta_cat
            d[k] = CATEGORICAL_DISTANCE * (theta[k, None] != self.t_sim_T[k])
        return d

    def _cross_z(self, beta: np.ndarray, dxz_t: np.ndarray) -> np.ndarray:
        """Unscaled correlation (n, m) of [x_obs, theta] with the design."""
        g = (beta[: self.p] @ self.Dxz_x).reshape(self.shape_nm) + beta[self.p :] @ dxz_t
        return np.exp(-g)

    def _cross_o(self, beta: np.ndarray) -> np.ndarray:
        """Unscaled correlation (n, n) among the observations (theta is common to all)."""
        return np.exp(-(beta[: self.p] @ self.Dxo)).reshape(self.shape_nn)

    def _obs_part(self, fac: tuple, j: int, prm: dict, cxz: np.ndarray, cxo: np.ndarray) -> tuple:
        """Cross terms (B, mu, cond, cxz, cxo) of component j given its factor tuple."""
        _, _, alpha, _, L, coef = fac
        if L is None:
            return (None, None, None, cxz, cxo)
        scale = 1.0 / prm["lamUz"][j]
        B, _ = lapack.dtrtrs(L, cxz.T * scale, lower=0, trans=1)
        Bt = B.T
        cond = cxo * scale - Bt @ B
        cond += self.eye_n * (1.0 / prm["lamWs"][j])
        mu = Bt @ alpha
        if coef is not None:  # the GLS mean at [x_obs, theta]
            obs = self.problem.obs
            xt = np.hstack([obs.x, np.tile(prm["theta"], (obs.n, 1))])
            mu = mu + self.mean_basis.matrix(xt) @ coef
        return (B, mu, cond, cxz, cxo)

    @staticmethod
    def _commit(c: _Component, out: tuple) -> None:
        c.ri, c.si, c.alpha, c.llw, c.L, c.coef = out[:6]
        c.ok = c.L is not None
        if len(out) > 6:
            c.B, c.mu, c.cond, c.cxz, c.cxo = out[6:]

    def _obs_terms(self) -> list[tuple]:
        return [(c.mu, c.cond) if c.ok else (None, None) for c in self.comps]

    def _sig_v(self, prm: dict) -> np.ndarray:
        """(G, n, n) discrepancy covariance of each precision group."""
        sig_v = np.exp(-(prm["betaV"].T @ self.Dxo)) / prm["lamVz"][:, None]
        return sig_v.reshape(-1, *self.shape_nn)

    def _vu(self, terms: list[tuple], sig_v, prm: dict) -> float:
        obs = self.problem.obs
        if obs is None:
            return 0.0
        if any(mu is None for mu, _ in terms):
            return -np.inf
        n, p_v = obs.n, obs.p_v
        C = obs.sig_obs * (1.0 / prm["lamOs"][0])
        mean = np.zeros(C.shape[0])
        for j, (mu, cond) in enumerate(terms):
            o = 0 if obs.scalar_out else n * (p_v + j)
            C[o : o + n, o : o + n] += cond
            mean[o : o + n] = mu
        if sig_v is not None:
            for i, g in enumerate(obs.block_groups):
                C[i * n : (i + 1) * n, i * n : (i + 1) * n] += sig_v[g]
        if C.shape[0] == 1:  # one scalar observation: no factorisation needed
            var = float(C[0, 0])
            r = float(self.z[0] - mean[0])
            return -0.5 * math.log(var) - 0.5 * r * r / var if var > 0 else -np.inf
        L = lower_cholesky(C)
        if L is None:
            return -np.inf
        r = _tri_solve(L, self.z - mean)
        return -_logdet_half(L) - 0.5 * float(r @ r) + obs.null_term(float(prm["lamOs"][0]))

    # --- proposals ----------------------------------------------------------------------------
    def propose(self, name: str, idx: tuple[int, ...], value: float) -> float:
        """Log-likelihood with element ``idx`` of ``name`` set to ``value`` (pending accept)."""
        prm = dict(self.params)
        arr = prm[name].copy()
        old = float(arr[idx])
        arr[idx] = value
        prm[name] = arr
        has_obs = self.problem.obs is not None
        dxz_t = self.Dxz_t
        sig_v = self.sig_v
        changed: dict[int, tuple] = {}
        cross: dict[int, tuple] = {}
        if name == "betaU":
            k, j = idx
            c = self.comps[j]
            new = 1 - c.ri
            np.multiply(self.D[k], old - value, out=self.tmp)
            np.add(c.ng[c.ri], self.tmp, out=c.ng[new])
            np.exp(c.ng[new], out=c.r[new])
            changed[j] = self._factor(c, j, new, 1 - c.si, prm)
            if has_obs:
                cross[j] = (self._cross_z(arr[:, j], dxz_t), self._cross_o(arr[:, j]))
        elif name in ("lamUz", "lamWs"):
            j = idx[0]
            c = self.comps[j]
            changed[j] = self._factor(c, j, c.ri, 1 - c.si, prm)
        elif name == "lamWOs":
            for j, c in enumerate(self.comps):
                changed[j] = self._factor(c, j, c.ri, 1 - c.si, prm)
        elif name == "theta":
            dxz_t = self._theta_dists(arr)
            beta = prm["betaU"]
            for j, c in enumerate(self.comps):
                changed[j] = (c.ri, c.si, c.alpha, c.llw, c.L, c.coef)
                cross[j] = (self._cross_z(beta[:, j], dxz_t), c.cxo)
        elif name in ("betaV", "lamVz"):
            sig_v = self._sig_v(prm)
        if has_obs:
            for j, fac in changed.items():
                cj = cross.get(j) or (self.comps[j].cxz, self.comps[j].cxo)
                changed[j] = fac + self._obs_part(fac, j, prm, *cj)
            terms = self._obs_terms()
            for j, out in changed.items():
                terms[j] = (out[7], out[8]) if out[4] is not None else (None, None)
            ll_vu = self._vu(terms, sig_v, prm)
        else:
            ll_vu = 0.0
        llw = [changed[j][3] if j in changed else c.llw for j, c in enumerate(self.comps)]
        ll = float(sum(llw)) + ll_vu
        self._pending = (prm, changed, sig_v, ll_vu, ll, dxz_t)
        return ll

    def propose_theta(self, theta: np.ndarray) -> float:
        """Log-likelihood with the whole theta (q,) at ``theta`` (pending accept): ``propose``'s
        theta case for several elements at once (a joint fit or calibration, with observations)."""
        prm = {**self.params, "theta": np.array(theta, dtype=np.float64)}
        dxz_t = self._theta_dists(prm["theta"])
        beta = prm["betaU"]
        changed: dict[int, tuple] = {}
        for j, c in enumerate(self.comps):
            fac = (c.ri, c.si, c.alpha, c.llw, c.L, c.coef)
            changed[j] = fac + self._obs_part(fac, j, prm, self._cross_z(beta[:, j], dxz_t), c.cxo)
        terms = [(out[7], out[8]) if out[4] is not None else (None, None)
                 for out in changed.values()]  # fmt: skip
        ll_vu = self._vu(terms, self.sig_v, prm)
        ll = float(sum([c.llw for c in self.comps])) + ll_vu
        self._pending = (prm, changed, self.sig_v, ll_vu, ll, dxz_t)
        return ll

    def accept(self) -> None:
        """Commit the last proposal."""
        prm, changed, sig_v, ll_vu, ll, dxz_t = self._pending
        for j, out in changed.items():
            self._commit(self.comps[j], out)
        self.params, self.sig_v, self.ll_vu, self.loglik, self.Dxz_t = prm, sig_v, ll_vu, ll, dxz_t
        self._pending = None
