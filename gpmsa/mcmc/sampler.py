"""Posterior draws (``Chains``) and the numpy Metropolis-within-Gibbs sampler in GPM/SA's order.

Each sweep updates every scalar element of the sampled parameters once, in the order theta,
betaV, betaU, lamVz, lamUz, lamWs, lamWOs, lamOs (betaU element order: input index fastest, as
GPM/SA's column-major loop). Proposals: uniform random walk (theta; beta on the rho = exp(-beta/4)
scale; precisions). Untuned precisions use GPM/SA's proportional step (width max(1, x/3)) with its
Hastings correction (``sample``'s ``proportional_steps`` chooses; a continuation of a tuned fit
steps them uniformly with its tuned widths, as SEPIA). A proposal outside the prior bounds is
rejected without a likelihood call.
Where it applies (one basis component, no observations) each sweep ends with moves along the
lamWs/lamWOs nugget ridge (``gpmsa.mcmc.ridge``; not in GPM/SA, ``ridge_moves=0`` turns them off).
Several chains run as parallel tasks (``gpmsa.mcmc.parallel``), each on its own seed. With
``temperatures`` (opt-in) each chain runs a ladder of tempered copies that swap states
(``gpmsa.mcmc.tempering``), keeping the T = 1 copy's draws.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import ChainError, GPMSAError
from gpmsa.limits import check_memory
from gpmsa.mcmc import level_moves, ridge, starts, tempering, tuning
from gpmsa.mcmc.acceptance import log_uniform
from gpmsa.mcmc.parallel import run_chains
from gpmsa.model.data import as_float, check_count, check_flag, check_seed
from gpmsa.model.kronecker import KroneckerLikelihood
from gpmsa.model.likelihood import IncrementalLikelihood, log_prior
from gpmsa.model.nugget import failing_component, not_positive_definite
from gpmsa.model.problem import Problem

DEFAULT_WIDTHS = {"theta": 0.2, "betaU": 0.1, "betaV": 0.1, "lamVz": 10.0, "lamUz": 5.0,
                  "lamWs": 100.0, "lamWOs": 100.0}  # fmt: skip
"""GPM/SA's initial step widths; lamOs starts at half its initial value."""

RHO_PARAMS = ("betaU", "betaV")
PRECISION_PARAMS = ("lamVz", "lamUz", "lamWs", "lamWOs", "lamOs")


@dataclass(eq=False)
class Chains:
    """Posterior draws of several chains.

    draws: name -> (n_chains, n_draws, *shape); log_post (n_chains, n_draws); accept_rate:
    name -> (n_chains, *shape) fraction of accepted proposals after tuning; step_widths:
    name -> (n_chains, *shape) the widths used (tuned, or given); info: free-form settings.
    """

    draws: dict[str, np.ndarray]
    log_post: np.ndarray
    accept_rate: dict[str, np.ndarray]
    step_widths: dict[str, np.ndarray]
    info: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        """GPMSAError naming the array whose shape disagrees with the chains' (n_chains,
        n_draws), the shape of ``log_post``: arrays of different shapes would be padded with NaN
        by ArviZ or broadcast wrongly."""
        self.log_post = np.asarray(self.log_post, dtype=float)
        if self.log_post.ndim != 2:
            raise GPMSAError(
                f"Chains: log_post must be (n_chains, n_draws), got shape {self.log_post.shape}"
            )
        for what in ("draws", "accept_rate", "step_widths"):
            if not isinstance(getattr(self, what), dict):
                raise GPMSAError(
                    f"Chains: {what} must be a dict name -> array, got "
                    f"{type(getattr(self, what)).__name__}"
                )
        if not self.draws:
            raise GPMSAError("Chains: draws is empty")
        lead = self.log_post.shape
        for name, arr in self.draws.items():
            if np.shape(arr)[:2] != lead:
                raise GPMSAError(
                    f"Chains: draws[{name!r}] has shape {np.shape(arr)}; its first two "
                    f"axes must be log_post's (n_chains, n_draws) = {lead}"
                )
        for what in ("accept_rate", "step_widths"):
            for name, arr in getattr(self, what).items():
                if np.shape(arr)[:1] != lead[:1]:
                    raise GPMSAError(
                        f"Chains: {what}[{name!r}] has shape {np.shape(arr)}; its "
                        f"first axis must be the {lead[0]} chains"
                    )

    @property
    def n_chains(self) -> int:
        """Number of chains."""
        return self.log_post.shape[0]

    @property
    def n_draws(self) -> int:
        """Draws per chain."""
        return self.log_post.shape[1]

    def to_arviz(self):
        """ArviZ ``InferenceData`` of the draws (arviz imported lazily)."""
        from gpmsa.mcmc.diagnostics import to_inference_data

        return to_inference_data(self.draws, self.log_post)

    def check_finite(self) -> None:
        """Raise ChainError naming every chain whose draws or log posterior are not finite."""
        require_finite(self.draws, self.log_post)

    def __repr__(self) -> str:
        names, shown = list(self.draws), 6
        more = f", +{len(names) - shown} more" if len(names) > shown else ""
        return (f"Chains({self.n_chains} chains x {self.n_draws} draws, "
                f"params={names[:shown]}{more})")  # fmt: skip


def require_finite(draws: dict[str, np.ndarray], log_post: np.ndarray | None = None) -> None:
    """Raise ChainError naming every chain (and its first bad draw) with a NaN or inf in
    ``draws`` (name -> (n_chains, n_draws, ...)) or ``log_post`` (n_chains, n_draws)."""
    arrays = list(draws.values()) + ([] if log_post is None else [log_post])
    n_chains = arrays[0].shape[0]
    bad = {}
    for c in range(n_chains):
        ok = np.ones(arrays[0].shape[1], dtype=bool)
        for v in arrays:
            ok &= np.isfinite(v[c].reshape(v.shape[1], -1)).all(axis=1)
        if not ok.all():
            bad[c] = int(np.argmin(ok))
    if bad:
        where = ", ".join(f"chain {c} (from draw {i})" for c, i in bad.items())
        raise ChainError(
            f"{len(bad)} of {n_chains} chains produced non-finite values (NaN or inf) in their "
            f"draws or log posterior: {where}", tuple(bad),
        )  # fmt: skip


def default_widths(problem: Problem) -> dict[str, np.ndarray]:
    """GPM/SA's default step widths, one per element."""
    out = {}
    for name in problem.names:
        shape = problem.init[name].shape
        if name == "lamOs":
            out[name] = np.full(shape, problem.init["lamOs"][0] / 2.0)
        else:
            out[name] = np.full(shape, DEFAULT_WIDTHS[name])
    return out


def elements(problem: Problem) -> list[tuple[str, tuple[int, ...]]]:
    """(name, index) of every sampled scalar element, in sweep order (held elements,
    ``problem.fixed_elements``, left out)."""
    out = []
    for name in problem.sampled:
        shape = problem.init[name].shape
        if len(shape) == 2:  # column-major, as GPM/SA
            idx = [(k, j) for j in range(shape[1]) for k in range(shape[0])]
        else:
            idx = [(k,) for k in range(shape[0])]
        held = problem.fixed_elements.get(name, frozenset())
        out += [(name, i) for i in idx if i not in held]
    return out


def _uniform_over_levels(x: float) -> float:
    """The log prior of a categorical theta element at a level (its sweep proposes levels)."""
    return 0.0


class ChainState:
    """One chain: current parameters, incremental likelihood, and the sweep.

    ``els`` restricts the sweep to some (name, index) elements (default: every sampled one).
    ``ridge_moves``: moves along the nugget ridge after each sweep (``gpmsa.mcmc.ridge``; only
    where the move applies, else none). ``beta``: the power 1/T of the likelihood in the
    acceptance (a tempered copy, ``gpmsa.mcmc.tempering``; the prior is not tempered); 1.0
    gives the plain sweep bit for bit (x * 1.0 == x).
    """

    beta = 1.0

    def __init__(
        self,
        problem: Problem,
        params: dict[str, np.ndarray],
        rng: np.random.Generator,
        els: list[tuple[str, tuple[int, ...]]] | None = None,
        ridge_moves: int = 0,
    ):
        self.problem = problem
        self.rng = rng
        self.ridge_moves = int(ridge_moves) if ridge.applies(problem) else 0
        self.ridge_accepted = 0
        pri = problem.priors
        self._ridge_priors = (pri.scalar_log_prior("lamWs"), pri.scalar_log_prior("lamWOs"))
        kron = problem.separable is not None  # a separable design: through its factors
        self.lik = (KroneckerLikelihood if kron else IncrementalLikelihood)(problem, params)
        self.els = elements(problem) if els is None else list(els)
        self.kinds = [
            1 if n in RHO_PARAMS else 2 if n in PRECISION_PARAMS else 0 for n, _ in self.els
        ]
        self.el_prior = [pri.scalar_log_prior(n, idx[-1]) for n, idx in self.els]
        levels = problem.theta_levels or []
        self.levels: list[np.ndarray | None] = [None] * len(self.els)
        for i, (n, idx) in enumerate(self.els):  # a categorical theta: a move to another level
            if n == "theta" and levels and levels[idx[0]] is not None:
                self.kinds[i], self.levels[i] = 3, levels[idx[0]]
                self.el_prior[i] = _uniform_over_levels
        self.log_prior = log_prior(problem, self.lik.params)
        self.constraint = problem.constraint if "theta" in problem.sampled else None
        if self.constraint is not None:
            self.constraint.check_start(self.lik.params["theta"], "the chain's start")
        self.level_shifts: dict[int, tuple] = {}  # `learn_level_shifts`: element -> its shifts
        self.level_offsets: dict[int, np.ndarray] = {}  # theta position -> its level_offsets

    def learn_level_shifts(self) -> None:
        """Each categorical theta element's joint level move (``gpmsa.mcmc.level_moves``): the
        shifts of the continuous sampled theta elements between the conditional modes at its
        levels, the other parameters at their current values; none without a categorical and a
        continuous sampled theta element (the sweep's moves stay those of GPM/SA's order)."""
        pos = {idx[0]: i for i, (n, idx) in enumerate(self.els) if n == "theta"}
        cat = [i for i in pos.values() if self.kinds[i] == 3 and self.levels[i].size > 1]
        cont = [k for k, i in pos.items() if self.kinds[i] == 0]
        if not cat or not cont:
            return
        priors = [self.el_prior[pos[k]] for k in cont]
        lik, con = self.lik, self.constraint

        def log_post(theta: np.ndarray) -> float:
            lp = sum(f(float(theta[k])) for f, k in zip(priors, cont, strict=True))
            if lp == -math.inf or (con is not None and not con(theta)):
                return -math.inf
            return lik.propose_theta(theta) + lp  # never accepted: the state is unchanged

        theta = lik.params["theta"]
        for i in cat:
            lv = self.levels[i]
            off = level_moves.level_offsets(log_post, theta, self.els[i][1][0], lv, cont)
            rows = {float(v): r for r, v in enumerate(lv)}
            self.level_shifts[i] = (rows, level_moves.shift_table(off), cont, priors)
            self.level_offsets[self.els[i][1][0]] = off

    def level_record(self) -> tuple[dict[int, np.ndarray], list[int]]:
        """The offsets of the level moves (`learn_level_shifts`; theta position -> (n_levels,
        n_shifted)) and the shifted elements' positions: the chain's record of the move."""
        cont = next(iter(self.level_shifts.values()))[2] if self.level_shifts else []
        return dict(self.level_offsets), list(cont)

    def _level_move(self, i: int, x: float, level: float, u1: float, accepted) -> None:
        """Element ``i`` (categorical theta, at level ``x``) to ``level`` with the continuous
        elements shifted (`learn_level_shifts`); Metropolis on the posterior ratio."""
        rows, table, cont, priors = self.level_shifts[i]
        lik = self.lik
        theta = lik.params["theta"].copy()
        theta[self.els[i][1][0]] = level
        d_lp = level_moves.shift(theta, cont, table[rows[x]][rows[level]],
                                 lambda k, v: priors[k](v))  # fmt: skip
        if d_lp == -math.inf:
            return
        if self.constraint is not None and not self.constraint(theta):
            return
        ll_old = lik.loglik
        ll_new = lik.propose_theta(theta)
        if ll_new == -math.inf:
            return
        if log_uniform(u1) < (ll_new - ll_old) * self.beta + d_lp:
            lik.accept()
            self.log_prior += d_lp
            accepted[i] += 1

    def use_level_shifts(self, source: ChainState) -> None:
        """``source``'s level shifts (`learn_level_shifts`; a tempered copy takes the T = 1
        copy's: any shifts keep the move exact)."""
        self.level_shifts = source.level_shifts

    @property
    def params(self) -> dict[str, np.ndarray]:
        """Current parameter values."""
        return self.lik.params

    @property
    def loglik(self) -> float:
        """Current log-likelihood (untempered)."""
        return self.lik.loglik

    def exchange(self, other: ChainState) -> None:
        """Swap states with ``other`` (a tempered copy: ``gpmsa.mcmc.tempering.swap``): the
        likelihood states, the parameters with them, and the running log priors."""
        self.lik, other.lik = other.lik, self.lik
        self.log_prior, other.log_prior = other.log_prior, self.log_prior

    def log_post(self) -> float:
        """Current log posterior (likelihood + priors of the sampled parameters)."""
        return self.lik.loglik + self.log_prior

    def check_start(self) -> None:
        """GPMSAError where the state (a chain's start) gives a log posterior of NaN, or where
        a component's Sigma_W is not positive definite there (`nugget.not_positive_definite`:
        a nugget too small for float64, as the torch backend refuses such a start). A start at
        log-likelihood -inf for another reason (a mean basis whose GLS term does not factor
        there, the observations' covariance) runs on: its first accepted proposal leaves it."""
        if math.isnan(self.log_post()):
            raise GPMSAError(
                f"the starting values give a log posterior of NaN (log-likelihood "
                f"{self.lik.loglik}); check the data and the starting values"
            )
        if self.lik.loglik == -math.inf:
            comps = getattr(self.lik, "comps", ())
            bad = [j for j, c in enumerate(comps) if not getattr(c, "ok", True)]
            prm, problem = self.lik.params, self.problem
            j = None if not bad else failing_component(
                problem.zt, prm, problem.lam_sim, problem.categorical, bad
            )  # fmt: skip
            if j is not None:
                raise GPMSAError(not_positive_definite(
                    j, prm, problem.lam_sim, problem.m, "at the chain's start"
                ))  # fmt: skip

    def flat_widths(self, widths: dict[str, np.ndarray]) -> np.ndarray:
        """Step widths name -> array as one (len(els),) array in the sweep's element order."""
        return np.array([float(widths[n][idx]) for n, idx in self.els])

    def element_records(self, accepted: np.ndarray, widths: np.ndarray, n_iter: int):
        """(acceptance rate, step width) name -> array from the sweep's per-element
        ``accepted`` counts over ``n_iter`` sweeps and ``widths``; NaN where not sampled."""
        names, shapes = self.problem.names, self.problem.init
        rate = {n: np.full(shapes[n].shape, np.nan) for n in names}
        wid = {n: np.full(shapes[n].shape, np.nan) for n in names}
        for i, (n, idx) in enumerate(self.els):
            rate[n][idx] = accepted[i] / max(n_iter, 1)
            wid[n][idx] = widths[i]
        return rate, wid

    def sweep(self, widths: np.ndarray, prop_mh: bool, accepted: np.ndarray) -> None:
        """One Metropolis-within-Gibbs sweep; adds 1 to ``accepted[i]`` per accepted element."""
        lik, beta = self.lik, self.beta
        u = self.rng.random((len(self.els), 2))
        for i, (name, idx) in enumerate(self.els):
            kind = self.kinds[i]
            x = float(lik.params[name][idx])
            corr = 0.0
            step = u[i, 0] - 0.5
            if kind == 1:
                r = math.exp(-0.25 * x) + widths[i] * step
                if r <= 0.0:
                    continue
                cand = -4.0 * math.log(r)
            elif kind == 3:  # another level, uniformly (symmetric; the prior is uniform)
                others = self.levels[i][self.levels[i] != x]
                if others.size == 0:
                    continue
                cand = float(others[int(u[i, 0] * others.size)])
                if i in self.level_shifts:  # with the continuous theta (level_moves)
                    self._level_move(i, x, cand, u[i, 1], accepted)
                    continue
            elif kind == 2 and prop_mh:
                w0 = max(1.0, x / 3.0)
                cand = x + w0 * 2.0 * step
                w1 = max(1.0, cand / 3.0)
                if x > cand + w1:
                    continue
                corr = math.log(w0 / w1)
            else:
                cand = x + widths[i] * step
            prior = self.el_prior[i]
            lp_new = prior(cand)
            if lp_new == -math.inf:
                continue
            if name == "theta" and self.constraint is not None:
                theta = lik.params["theta"].copy()
                theta[idx] = cand
                if not self.constraint(theta):  # zero prior mass outside the constraint
                    continue
            ll_old = lik.loglik
            ll_new = lik.propose(name, idx, cand)
            if ll_new == -math.inf:
                continue
            lp_old = prior(x)
            if log_uniform(u[i, 1]) < (ll_new - ll_old) * beta + lp_new - lp_old + corr:
                lik.accept()
                self.log_prior += lp_new - lp_old
                accepted[i] += 1
        if self.ridge_moves:
            self.ridge_sweep(self.rng.random((self.ridge_moves, 2)))

    def ridge_sweep(self, u: np.ndarray) -> None:
        """Moves along the nugget ridge (likelihood unchanged), one per row of uniforms u (k, 2)."""
        lik = self.lik
        g_s, g_t = self._ridge_priors
        lam_sim = float(self.problem.lam_sim[0])
        for u0, u1 in u:
            s, t = float(lik.params["lamWs"][0]), float(lik.params["lamWOs"][0])
            prop = ridge.proposal(s, t, lam_sim, u0)
            if prop is None:
                continue
            s2, t2 = prop
            lp_new = g_s(s2) + g_t(t2)
            if lp_new == -math.inf:
                continue
            lp_old = g_s(s) + g_t(t)
            if log_uniform(u1) < lp_new - lp_old + ridge.log_jacobian_ratio(s, t, s2, t2):
                lik.params = {**lik.params, "lamWs": np.array([s2]), "lamWOs": np.array([t2])}
                self.log_prior += lp_new - lp_old
                self.ridge_accepted += 1


def check_sample_args(n_iter, n_chains, seed) -> None:
    """The checks every backend's ``sample`` makes on its run arguments (GPMSAError naming it;
    a bool is not a count)."""
    check_count(n_iter, "n_iter")
    check_count(n_chains, "n_chains")
    check_seed(seed)


def parameter_elements(problem: Problem) -> int:
    """Parameter elements a sweep stores (every parameter of ``problem.init``, fixed ones too)."""
    return sum(int(np.size(v)) for v in problem.init.values())


def sweeps_nbytes(elements: int, n_iter: int, n_chains: int) -> float:
    """Bytes of the stored sweeps of every chain, each holding ``elements`` parameter elements
    and the log posterior, kept twice while the chains are stacked."""
    return 16.0 * n_chains * n_iter * (elements + 1)


def draws_nbytes(problem: Problem, n_iter: int, n_chains: int) -> float:
    """`sweeps_nbytes` of ``problem``'s parameter elements."""
    return sweeps_nbytes(parameter_elements(problem), n_iter, n_chains)


def check_draws_memory(problem: Problem, n_iter: int, n_chains: int) -> None:
    """ResourceLimitError (before any chain runs) when `draws_nbytes` exceeds
    ``gpmsa.limits.MAX_MEMORY_BYTES``."""
    check_memory(draws_nbytes(problem, n_iter, n_chains),
                 f"sample(n_iter={n_iter}, n_chains={n_chains}) of "
                 f"{parameter_elements(problem)} parameter elements")  # fmt: skip


def proportional_step_choice(proportional_steps, tune: bool) -> bool:
    """Whether the precisions take GPM/SA's proportional step: ``proportional_steps`` (True or
    False), or None: ``not tune`` (GPM/SA's and SEPIA's rule). GPMSAError naming another value."""
    if proportional_steps is None:
        return not tune
    if not isinstance(proportional_steps, (bool, np.bool_)):
        raise GPMSAError(
            f"proportional_steps must be None (not tune), True or False, got {proportional_steps!r}"
        )
    return bool(proportional_steps)


def check_ridge(ridge_moves, problem: Problem) -> int:
    """Moves along the nugget ridge per sweep: ``ridge_moves`` (None: the default where the move
    applies), 0 where it does not apply; GPMSAError for a value that is not an integer in
    [0, ``ridge.MAX_MOVES``], or for one above 0 given where the move does not apply (it would
    have no effect)."""
    given = ridge_moves is not None
    if ridge_moves is None:
        ridge_moves = ridge.N_MOVES
    n = check_count(ridge_moves, "ridge_moves", 0, ridge.MAX_MOVES)
    if ridge.applies(problem):
        return n
    if given and n > 0:
        why = ("the model has observations (a joint fit or a calibration)"
               if problem.obs is not None else
               f"the basis has {problem.p_u} components" if problem.p_u != 1 else
               "lamWs or lamWOs is held (fixed=)")  # fmt: skip
        raise GPMSAError(
            f"ridge_moves={n}: the nugget-ridge move runs only where the likelihood depends on "
            "lamWs and lamWOs through their nugget alone (a simulation-only fit with one basis "
            f"component, both sampled), and here {why}, so it would have no effect: leave "
            "ridge_moves out (or 0)"
        )
    return 0


def check_step_widths(
    step_widths, problem: Problem, n_chains: int = 1
) -> list[dict[str, np.ndarray]]:
    """Each chain's step widths: GPM/SA's initial ones with ``step_widths`` (None, or a dict
    name -> a scalar, the parameter's shape, or (n_chains, *shape): one set per chain, as
    ``Emulator.settings["step_widths"]`` records them) in place. Elements that are not sampled
    (fixed parameters, held elements) may hold anything, NaN or None as the record writes them,
    and keep the defaults. GPMSAError naming an unknown parameter, a wrong shape or a sampled
    element's width that is not finite and > 0 (a chain would never move)."""
    widths = default_widths(problem)
    per_chain = [{k: v.copy() for k, v in widths.items()} for _ in range(n_chains)]
    if step_widths is None:
        return per_chain
    if not isinstance(step_widths, dict):
        raise GPMSAError(
            f"step_widths must be None or a dict name -> widths, got {type(step_widths).__name__}"
        )
    sampled: dict[str, list] = {}
    for name, idx in elements(problem):
        sampled.setdefault(name, []).append(idx)
    for name, val in step_widths.items():
        if name not in widths:
            raise GPMSAError(f"step_widths: unknown parameter {name!r}; this model has "
                             f"{problem.names}")  # fmt: skip
        shape = widths[name].shape
        arr = as_float(none_as_nan(val), f"step_widths[{name!r}]")
        if arr.size == 0 == widths[name].size:  # betaV (0, G) when p = 0: nothing to set (its
            continue  # record holds [] per chain: JSON keeps no empty shape)
        if arr.size == 1:
            arr = np.full((n_chains, *shape), arr.item())
        elif arr.shape == shape:
            arr = np.broadcast_to(arr, (n_chains, *shape))
        elif arr.shape != (n_chains, *shape):
            raise GPMSAError(
                f"step_widths[{name!r}] must be a scalar or have shape {shape} (or "
                f"{(n_chains, *shape)}, one per chain), got {arr.shape}"
            )
        used = [arr[(slice(None), *idx)] for idx in sampled.get(name, [])]
        if used and not np.all(np.isfinite(used) & (np.asarray(used) > 0)):
            raise GPMSAError(
                f"step_widths[{name!r}] must be finite and > 0, got {np.ravel(used).tolist()}"
            )
        for c in range(n_chains):
            for idx in sampled.get(name, []):
                per_chain[c][name][idx] = arr[(c, *idx)]
    return per_chain


def none_as_nan(value):
    """``value`` with None (JSON's NaN, in a file's recorded widths) as NaN, in nested lists."""
    if value is None:
        return float("nan")
    if isinstance(value, list | tuple):
        return [none_as_nan(v) for v in value]
    return value


def run_chain(
    problem: Problem,
    n_iter: int,
    *,
    tune: bool,
    widths: dict[str, np.ndarray],
    rng: np.random.Generator,
    tune_rounds: int = tuning.N_BURN,
    tune_levels: int = tuning.N_LEVELS,
    progress: bool = False,
    desc: str = "MCMC",
    start: dict[str, np.ndarray] | None = None,
    ridge_moves: int = 0,
    proportional_steps: bool | None = None,
    record: dict | None = None,
) -> tuple[dict[str, np.ndarray], np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Tune (optionally), then ``n_iter`` sweeps from ``start`` (default ``problem.init``), the
    precisions by GPM/SA's proportional step where ``proportional_steps`` (None: ``not tune``).

    Returns draws, log_post, accept rates, widths; ``record`` (a dict) gets "level" (the level
    moves' offsets and shifted elements, ``ChainState.level_record``). GPMSAError when the
    start's log posterior is NaN (no proposal could ever be accepted).
    """
    state = ChainState(problem, problem.init if start is None else start, rng,
                       ridge_moves=ridge_moves)  # fmt: skip
    state.check_start()
    els = state.els
    w = state.flat_widths(widths)
    total = n_iter + (tune_rounds * tune_levels if tune else 0)
    with progress_bar(progress, total, desc, unit="it") as bar, one_thread(None):
        if tune and els:
            bar.set_description(f"{desc}: tuning step widths")  # the bar counts both phases
            names = [n for n, _ in els]
            state.learn_level_shifts()  # the widths tuned with the level moves (categorical)
            w = tuning.tune_widths(state.sweep, names, w, tune_rounds, tune_levels, bar.update)
        state.learn_level_shifts()  # found anew, frozen before the draws (a categorical theta)
        bar.set_description(f"{desc}: sampling")
        draws = {n: np.empty((n_iter, *problem.init[n].shape)) for n in problem.names}
        log_post = np.empty(n_iter)
        accepted = np.zeros(len(els))
        prop_mh = (not tune) if proportional_steps is None else proportional_steps
        names = problem.names
        for it in range(n_iter):
            state.sweep(w, prop_mh, accepted)
            prm = state.params
            for n in names:
                draws[n][it] = prm[n]
            log_post[it] = state.log_post()
            if it % 100 == 99:
                bar.update(100)
        bar.update(n_iter % 100)
    if record is not None:
        record["level"] = state.level_record()
    return draws, log_post, *state.element_records(accepted, w, n_iter)


def _chain_task(
    problem: Problem, n_iter: int, tune: bool, widths: dict[str, np.ndarray],
    seed: np.random.SeedSequence, start: dict[str, np.ndarray], tune_rounds: int,
    tune_levels: int, ridge_moves: int = 0, progress: bool = False, desc: str = "MCMC",
    proportional_steps: bool | None = None, temperatures: tuple[float, ...] | None = None,
    swap_every: int = 1, adapt_ladder: bool = False, copies: list | None = None,
):  # fmt: skip
    """One chain from plain data (run in a worker process): ``run_chain`` from ``start`` (drawn
    by ``sample`` in the parent), its generator from ``seed``; ``run_chain``'s result (with
    ``temperatures``: ``tempering.run_tempered_chain``'s, its hot copies resumed from
    ``copies``, the swap rates after it, and the adapted ladder after them with
    ``adapt_ladder``), then a dict of the level moves' offsets (``ChainState.level_record``:
    "offsets", "shifted") and, tempered, "hot": the hot copies' last states and widths."""
    record: dict = {}
    with one_thread(None):
        if temperatures is not None:
            rng = np.random.default_rng(seed)
            first = problem.init if start is None else start

            def new_state(at: dict | None) -> ChainState:
                return ChainState(problem, first if at is None else at, rng,
                                  ridge_moves=ridge_moves)  # fmt: skip

            out = tempering.run_tempered_chain(
                problem, n_iter, new_state,
                temperatures=temperatures, swap_every=swap_every, tune=tune, widths=widths,
                rng=rng, tune_rounds=tune_rounds, tune_levels=tune_levels, progress=progress,
                desc=desc, proportional_steps=proportional_steps, record=record,
                adapt_ladder=adapt_ladder, copies=copies,
            )  # fmt: skip
        else:
            out = run_chain(
                problem, n_iter, tune=tune, widths=widths, rng=np.random.default_rng(seed),
                tune_rounds=tune_rounds, tune_levels=tune_levels, progress=progress, desc=desc,
                start=start, ridge_moves=ridge_moves, proportional_steps=proportional_steps,
                record=record,
            )  # fmt: skip
    offsets, shifted = record["level"]
    return (*out, {"offsets": offsets, "shifted": shifted,
                   **({"hot": record["hot"]} if "hot" in record else {})})  # fmt: skip


def check_hot_copies(hot_copies, problem: Problem, ladders, n_chains: int) -> list | None:
    """``sample``'s ``hot_copies``: None, or {"starts": ..., "widths": ...}, each name ->
    (n_chains, K - 1, *shape) (as ``info`` "hot_states" and "hot_step_widths" record them), at
    ``ladders`` (each chain's, K rungs). Returns per chain the K - 1 hot copies' (start,
    widths), checked as a chain's ``init`` and ``step_widths`` are (``starts.chain_starts``,
    `check_step_widths`: inside the priors' support, finite widths > 0); GPMSAError naming
    ``hot_copies`` and the problem otherwise."""
    if hot_copies is None:
        return None
    if ladders is None:
        raise GPMSAError("hot_copies needs temperatures= (the copies of a tempered chain)")
    if not isinstance(hot_copies, dict) or set(hot_copies) != {"starts", "widths"}:
        raise GPMSAError(
            "hot_copies must be a dict with 'starts' and 'widths' (name -> (n_chains, K - 1, "
            f"*shape)), got {hot_copies!r:.80}"
        )
    n_hot = len(ladders[0]) - 1
    flat = {}
    for part in ("starts", "widths"):
        given = hot_copies[part]
        if not isinstance(given, dict):
            raise GPMSAError(f"hot_copies[{part!r}] must be a dict name -> (n_chains, K - 1, "
                             f"*shape), got {type(given).__name__}")  # fmt: skip
        flat[part] = {}
        for name, val in given.items():
            arr = as_float(none_as_nan(val), f"hot_copies[{part!r}][{name!r}]", advice=False)
            shape = problem.init[name].shape if name in problem.init else None
            if shape is not None and 0 in shape and arr.size == 0:  # JSON keeps no empty shape
                arr = np.zeros((n_chains, n_hot, *shape))
            if shape is not None and arr.shape != (n_chains, n_hot, *shape):
                raise GPMSAError(
                    f"hot_copies[{part!r}][{name!r}] must have shape {(n_chains, n_hot, *shape)}"
                    f" (chains, hot copies, *shape), got {arr.shape}"
                )
            flat[part][name] = arr if shape is None else arr.reshape(n_chains * n_hot, *shape)
    n_copies = n_chains * n_hot
    try:
        _, firsts = starts.chain_starts(problem, flat["starts"], [None] * n_copies)
        widths = check_step_widths(flat["widths"], problem, n_copies)
    except GPMSAError as exc:
        raise GPMSAError(f"hot_copies (its chain c below: chain c // {n_hot}'s hot copy "
                         f"1 + c % {n_hot}): {exc}") from None  # fmt: skip
    pairs = list(zip(firsts, widths, strict=True))
    return [pairs[c * n_hot : (c + 1) * n_hot] for c in range(n_chains)]


def wrong_result(result, expected: tuple, what: str) -> str | None:
    """``run_chains``' check of a chain task's ``result``: None when it is a tuple of one item
    per ``expected`` entry, a shape tuple (an array of that shape) or a dict name -> shape (a
    dict of such arrays) or ``dict`` (any dict); otherwise ``what``, the draws it should hold."""
    ok = isinstance(result, tuple) and len(result) == len(expected)
    for got, want in zip(result if ok else (), expected, strict=False):
        if want is dict:
            ok = ok and isinstance(got, dict)
        elif isinstance(want, dict):
            ok = ok and isinstance(got, dict) and set(got) == set(want)
            ok = ok and all(np.shape(got[k]) == shape for k, shape in want.items())
        else:
            ok = ok and isinstance(got, np.ndarray) and got.shape == want
    return None if ok else what


def sample(
    problem: Problem,
    *,
    n_iter: int,
    n_chains: int = 1,
    tune: bool = True,
    step_widths: dict[str, np.ndarray] | None = None,
    seed=None,
    progress: bool = False,
    tune_rounds: int = tuning.N_BURN,
    tune_levels: int = tuning.N_LEVELS,
    init: str | dict = "auto",
    n_jobs: int | None = None,
    executor=None,
    ridge_moves: int | None = None,
    proportional_steps: bool | None = None,
    temperatures=None,
    swap_every: int = 1,
    adapt_ladder: bool = False,
    hot_copies: dict | None = None,
) -> Chains:
    """Draw ``n_iter`` sweeps per chain after GPM/SA step-size tuning (``tune=True``).

    The numpy backend's ``sample``. ``tune_rounds`` x ``tune_levels`` tuning sweeps (default
    50 x 20 = 1,000) precede the draws of each chain; ``step_widths`` (name -> widths, or
    (n_chains, *shape) per chain: `check_step_widths`) replace GPM/SA's initial widths. Draws
    hold every sweep (no burn-in removed).

    Chains: chain c runs on ``SeedSequence(seed).spawn(n_chains)[c]``, so its draws do not
    depend on where it runs; they run in parallel processes (``gpmsa.mcmc.parallel``):
    ``n_jobs`` workers (None or -1: every CPU, never more than the chains) or any
    ``concurrent.futures.Executor`` / dask ``Client`` given as ``executor``. ``init``: the
    chains' starts (``gpmsa.mcmc.starts``: "auto" is GPM/SA's initial values for one chain,
    dispersed ones for several; a dict name -> (n_chains, *shape) gives them).
    ``ridge_moves``: moves along the lamWs/lamWOs nugget ridge per sweep (``gpmsa.mcmc.ridge``;
    None: ``ridge.N_MOVES`` where the move applies, a simulation-only problem with one basis
    component; 0: GPM/SA's sweep alone; a number above 0 where the move does not apply, a
    GPMSAError: `check_ridge`). ``proportional_steps``: the precisions (lamVz, lamUz,
    lamWs, lamWOs, lamOs) step by GPM/SA's proportional step, width max(1, x/3) whatever their
    step widths (True), or uniformly with their widths (False); None: ``not tune``, as GPM/SA
    and SEPIA (``info["proportional_steps"]`` records it). ``temperatures``: parallel
    tempering (``gpmsa.mcmc.tempering``; None: off, GPM/SA's sampler bit for bit): an integer
    n (the ladder 2**k, k = 0 .. n - 1) or a ladder from 1; each chain runs a copy per
    temperature (each tuned at its temperature), neighbours propose a swap every
    ``swap_every`` sweeps (at most ``n_iter``), and the T = 1 copy's draws are kept; ``info``
    records "temperatures" (a ladder per chain, (n_chains, K), where they differ), "swap_every"
    and "swap_rate" (n_chains, K - 1), each neighbour pair's swap acceptance over the draws;
    ``temperatures`` may also be an (n_chains, K) array, chain c at ladder c (a continuation of
    chains that adapted their ladders, `tempering.chain_ladders`). ``adapt_ladder`` (with
    ``temperatures``, at least 3, and ``tune``): each chain adapts its ladder's temperatures
    between 1 and the hottest during tuning towards equal swap rates, then freezes it before
    the tuning of the widths and the draws, which are therefore an exact MCMC
    (``tempering.adapt_ladder``); ``info`` records "adapt_ladder" and "adapted_temperatures"
    (n_chains, K) ("temperatures": the starting ladder). A tempered run's ``info`` records
    "hot_states" and "hot_step_widths" (name -> (n_chains, K - 1, *shape)): each hot copy's
    last state and its widths (NaN where not sampled); ``hot_copies`` ({"starts": ...,
    "widths": ...} of that form; `check_hot_copies`) starts each hot copy there, with those
    widths where ``tune`` is False (a continuation resuming every copy where it stopped; else
    every copy starts at its chain's start). Raises ChainError naming a chain that failed or
    whose draws are not finite.
    """
    check_sample_args(n_iter, n_chains, seed)
    tune, progress = check_flag(tune, "tune"), check_flag(progress, "progress")
    prop_mh = proportional_step_choice(proportional_steps, tune)
    ladders = tempering.chain_ladders(temperatures, int(n_chains))  # each chain's
    temps = None if ladders is None else ladders[0]
    swap_every = tempering.check_swap_every(swap_every, temps, int(n_iter))
    adapt = tempering.check_adapt(adapt_ladder, temps, tune)
    check_draws_memory(problem, int(n_iter), int(n_chains))
    tune_rounds, tune_levels = tuning.check_tuning(tune_rounds, tune_levels)
    seq = np.random.SeedSequence(seed)
    seeds = seq.spawn(int(n_chains))
    # every chain's start drawn here, not in a worker: a start outside a prior's support (or a
    # jitter range out of reach of its bounds) is a plain GPMSAError before any chain runs
    how, firsts = starts.chain_starts(problem, init, seeds)
    n_ridge = check_ridge(ridge_moves, problem)
    widths = check_step_widths(step_widths, problem, int(n_chains))
    copies = check_hot_copies(hot_copies, problem, ladders, int(n_chains))
    tasks = [
        {"problem": problem, "n_iter": int(n_iter), "tune": tune, "widths": w, "seed": s,
         "start": first, "tune_rounds": tune_rounds, "tune_levels": tune_levels,
         "ridge_moves": n_ridge, "proportional_steps": prop_mh,
         **({} if temps is None else {"temperatures": ladders[c], "swap_every": swap_every}),
         **({"adapt_ladder": True} if adapt else {}),
         **({} if copies is None else {"copies": copies[c]})}
        for c, (s, first, w) in enumerate(zip(seeds, firsts, widths, strict=True))
    ]  # fmt: skip
    names = problem.names
    shapes = {n: problem.init[n].shape for n in names}
    expected = ({n: (int(n_iter), *v) for n, v in shapes.items()}, (int(n_iter),), shapes,
                shapes)  # fmt: skip
    if temps is not None:  # and each neighbour pair's swap rate
        expected += ((len(temps) - 1,),) + (((len(temps),),) if adapt else ())
    expected += (dict,)  # the level moves' offsets (a categorical theta; else empty)
    runs = run_chains(_chain_task, tasks, n_jobs=n_jobs, executor=executor, progress=progress,
                      desc="chain",
                      check=lambda _, r: wrong_result(r, expected, f"{n_iter} sweeps"))  # fmt: skip
    chains = Chains(
        draws={n: np.stack([r[0][n] for r in runs]) for n in names},
        log_post=np.stack([r[1] for r in runs]),
        accept_rate={n: np.stack([r[2][n] for r in runs]) for n in names},
        step_widths={n: np.stack([r[3][n] for r in runs]) for n in names},
        info={"n_iter": n_iter, "n_chains": n_chains, "tune": tune, "tune_rounds": tune_rounds,
              "tune_levels": tune_levels, "seed": seed, "seed_entropy": str(seq.entropy),
              "init": how, "ridge_moves": n_ridge, "proportional_steps": prop_mh,
              "starts": {n: np.stack([first[n] for first in firsts]) for n in names},
              "backend": "numpy"},
    )  # fmt: skip
    if temps is not None:
        ran = list(temps) if ladders.count(temps) == len(ladders) else [list(t) for t in ladders]
        chains.info.update(temperatures=ran, swap_every=swap_every,
                           swap_rate=np.stack([r[4] for r in runs]))  # fmt: skip
        for key, part in (("hot_states", 0), ("hot_step_widths", 1)):  # (n_chains, K - 1, ...)
            chains.info[key] = {n: np.stack([np.stack([c[n] for c in r[-1]["hot"][part]])
                                             for r in runs]) for n in names}  # fmt: skip
    if adapt:  # each chain's ladder, adapted in its tuning and frozen for its draws
        chains.info.update(adapt_ladder=True, adapted_temperatures=np.stack([r[5] for r in runs]))
    moves = level_moves.chains_record([r[-1]["offsets"] for r in runs], runs[0][-1]["shifted"])
    if moves:  # a categorical theta's joint level move: its offsets, per chain
        chains.info["level_offsets"] = moves
    chains.check_finite()
    return chains
