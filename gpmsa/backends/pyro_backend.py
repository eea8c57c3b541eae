"""pyro backend: the GPM/SA posterior as a pyro model, sampled by NUTS.

The model is the torch backend's likelihood (``gpmsa.backends.torch_backend``) with GPM/SA's
priors: theta on (0, 1); betaU/betaV sampled as rho = exp(-beta/4) on (0, 1) with the Beta prior
density of rho (the same target as the Metropolis samplers, which walk on rho); precisions on
their prior bounds with Gamma densities. Bounds are pyro constraints (NUTS moves in the
unconstrained space); densities enter through ``pyro.factor``. Chains start where the numpy
backend's chain c would (``gpmsa.mcmc.starts``: GPM/SA's initial values for one chain, dispersed
ones for several); fixed parameters are constants. A parameter with held elements
(``problem.fixed_elements``) is one site of its free elements (flattened, C order; their own
bounds), scattered with the held values into the full array; the held elements' priors are left
out, as the numpy backend leaves them out.
Categorical inputs and a "constant" or "linear" mean basis (its coefficients integrated out, as
the numpy likelihood's) are sampled. A categorical theta (its prior uniform over its levels, as
the numpy sampler's) is marginalised out of the density NUTS samples: the log-sum-exp over the
combinations of the free categorical elements' levels of prior x likelihood
(`PyroModel.with_levels`; at most `MAX_LEVEL_COMBINATIONS`, each costs one likelihood); each
kept draw's levels are then drawn from their conditional given its continuous parameters
(exact), so the draws carry the levels as the other backends' do; with a continuous theta
beside it, the joint level move (`LevelJumps`, ``gpmsa.mcmc.level_moves``) after each draw
carries a chain between the modes of a level and a continuous parameter that trade off.
A theta constraint (``problem.constraint``, a numpy callable of native theta) enters the prior:
a theta it rejects (the full theta, held elements at their values; with a categorical theta,
each combination of levels with the continuous values) has log density -inf, a constant of the
detached verdict (no gradient; asked only where theta's prior allows it, as the numpy and
torch samplers ask it: never outside (0, 1)), so NUTS sees an infinite energy there: a
divergence, whose subtree gets zero weight and ends the trajectory's doubling (pyro's
``NUTS._build_basetree``; the chain stays exact, a hard wall as Stan's). The level draws and
moves take the same -inf (a move's candidate it rejects is refused without its likelihood). The
verdict is numpy, which a JIT trace would freeze at its first value, so with a constraint the
potential energy is not JIT-compiled (``jit`` is ignored). A callable mean basis with theta
sampled is refused (`refuse_unsupported`).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager

import numpy as np
import pyro
import pyro.distributions as dist
import torch
from pyro.distributions import constraints
from pyro.infer import MCMC, NUTS
from pyro.infer.autoguide import init_to_value
from pyro.infer.mcmc.mcmc_kernel import MCMCKernel

from gpmsa.backends import check_sample_args
from gpmsa.backends.torch_backend import (
    SIM_PARAMS,
    ModelTensors,
    gls,
    log_prior_elements,
    mean_rows,
    obs_loglik,
    sim_factor,
    torch_threads,
)
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import level_moves, parallel, starts
from gpmsa.mcmc.sampler import RHO_PARAMS, Chains, check_draws_memory
from gpmsa.model.data import as_real, check_count, check_flag
from gpmsa.model.problem import Problem

N_WARMUP = 500
"""Default NUTS warm-up (step size and mass-matrix adaptation) iterations per chain."""
MAX_LEVEL_COMBINATIONS = 64
"""Most combinations of a categorical theta's levels (the product over its free categorical
elements) the pyro backend marginalises: each costs one likelihood evaluation per gradient."""


def _support(
    problem: Problem, name: str, dtype: torch.dtype, free: np.ndarray | None = None
) -> constraints.Constraint:
    """Constraint of the sampled coordinate of ``name`` (rho for the correlation parameters);
    per-group lamVz priors of different bounds give per-element bounds, whose upper ones must be
    all finite or all infinite (GPMSAError otherwise). ``free``: the flat indices of the sampled
    elements of a parameter with held elements (None: every element)."""
    if name == "theta" or name in RHO_PARAMS:
        return constraints.interval(0.0, 1.0)
    _, _, lows, highs = problem.priors.gamma_arrays(name, int(np.size(problem.init[name])))
    if free is not None:
        lows, highs = lows[free], highs[free]
    if np.all(lows == lows[0]) and np.all(highs == highs[0]):  # one prior's bounds, as floats
        lower, upper = float(lows[0]), float(highs[0])
    else:
        lower, upper = torch.tensor(lows, dtype=dtype), torch.tensor(highs, dtype=dtype)
    finite = np.isfinite(highs)
    if finite.all():
        return constraints.interval(lower, upper)
    if not finite.any():
        return constraints.greater_than(lower)
    raise GPMSAError(
        f"backend='pyro' samples {name} on its per-group priors' bounds, whose upper bounds "
        f"{highs.tolist()} mix finite and infinite ones: give every group a finite "
        "upper bound, or none (or use backend='numpy' or 'torch')"
    )


def _site(name: str) -> str:
    return f"{name}_rho" if name in RHO_PARAMS else name


class PyroModel:
    """The GPM/SA posterior of ``problem`` as a pyro model (call it with no arguments)."""

    def __init__(self, problem: Problem, dtype: torch.dtype = torch.float64):
        """Each parameter is one NUTS sample site, or a constant when fixed whole (or empty);
        one with held elements (``problem.fixed_elements``) is a site of its free elements,
        ``self.held[name]`` = (free flat indices, scatter order, held values (model scale))."""
        self.problem = problem
        self.dtype = dtype
        self.data = ModelTensors.from_problem(problem, dtype, "cpu")
        self.const = {  # fixed, or empty (betaV with no known inputs, p = 0): no sample site
            k: torch.as_tensor(v, dtype=dtype).unsqueeze(0)
            for k, v in problem.init.items()
            if k in problem.fixed or np.size(v) == 0
        }
        self.free = tuple(k for k in problem.sampled if k not in self.const)
        self.constraint = problem.constraint if "theta" in self.free else None
        masks = problem.held_masks(self.free)
        self.cat, self.combos = _level_combinations(problem, masks, self.free, dtype)
        self.cat_levels = [problem.theta_levels[k] for k in self.cat]  # unit scale, each
        if self.cat.size:  # theta's site: its continuous free elements, the levels scattered in
            masks["theta"] = masks.get("theta", np.zeros(problem.q, dtype=bool))
            masks["theta"][self.cat] = True
        self.held = {k: _scatter(problem.init[k], mask, dtype) for k, mask in masks.items()}
        self.support = {
            name: _support(problem, name, dtype, self.held[name][0].numpy() if name in self.held
                           else None)
            for name in self.free
        }  # fmt: skip
        self.sim_cache = None
        if all(k in self.const for k in SIM_PARAMS):  # Sigma_W constant: factor it once
            d = self.data
            chol, alpha, ll = sim_factor(
                d.d_sim, d.w, d.lam_sim, *(self.const[k] for k in SIM_PARAMS)
            )
            coef = None
            if d.h_sim is not None:
                alpha, ll, coef = gls(chol, alpha, ll, d.h_sim)
            self.sim_cache = (chol, alpha, ll.sum(-1), coef)

    def init_values(self, start: dict[str, np.ndarray] | None = None) -> dict[str, torch.Tensor]:
        """A chain's starting values (name -> array; default GPM/SA's ``problem.init``) in the
        model's sample sites."""
        start = self.problem.init if start is None else start
        out = {}
        for name in self.sites:
            v = torch.as_tensor(start[name], dtype=self.dtype)
            if name in self.held:
                v = v.reshape(-1)[self.held[name][0]]
            out[_site(name)] = torch.exp(-0.25 * v) if name in RHO_PARAMS else v
        return out

    @property
    def sites(self) -> tuple[str, ...]:
        """The parameters NUTS samples (a theta of categorical and held elements only has no
        site: its levels are marginalised)."""
        return tuple(k for k in self.free if k not in self.held or self.held[k][0].numel())

    def params(self, sites: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """Model parameters (name -> (C, *shape)) from sample-site values (C, *shape)."""
        out = {}
        for name in self.problem.names:
            if name in self.const:
                continue
            if name not in self.sites:  # categorical and held elements only
                c = next(iter(sites.values())).shape[0]
                v = torch.zeros(c, 0, dtype=self.dtype)
            else:
                v = sites[_site(name)]
            v = -4.0 * torch.log(v) if name in RHO_PARAMS else v
            if name in self.held:  # free elements (C, n_free) and held values, in C order
                _, order, values = self.held[name]
                full = torch.cat([v, values.expand(v.shape[0], -1)], -1)[:, order]
                v = full.reshape(v.shape[0], *self.problem.init[name].shape)
            out[name] = v
        c = next(iter(out.values())).shape[0] if out else 1
        out.update({k: v.expand(c, *v.shape[1:]) for k, v in self.const.items()})
        return out

    def log_likelihood(self, prm: dict[str, torch.Tensor]) -> torch.Tensor:
        """GPM/SA log-likelihood (C,) at parameters name -> (C, *shape)."""
        d = self.data
        if self.sim_cache is not None:
            chol, alpha, ll_w, coef = self.sim_cache  # shared by all draws (leading axis 1)
        else:
            chol, alpha, ll = sim_factor(d.d_sim, d.w, d.lam_sim, *(prm[k] for k in SIM_PARAMS))
            coef = None
            if d.h_sim is not None:  # the mean basis's coefficients integrated out
                alpha, ll, coef = gls(chol, alpha, ll, d.h_sim)
            ll_w = ll.sum(-1)
        if d.has_obs:
            h_obs = None if coef is None else mean_rows(self.problem, d, prm["theta"])
            ll_w = ll_w + obs_loglik(d, chol, alpha, prm, coef, h_obs)
        return ll_w

    def with_levels(self, prm: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """``prm`` (name -> (C, *shape)) at every combination of the categorical theta's levels
        (``self.combos`` (K, n_cat)): name -> (C K, *shape), draw c's combination j at row
        c K + j."""
        k = self.combos.shape[0]
        out = {n: v.repeat_interleave(k, 0) for n, v in prm.items() if n != "theta"}
        theta = prm["theta"].unsqueeze(1).repeat(1, k, 1)
        theta[:, :, self.cat] = self.combos
        out["theta"] = theta.reshape(-1, theta.shape[-1])
        return out

    def log_post_at(self, prm: dict[str, torch.Tensor], combo: torch.Tensor) -> torch.Tensor:
        """GPM/SA log posterior (C,) of ``prm`` (name -> (C, *shape)) with the categorical
        theta at ``combo`` (n_cat,) (its levels' prior uniform, 0)."""
        theta = prm["theta"].clone()
        theta[:, self.cat] = combo
        each = {**prm, "theta": theta}
        return self.log_likelihood(each) + self.log_prior(each)

    def level_log_post(self, prm: dict[str, torch.Tensor]) -> torch.Tensor:
        """GPM/SA log posterior (C, K) of each draw of ``prm`` at each combination of the
        categorical theta's levels (`with_levels`; the levels' prior uniform, 0 as the numpy
        sampler's)."""
        each = self.with_levels(prm)
        lp = self.log_likelihood(each) + self.log_prior(each)
        return lp.reshape(-1, self.combos.shape[0])

    def log_prior(self, prm: dict[str, torch.Tensor]) -> torch.Tensor:
        """Sum of the sampled elements' log priors (C,) (held elements and a categorical theta,
        uniform over its levels, left out), -inf where the theta constraint rejects theta."""
        c = prm["betaU"].shape[0]
        lp = torch.zeros(c, dtype=self.dtype)
        for name in self.free:
            each = log_prior_elements(self.problem.priors, name, prm[name]).reshape(c, -1)
            if name in self.held:
                each = each[:, self.held[name][0]]
            lp = lp + each.sum(-1)
        if self.constraint is not None:  # asked only where the priors allow (numpy's order)
            lp = lp + self.constraint_term(prm["theta"], torch.isfinite(lp).numpy())
        return lp

    def constraint_term(self, theta: torch.Tensor, ask: np.ndarray) -> torch.Tensor:
        """0 where the theta constraint allows unit-scale theta (C, q), -inf where it rejects
        it: (C,), a constant (the verdict of the detached values, called once per row asked).
        ``ask`` (C,) bool: the rows to ask (the others 0: rows outside theta's prior, where the
        numpy and torch samplers never call the constraint, which may fail there)."""
        con, th = self.constraint, theta.detach().numpy()
        if ask.all():
            ok = con.allows(con.native(th))
        else:
            ok = np.ones(ask.size, dtype=bool)
            ok[ask] = con.allows(con.native(th[ask]))
        out = torch.zeros(theta.shape[0], dtype=self.dtype)
        return out.masked_fill_(torch.as_tensor(~ok), -torch.inf)

    def __call__(self) -> None:
        sites = {}
        for name in self.sites:
            shape = self.problem.init[name].shape
            if name in self.held:
                shape = self.held[name][0].shape
            base = dist.ImproperUniform(self.support[name], (), shape)
            sites[_site(name)] = pyro.sample(_site(name), base).unsqueeze(0)
        prm = self.params(sites)
        if self.cat.size:  # the levels marginalised: log sum over them of prior x likelihood
            lse = torch.logsumexp(self.level_log_post(prm)[0], 0)
            if self.constraint is not None and lse == -torch.inf:  # every level rejected: no
                lse = lse.detach()  # gradient (a NaN one through logsumexp), a divergence
            pyro.factor("log_post", lse)
            return
        pyro.factor("log_prior", self.log_prior(prm)[0])
        pyro.factor("log_likelihood", self.log_likelihood(prm)[0])

    def draw_levels(self, prm: dict[str, torch.Tensor], rng: np.random.Generator,
                    chunk: int = 256) -> tuple[dict[str, torch.Tensor], np.ndarray]:  # fmt: skip
        """(``prm`` with each draw's categorical theta at levels drawn from their conditional
        given its other parameters, the log posterior (n,) of each draw there); ``prm``: name
        -> (n, *shape), ``rng`` the draws' generator (Gumbel-max, one (n, K) block)."""
        n, k = prm["theta"].shape[0], self.combos.shape[0]
        step = max(1, chunk // k)  # bounds the memory of Sigma_W as `_chunked_log_post`
        lp = torch.cat([self.level_log_post({a: v[s : s + step] for a, v in prm.items()})
                        for s in range(0, n, step)]).numpy()  # fmt: skip
        pick = np.argmax(lp + rng.gumbel(size=lp.shape), axis=1)
        theta = prm["theta"].clone()
        theta[:, self.cat] = self.combos[torch.as_tensor(pick)]
        return {**prm, "theta": theta}, lp[np.arange(n), pick]


class LevelJumps(MCMCKernel):
    """NUTS on the continuous parameters (the categorical theta marginalised, `PyroModel`) and,
    after each of its draws past the warm-up, a categorical theta element's joint level move
    (``gpmsa.mcmc.level_moves``, the numpy sampler's): the levels drawn from their conditional
    given the draw (exact), then each element to another of its levels drawn uniformly with the
    continuous theta shifted by o[l'] - o[l] (their conditional modes at the two levels, found
    by `level_moves.level_offsets` at the last warm-up draw (without a warm-up: the first draw,
    which has no move), frozen then), accepted on the posterior ratio. Both leave the joint
    posterior of (levels, continuous) invariant, so the continuous draws keep the marginal NUTS
    targets; the move carries a chain between the modes of a level and a continuous parameter
    that trade off, which NUTS alone does not cross."""

    def __init__(self, nuts: NUTS, model: PyroModel, rng: np.random.Generator):
        self.nuts, self.model, self.rng = nuts, model, rng
        self.warmup, self.t, self.moves, self.accepted = 0, 0, 0, 0
        self.offsets: dict[int, np.ndarray] | None = None  # theta position -> (levels, cont)
        self.cont = model.held["theta"][0].numpy()  # theta's continuous free elements
        self.sizes = [len(lv) for lv in model.cat_levels]

    def setup(self, warmup_steps, *args, **kwargs):
        self.warmup = int(warmup_steps)
        self.nuts.setup(warmup_steps, *args, **kwargs)

    def __getattr__(self, name):  # NUTS's transforms, model, step_size, ...
        if "nuts" not in self.__dict__:
            raise AttributeError(name)
        return getattr(self.__dict__["nuts"], name)

    @property
    def initial_params(self):
        return self.nuts.initial_params

    @initial_params.setter
    def initial_params(self, params):
        self.nuts.initial_params = params

    def logging(self):
        return self.nuts.logging()

    def diagnostics(self):
        return self.nuts.diagnostics()

    def cleanup(self):
        self.nuts.cleanup()

    def _prm(self, params: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """Model parameters (batch 1) of unconstrained site values ``params``."""
        sites = {k: self.nuts.transforms[k].inv(v).unsqueeze(0) for k, v in params.items()}
        return self.model.params(sites)

    def sample(self, params):
        params = self.nuts.sample(params)
        self.t += 1
        if self.t < max(self.warmup, 1):
            return params
        with torch.no_grad():
            prm = self._prm(params)
            lp = self.model.level_log_post(prm)[0].numpy()
            row = int(np.argmax(lp + self.rng.gumbel(size=lp.shape)))  # levels | the draw
            if self.offsets is None:  # frozen before the moves: each kept draw's move exact
                self.offsets = self._learn(prm, row)
                return params
            theta, row = self._moves(prm, row, float(lp[row]))
        if theta is None:
            return params
        self.nuts.clear_cache()  # NUTS goes on from the moved point
        site = self.nuts.transforms["theta"](theta[0, self.cont])
        return {**params, "theta": site}

    def _learn(self, prm: dict[str, torch.Tensor], row: int) -> dict[int, np.ndarray]:
        """Each categorical element's conditional modes of the continuous theta at its levels,
        the other parameters at ``prm``'s values and the other levels at combination ``row``."""
        model, out = self.model, {}
        theta0 = prm["theta"][0].clone()
        theta0[model.cat] = model.combos[row]

        def log_post(th: np.ndarray) -> float:
            theta = torch.as_tensor(th, dtype=model.dtype).unsqueeze(0)
            at = {**prm, "theta": theta}
            return float(model.log_post_at(at, theta[0, model.cat])[0])

        for i, k in enumerate(model.cat):
            if self.sizes[i] > 1:
                out[int(k)] = level_moves.level_offsets(
                    log_post, theta0.numpy(), int(k), model.cat_levels[i], self.cont
                )
        return out

    def _moves(self, prm, row: int, lp: float):
        """Each categorical element's joint level move from combination ``row`` (log posterior
        ``lp``): (the moved theta (1, q), or None where none was accepted; the final row)."""
        model, theta, moved = self.model, prm["theta"], None
        idx = list(np.unravel_index(row, self.sizes))
        for i, k in enumerate(model.cat):
            off = self.offsets.get(int(k))
            if off is None:
                continue
            a = idx[i]
            b = int(self.rng.integers(self.sizes[i] - 1))
            b += b >= a  # another level, uniformly
            new = theta.clone()
            shifted = new[0, self.cont] + torch.as_tensor(off[b] - off[a], dtype=model.dtype)
            new[0, self.cont] = shifted
            cand = list(idx)
            cand[i] = b
            r = int(np.ravel_multi_index(cand, self.sizes))
            self.moves += 1
            if not bool(torch.all((shifted > 0.0) & (shifted < 1.0))):
                continue  # outside theta's prior: rejected
            if model.constraint is not None and not self._allowed(new, r):
                self.rng.random()  # rejected without the likelihood; the draws as if asked
                continue
            lp_new = float(model.log_post_at({**prm, "theta": new}, model.combos[r])[0])
            if np.log(self.rng.random()) < lp_new - lp:
                theta, idx, row, lp, moved = new, cand, r, lp_new, True
                self.accepted += 1
        return (theta if moved else None), row

    def _allowed(self, theta: torch.Tensor, row: int) -> bool:
        """Whether the theta constraint allows ``theta`` (1, q) at level combination ``row``
        (a candidate it rejects has log posterior -inf: no likelihood is needed)."""
        at = theta.clone()
        at[0, self.model.cat] = self.model.combos[row]
        return bool(self.model.constraint_term(at, np.ones(1, dtype=bool))[0] == 0.0)


def _scatter(init: np.ndarray, held: np.ndarray, dtype: torch.dtype):
    """(free flat indices (n_free,), order (n,), held values (n_held,)) of a parameter of
    initial value ``init`` whose elements ``held`` (a boolean mask, ``Problem.held_masks``) are
    held at ``init``'s values: ``cat([free values, held values])[..., order]`` is the flattened
    full array."""
    mask = np.asarray(held, dtype=bool).reshape(-1)
    free, fixed = np.flatnonzero(~mask), np.flatnonzero(mask)
    order = np.empty(mask.size, dtype=np.int64)
    order[free], order[fixed] = np.arange(free.size), free.size + np.arange(fixed.size)
    values = torch.as_tensor(init.reshape(-1)[fixed], dtype=dtype)
    return torch.as_tensor(free), torch.as_tensor(order), values


def _level_combinations(problem: Problem, masks: dict[str, np.ndarray], free: tuple[str, ...],
                        dtype: torch.dtype) -> tuple[np.ndarray, torch.Tensor]:  # fmt: skip
    """(positions (n_cat,) of theta's free categorical elements, every combination of their
    unit-scale levels (K, n_cat), the first element slowest); (empty, (1, 0)) without one.
    GPMSAError when K exceeds `MAX_LEVEL_COMBINATIONS`."""
    levels = problem.theta_levels if "theta" in free else None
    held = masks.get("theta", np.zeros(problem.q, dtype=bool))
    cat = [k for k, lv in enumerate(levels or ()) if lv is not None and not held[k]]
    if not cat:
        return np.zeros(0, dtype=np.int64), torch.zeros(1, 0, dtype=dtype)
    sizes = [len(levels[k]) for k in cat]
    if int(np.prod(sizes)) > MAX_LEVEL_COMBINATIONS:
        raise GPMSAError(
            f"the pyro backend marginalises a categorical theta over the combinations of its "
            f"levels: theta elements {cat} have {' x '.join(map(str, sizes))} = "
            f"{int(np.prod(sizes))}, more than MAX_LEVEL_COMBINATIONS = "
            f"{MAX_LEVEL_COMBINATIONS}; hold some with fixed=, or use backend='numpy' or 'torch'"
        )
    grid = np.meshgrid(*(levels[k] for k in cat), indexing="ij")
    combos = np.stack([g.reshape(-1) for g in grid], axis=-1)
    return np.asarray(cat, dtype=np.int64), torch.as_tensor(combos, dtype=dtype)


def refuse_unsupported(problem: Problem) -> None:
    """GPMSAError naming what of ``problem``'s extensions NUTS cannot sample (categorical inputs,
    a categorical theta (marginalised, `PyroModel`), a named mean basis and a theta constraint
    (-inf outside it, `PyroModel.log_prior`) it can; a fixed or held theta lifts the theta-side
    refusal): a callable mean basis at the observations' sampled theta (a numpy callable: no
    gradient)."""
    masks = problem.held_masks(("theta",))
    held = masks.get("theta", np.zeros(problem.q, dtype=bool)) if "theta" in problem.init else None
    free = None if held is None else ~held  # theta's free elements (None: no theta)
    mean = problem.mean_basis
    if free is not None and free.any() and mean is not None and mean.kind == "callable":
        raise GPMSAError(
            "the pyro backend does not support a callable mean_basis with theta sampled "
            "('constant' and 'linear' it takes; NUTS moves on gradients, which a numpy "
            "callable has none of); use backend='numpy' or 'torch'"
        )


MIN_DRAWS = 4
"""Draws a NUTS chain needs: pyro's diagnostics split it into two halves of two draws."""


def _check_nuts_args(n_iter, tune, n_warmup, target_accept, max_tree_depth, full_mass, jit) -> int:
    """The NUTS options checked (GPMSAError naming the first bad one); the warm-up steps
    (``num_threads`` is checked by `torch_threads`, before any sampling)."""
    if n_iter < MIN_DRAWS:
        raise GPMSAError(
            f"the pyro backend needs at least {MIN_DRAWS} draws a chain (pyro's diagnostics "
            f"split each chain in two halves), got n_iter = {n_iter}"
        )
    for name, flag in (("tune", tune), ("full_mass", full_mass), ("jit", jit)):
        check_flag(flag, name)
    if not 0.0 < as_real(target_accept, "target_accept") < 1.0:
        raise GPMSAError(f"target_accept must be a number in (0, 1), got {target_accept!r}")
    check_count(max_tree_depth, "max_tree_depth")
    return check_count(n_warmup, "n_warmup") if tune else 0


def check_n_jobs(n_jobs) -> None:
    """GPMSAError for an ``n_jobs`` that `sample` refuses, whatever the problem: any but None,
    1 or -1 (the chains run one after another in this process)."""
    parallel.n_workers(n_jobs, 1)  # refuse a bad n_jobs
    if n_jobs is not None and n_jobs > 1:
        raise GPMSAError(
            f"n_jobs={n_jobs}: the pyro backend runs its chains one after another in this "
            "process; leave n_jobs=None (or 1)"
        )


def sample(
    problem: Problem,
    *,
    n_iter: int,
    n_chains: int = 1,
    tune: bool = True,
    step_widths: dict[str, np.ndarray] | None = None,
    seed=None,
    progress: bool = False,
    n_warmup: int = N_WARMUP,
    target_accept: float = 0.9,
    max_tree_depth: int = 10,
    full_mass: bool = True,
    jit: bool = True,
    num_threads: int | None = 1,
    init: str | dict = "auto",
    n_jobs: int | None = None,
) -> Chains:
    """NUTS draws of every sampled parameter: ``n_chains`` chains (one after another) of
    ``n_iter`` draws after ``n_warmup`` adaptation steps.

    Starts: ``init`` ("auto": GPM/SA's initial values for one chain, dispersed ones for several,
    so that R-hat can see chains that have not forgotten them; chain c starts as the numpy
    backend's chain c; a dict name -> (n_chains, *shape) gives them; see
    ``gpmsa.mcmc.starts``), recorded in ``info["starts"]``.

    ``tune=False`` skips the adaptation (unit step size and mass matrix, no warm-up); a chain
    that never leaves its starting point (as then on the road case) is a GPMSAError, not a
    sample. A chain needs at least ``MIN_DRAWS`` draws.
    ``full_mass``: adapt a dense mass matrix (default) rather than a diagonal one (1.5x less
    wall time per draw on the road case's fit); ``target_accept`` 0.9 (pyro's default: 0.8) takes
    shorter steps along the curved lamWs/lamWOs ridge of a scalar-output emulator. With these
    defaults the road case's fit reaches R-hat 1.005 in 4 x 1,500 draws (docs/performance.md).
    ``step_widths`` do not apply to NUTS (an error if given). Each chain's torch randomness is
    seeded from ``seed`` inside ``torch.random.fork_rng`` (the global RNG is left as it was);
    NUTS runs on the CPU with gradients whatever torch's grad or inference mode and default
    device as the caller set them (`_autograd_on_cpu`).
    ``accept_rate`` holds pyro's per-chain "acceptance rate" diagnostic and ``step_widths`` the
    adapted NUTS step size, each repeated over every sampled element (NaN for held elements,
    ``problem.fixed_elements``, whose draws are their values exactly; a categorical theta
    element, marginalised and drawn from its conditional per draw: width NaN, rate its joint
    level moves' acceptance (1 where no continuous theta is sampled: no move);
    ``info["marginalised_levels"]`` its positions). ``jit``: compile the
    potential energy with the torch JIT (about 1.6x faster on the road case; not with a theta
    constraint, whose numpy verdict a trace would freeze: `PyroModel`). A start the constraint
    rejects is the numpy sampler's StartRejectedError ("pass theta_init="). ``num_threads``:
    torch CPU threads while sampling (see the torch backend; None: unchanged). ``n_jobs``: None,
    1 or -1 (the chains run one after another in this process; any other number is a
    GPMSAError).
    """
    if step_widths:
        raise GPMSAError("the pyro backend (NUTS) takes no step_widths; leave step_widths=None")
    check_sample_args(n_iter, n_chains, seed)
    progress = check_flag(progress, "progress")
    check_draws_memory(problem, int(n_iter), int(n_chains))
    check_n_jobs(n_jobs)
    refuse_unsupported(problem)
    warmup = _check_nuts_args(n_iter, tune, n_warmup, target_accept, max_tree_depth, full_mass,
                              jit)  # fmt: skip
    seqs = np.random.SeedSequence(seed).spawn(int(n_chains))
    how, firsts = starts.chain_starts(problem, init, seqs)
    with _autograd_on_cpu():  # whatever the caller's grad mode and default device
        model = PyroModel(problem)
        if not model.sites:
            raise GPMSAError(
                "the pyro backend samples the continuous parameters by NUTS, with a categorical "
                "theta's levels marginalised; every other parameter is held here: use "
                "backend='numpy' or 'torch'"
            )
        runs = []
        for seq, first in zip(seqs, firsts, strict=True):
            seed_c = int(seq.generate_state(1)[0])
            kernel = NUTS(
                model, adapt_step_size=tune, adapt_mass_matrix=tune,
                target_accept_prob=target_accept, max_tree_depth=max_tree_depth,
                max_plate_nesting=0,
                jit_compile=jit and model.constraint is None,  # a trace would freeze the verdict
                full_mass=full_mass,
                ignore_jit_warnings=True,
                init_strategy=init_to_value(values=model.init_values(first)),
            )  # fmt: skip
            rng = _level_generator(seq)  # a categorical theta's moves and draws
            driver = kernel
            if model.cat.size and model.held["theta"][0].numel():  # levels and continuous theta
                driver = LevelJumps(kernel, model, rng)
            with torch.random.fork_rng(), torch_threads(num_threads):
                torch.manual_seed(seed_c)
                mcmc = MCMC(driver, num_samples=int(n_iter), warmup_steps=warmup,
                            disable_progbar=not progress)  # fmt: skip
                with warnings.catch_warnings():  # pyro's JIT uses the deprecated torch.jit.trace
                    warnings.filterwarnings(
                        "ignore", message=".*jit.trace", category=DeprecationWarning
                    )
                    mcmc.run()
            sites = {k: v.detach() for k, v in mcmc.get_samples().items()}
            accept = mcmc.diagnostics()["acceptance rate"]["chain 0"]
            if all(bool(torch.all(v == v[:1])) for v in sites.values()):
                why = ("with tune=False NUTS keeps a unit step size; use tune=True" if not tune
                       else "raise n_warmup, or lower target_accept")  # fmt: skip
                raise GPMSAError(
                    f"NUTS never left its starting point in {int(n_iter)} draws (acceptance rate "
                    f"{float(accept):.2g}): the chain is no sample of the posterior; {why}"
                )
            jumps = (1.0, {})  # (the level moves' acceptance, their offsets)
            if driver is not kernel:
                jumps = (driver.accepted / max(driver.moves, 1), driver.offsets or {})
            runs.append((sites, float(accept), float(kernel.step_size), rng, jumps))
        draws, log_post = {}, []
        for sites, _, _, rng, _ in runs:
            with torch.no_grad():
                prm = model.params(sites)
                if model.cat.size:  # each draw's levels from their conditional (exact)
                    prm, lp = model.draw_levels(prm, rng)
                    log_post.append(lp)
                else:
                    log_post.append(_chunked_log_post(model, prm))
            for name in problem.names:
                draws.setdefault(name, []).append(prm[name].numpy())
        rate, wid = {}, {}
        masks = problem.held_masks()
        for name in problem.names:  # held: no step, no acceptance
            held = masks.get(name, np.zeros(problem.init[name].shape, dtype=bool))
            rate[name] = np.stack([np.where(held, np.nan, float(r[1])) for r in runs])
            wid[name] = np.stack([np.where(held, np.nan, float(r[2])) for r in runs])
        if model.cat.size:  # the level moves' acceptance (1: no continuous theta, drawn), no step
            rate["theta"][:, model.cat] = np.array([r[4][0] for r in runs])[:, None]
            wid["theta"][:, model.cat] = np.nan
        moves = level_moves.chains_record([r[4][1] for r in runs], model.held["theta"][0].tolist()
                                          if model.cat.size else [])  # fmt: skip
        return Chains(
            draws={k: np.stack(v) for k, v in draws.items()},
            log_post=np.stack(log_post),
            accept_rate=rate,
            step_widths=wid,
            info={"n_iter": int(n_iter), "n_chains": int(n_chains), "tune": tune,
                  "n_warmup": warmup, "target_accept": target_accept, "full_mass": full_mass,
                  "seed": seed, "init": how,
                  "starts": {k: np.stack([f[k] for f in firsts]) for k in problem.init},
                  "backend": "pyro", "sampler": "NUTS",
                  **({"marginalised_levels": [int(k) for k in model.cat]}
                     if model.cat.size else {}),
                  **({"level_offsets": moves} if moves else {})},
        )  # fmt: skip


@contextmanager
def _autograd_on_cpu() -> Iterator[None]:
    """Gradients recorded (NUTS differentiates the potential) and new tensors on the CPU inside
    the block, whatever the caller set: ``torch.no_grad()``, ``set_grad_enabled(False)``,
    ``inference_mode()``, a default device (``set_default_device``, ``with torch.device``);
    restored afterwards. (The device mode costs every torch call: entered only where needed.)"""
    with ExitStack() as stack:
        stack.enter_context(torch.inference_mode(False))
        stack.enter_context(torch.enable_grad())
        if torch.empty(0).device.type != "cpu":  # (torch.get_default_device: torch >= 2.3)
            stack.enter_context(torch.device("cpu"))
        yield


def _level_generator(seq: np.random.SeedSequence) -> np.random.Generator:
    """The generator of a chain's categorical theta draws: a child of its SeedSequence (not its
    NUTS stream nor its start's, ``gpmsa.mcmc.starts.start_generator``)."""
    child = np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, 0x1E7E1))
    return np.random.default_rng(child)


def _chunked_log_post(model: PyroModel, prm: dict[str, torch.Tensor], chunk: int = 256):
    """GPM/SA log posterior of each draw (n,), in chunks to bound the memory of Sigma_W."""
    n = prm["betaU"].shape[0]
    out = []
    for s in range(0, n, chunk):
        part = {k: v[s : s + chunk] for k, v in prm.items()}
        out.append(model.log_likelihood(part) + model.log_prior(part))
    return torch.cat(out).numpy()
