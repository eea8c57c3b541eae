"""Metropolis-within-Gibbs over several GPM/SA models whose theta share study elements.

One sweep: each study theta element (a uniform walk on the unit scale, accepted on the sum over
the models that use it of their log-likelihood change, plus its prior: the models' theta prior
or its hierarchical group's truncated normal), then each model's own parameters by that model's
``gpmsa.mcmc.sampler.ChainState`` sweep (its theta held by the study), then each hierarchical
group's mean mu (uniform walk) and precision lam (walk on log lam, with its Hastings factor).
Step widths are tuned as GPM/SA tunes them (``gpmsa.mcmc.tuning``) over every element at once.
A categorical study element (shared or a model's own, never hierarchical: `element_levels`)
moves to another of its levels drawn uniformly, with the continuous free elements of its models
shifted between their per-level conditional modes (``gpmsa.mcmc.level_moves``; found at the
start, so that the tuned widths suit every level the chain visits, and again after tuning, then
frozen for the draws: `StudyState.learn_level_shifts`), accepted on the sum of the
touched models' log-likelihood changes and the shifted elements' priors (its own prior is
uniform over its levels).

With ``temperatures`` (parallel tempering, ``gpmsa.mcmc.tempering``) a chain runs a ladder of
whole study states, copy k at temperature T_k targeting prior x L^(1/T_k), L the product of the
models' likelihoods (every likelihood change in the sweep's acceptances times 1/T_k; the priors,
the groups' hyperpriors and truncated normals with them, untempered: the groups' moves are the
same at every temperature); neighbours swap their whole states (study elements, groups, each
model's likelihood state) as ``tempering.swap`` accepts; the T = 1 copy's draws are kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import level_moves, starts, tempering, tuning
from gpmsa.mcmc.acceptance import log_uniform
from gpmsa.mcmc.parallel import in_this_process, run_chains
from gpmsa.mcmc.sampler import DEFAULT_WIDTHS, ChainState, default_widths, require_finite
from gpmsa.model.problem import Problem
from gpmsa.studies.layout import HyperPriors, Layout

MU_WIDTH = 0.2
"""Initial step width of a group mean mu (unit scale), as SEPIA's."""
LOG_LAM_WIDTH = 1.0
"""Initial step width of a group precision on the log scale."""
_SQRT_HALF = math.sqrt(0.5)


def log_mass01(mu: float, lam: float) -> float:
    """log P(0 < X < 1) for X ~ Normal(mu, 1/lam), mu in (0, 1) (accurate in both tails, and
    for a tiny lam, where the erfc form's 1 - P rounds to 1)."""
    s = math.sqrt(lam) * _SQRT_HALF
    q = 0.5 * (math.erfc(mu * s) + math.erfc((1.0 - mu) * s))  # 1 - P
    if q < 0.5:
        return math.log1p(-q)
    p = 0.5 * (math.erf(mu * s) + math.erf((1.0 - mu) * s))  # P, no cancellation
    return math.log(p) if p > 0 else -math.inf  # (lam 0: a flat normal puts no mass there)


@dataclass(frozen=True)
class StudyChains:
    """Draws of a study's chains (unit scale).

    theta (C, N, G): study elements; mu, lam (C, N, H): hierarchical groups' mean and
    precision; log_post (C, N): the joint log posterior up to a constant; members: per model,
    name -> (C, N, *shape) of its own sampled parameters; accept_rate, widths (C, n_el): per
    element in sweep order (``names``).
    """

    theta: np.ndarray
    mu: np.ndarray
    lam: np.ndarray
    log_post: np.ndarray
    members: tuple[dict[str, np.ndarray], ...]
    accept_rate: np.ndarray
    widths: np.ndarray
    names: tuple[str, ...]
    info: dict

    def __repr__(self) -> str:
        c, n = np.shape(self.log_post)[:2] if np.ndim(self.log_post) == 2 else (0, 0)
        g, h = np.shape(self.theta)[-1], np.shape(self.mu)[-1]
        return (f"StudyChains({c} chains x {n} draws, {g} study elements, {h} groups, "
                f"{len(self.members)} models)")  # fmt: skip


def held_elements(problems: list[Problem], layout: Layout) -> dict[int, float]:
    """Study element -> its unit-scale value, for each element the models' problems hold (their
    theta fixed whole or by element: ``fixed={"theta": ...}``); GPMSAError where models that
    share an element hold it at different values, or some of them do not hold it."""
    held: dict[int, float] = {}
    for i, prob in enumerate(problems):
        for k in np.flatnonzero(_theta_mask(prob)):
            e, v = layout.index[i][k], float(prob.init["theta"][k])
            if not layout.same_unit_value(e, held.get(e, v), v):
                raise GPMSAError(
                    f"fixed theta: the models sharing {layout.elements[e].name} hold it at "
                    "different values; hold a shared parameter at one value"
                )
            held[e] = v
    for e in held:
        el = layout.elements[e]
        free = [layout.labels[i] for i, k in el.uses if not _holds(problems[i], k)]
        if free:
            raise GPMSAError(
                f"fixed theta: {el.name} is shared, held by some of its models but not by "
                f"{free}: hold it in every model that has it (one fixed= dict for every model "
                "does so)"
            )
    return held


def element_levels(problems: list[Problem], layout: Layout) -> list[np.ndarray | None]:
    """Each study element's unit-scale levels where it is categorical (its models'
    ``Problem.theta_levels``), else None. GPMSAError naming the parameter for a categorical
    hierarchical one (a normal hierarchy over level codes has no meaning) and for a shared one
    that is categorical in some of its models only, or whose models' levels differ."""
    out: list[np.ndarray | None] = []
    for el in layout.elements:
        per = [(problems[i].theta_levels or [None] * problems[i].q)[k] for i, k in el.uses]
        if all(lv is None for lv in per):
            out.append(None)
            continue
        if el.group >= 0:
            raise GPMSAError(
                f"hierarchical parameter {el.param!r} is categorical: a normal hierarchy over "
                "its level codes has no meaning; give it as shared (one level in every model) "
                "or leave it each model's own"
            )
        first = per[0]
        if any(lv is None or not np.array_equal(lv, first) for lv in per):
            what = {layout.labels[i]: None if lv is None else np.asarray(lv).tolist()
                    for (i, _), lv in zip(el.uses, per, strict=True)}  # fmt: skip
            raise GPMSAError(
                f"shared parameter {el.param!r} is categorical with different levels (or "
                f"continuous) in its models (unit-scale levels, None: continuous: {what}); "
                "give every model that shares it the same training levels and range"
            )
        out.append(np.asarray(first, dtype=np.float64))
    return out


def _theta_mask(problem: Problem) -> np.ndarray:
    """The theta elements ``problem`` holds (``Problem.held_masks``), a boolean mask (q,)."""
    return problem.held_masks(("theta",)).get("theta", np.zeros(problem.q, dtype=bool))


def _holds(problem: Problem, k: int) -> bool:
    """Whether ``problem`` holds its theta element ``k``."""
    return bool(_theta_mask(problem)[k])


class StudyState:
    """The current state of one study chain: the models' ``ChainState``s (theta held), the study
    elements g, and the groups' (mu, lam). ``beta``: the power 1/T of the likelihoods in the
    acceptances (a tempered copy; 1.0: the plain sweep bit for bit)."""

    def __init__(
        self, problems: list[Problem], layout: Layout, hyper: HyperPriors,
        start: list[dict[str, np.ndarray]], g: np.ndarray, mu: np.ndarray, lam: np.ndarray,
        rng: np.random.Generator,
    ):  # fmt: skip
        self.layout, self.hyper, self.rng = layout, hyper, rng
        self.held = held_elements(problems, layout)  # never proposed
        self.g, self.mu, self.lam = g.copy(), mu.copy(), lam.copy()
        for e, v in self.held.items():
            self.g[e] = v
        self.states = []
        for i, prob in enumerate(problems):
            held = prob.with_init({}, fixed=prob.fixed | {"theta"})
            init = {**start[i], "theta": self.g[list(layout.index[i])]}
            self.states.append(ChainState(held, init, rng))
        self.group_els = [layout.members_of(h) for h in range(len(layout.groups))]
        self.sizes = [len(s.els) for s in self.states]
        self.levels = element_levels(problems, layout)  # a categorical element: its level moves
        self.shifts: dict[int, tuple] = {}  # `learn_level_shifts`: element -> its shifts
        self.offsets: dict[int, np.ndarray] = {}  # and its level_offsets (the record's)
        self.touched = {e: _models_of(layout, [e]) for e, lv in enumerate(self.levels)
                        if lv is not None}  # fmt: skip
        self._beta = 1.0

    # --- a tempered copy (gpmsa.mcmc.tempering) ------------------------------------------------
    @property
    def beta(self) -> float:
        """The power 1/T of the likelihoods (every model's sweep takes it too)."""
        return self._beta

    @beta.setter
    def beta(self, value: float) -> None:
        self._beta = float(value)
        for s in self.states:
            s.beta = self._beta

    @property
    def loglik(self) -> float:
        """The sum of the models' log-likelihoods (untempered)."""
        return sum(s.lik.loglik for s in self.states)

    def exchange(self, other: StudyState) -> None:
        """Swap states with ``other`` (``tempering.swap``): the study elements, the groups'
        (mu, lam) and each model's likelihood state and running log prior."""
        self.g, other.g = other.g, self.g
        self.mu, other.mu = other.mu, self.mu
        self.lam, other.lam = other.lam, self.lam
        for s, t in zip(self.states, other.states, strict=True):
            s.exchange(t)

    def use_level_shifts(self, source: StudyState) -> None:
        """``source``'s level moves (`learn_level_shifts`; any shifts keep the move exact)."""
        self.shifts, self.touched = source.shifts, source.touched

    # --- priors -------------------------------------------------------------------------------
    def _theta_lp(self, e: int, x: float) -> float:
        """Log prior of study element e at x, up to terms that do not depend on x."""
        if not 0.0 < x < 1.0:
            return -math.inf
        el = self.layout.elements[e]
        if el.group < 0:
            m, sd = el.prior
            return -0.5 * ((x - m) / sd) ** 2
        d = x - self.mu[el.group]
        return -0.5 * self.lam[el.group] * d * d

    def _element_lp(self, e: int, x: float) -> float:
        """`_theta_lp`, and for a categorical element its uniform prior over its levels."""
        if self.levels[e] is None:
            return self._theta_lp(e, x)
        return 0.0 if x in self.levels[e] else -math.inf

    def _group_lp(self, h: int, mu: float, lam: float) -> float:
        """Log density of group h's (mu, lam): hyperpriors and the elements' truncated normals."""
        hp = self.hyper
        if not (0.0 < mu < 1.0 and lam > 0.0):
            return -math.inf
        els = self.group_els[h]
        ss = sum((self.g[e] - mu) ** 2 for e in els)
        lp = -0.5 * ((mu - hp.mu_mean) / hp.mu_sd) ** 2 + hp.log_prior_lam(lam)
        if lp == -math.inf:
            return lp
        return lp + len(els) * (0.5 * math.log(lam) - log_mass01(mu, lam)) - 0.5 * lam * ss

    def log_post(self) -> float:
        """The joint log posterior (up to a constant)."""
        lp = sum(s.log_post() for s in self.states)
        for e, el in enumerate(self.layout.elements):
            if el.group < 0:
                lp += self._element_lp(e, float(self.g[e]))
        for h in range(len(self.group_els)):
            lp += self._group_lp(h, float(self.mu[h]), float(self.lam[h]))
        return lp

    # --- the sweep ----------------------------------------------------------------------------
    def sweep(self, widths: np.ndarray, prop_mh: bool, accepted: np.ndarray) -> None:
        """One sweep (theta elements, each model's own parameters, the groups' mu and lam);
        adds 1 to ``accepted[i]`` per accepted element (order as ``element_names``)."""
        G, H = self.layout.n_elements, len(self.group_els)
        beta = self._beta
        u = self.rng.random((G + 2 * H, 2))
        for e, el in enumerate(self.layout.elements):
            if e in self.held:
                continue
            if self.levels[e] is not None:  # another level (with the continuous elements)
                self._level_move(e, u[e, 0], u[e, 1], accepted)
                continue
            x = float(self.g[e])
            cand = x + widths[e] * (u[e, 0] - 0.5)
            lp_new = self._theta_lp(e, cand)
            if lp_new == -math.inf:
                continue
            dll = 0.0
            for i, k in el.uses:
                lik = self.states[i].lik
                ll = lik.propose("theta", (k,), cand)
                if ll == -math.inf:
                    dll = -math.inf
                    break
                dll += ll - lik.loglik
            if dll == -math.inf:
                continue
            if log_uniform(u[e, 1]) < dll * beta + lp_new - self._theta_lp(e, x):
                for i, _ in el.uses:
                    self.states[i].lik.accept()
                self.g[e] = cand
                accepted[e] += 1
        o = G
        for s, n in zip(self.states, self.sizes, strict=True):
            s.sweep(widths[o : o + n], prop_mh, accepted[o : o + n])
            o += n
        for h in range(H):
            mu, lam = float(self.mu[h]), float(self.lam[h])
            cur = self._group_lp(h, mu, lam)
            cand = mu + widths[o] * (u[G + 2 * h, 0] - 0.5)
            new = self._group_lp(h, cand, lam)
            if log_uniform(u[G + 2 * h, 1]) < new - cur:
                self.mu[h], mu, cur = cand, cand, new
                accepted[o] += 1
            step = widths[o + 1] * (u[G + 2 * h + 1, 0] - 0.5)
            cand = lam * math.exp(step)
            new = self._group_lp(h, mu, cand)
            # step = log(lam'/lam): the Hastings factor
            if log_uniform(u[G + 2 * h + 1, 1]) < new - cur + step:
                self.lam[h] = cand
                accepted[o + 1] += 1
            o += 2

    # --- a categorical element's level move (gpmsa.mcmc.level_moves) ---------------------------
    def learn_level_shifts(self) -> None:
        """Each free categorical element's joint level move: the shifts of the continuous free
        elements of its models between their conditional modes at its levels (the other
        parameters at their current values; ``level_moves.level_offsets``); none where its
        models have no such element (its level moves alone)."""
        lay = self.layout
        for e, lv in enumerate(self.levels):
            if lv is None or e in self.held or lv.size < 2:
                continue
            models = {i for i, _ in lay.elements[e].uses}
            cont = sorted({j for i in models for j in lay.index[i]
                           if self.levels[j] is None and j not in self.held})  # fmt: skip
            if not cont:
                continue
            touched = _models_of(lay, [e, *cont])

            def log_post(g: np.ndarray, cont=cont, touched=touched) -> float:
                lp = sum(self._theta_lp(j, float(g[j])) for j in cont)
                if lp == -math.inf:
                    return lp
                for i in touched:  # never accepted: the models' states are unchanged
                    lp += self.states[i].lik.propose_theta(g[list(lay.index[i])])
                return lp

            off = level_moves.level_offsets(log_post, self.g, e, lv, cont)
            rows = {float(v): r for r, v in enumerate(lv)}
            self.shifts[e] = (rows, level_moves.shift_table(off), cont)
            self.offsets[e] = off
            self.touched[e] = touched

    def level_record(self) -> dict[int, dict]:
        """The level moves' record (`learn_level_shifts`): categorical element -> {"shifted":
        the continuous elements it shifts, "offsets": their ``level_moves.level_offsets``
        (n_levels, len(shifted)), unit scale}; {} where no element makes the joint move."""
        return {e: {"shifted": [int(j) for j in self.shifts[e][2]], "offsets": off}
                for e, off in self.offsets.items()}  # fmt: skip

    def _level_move(self, e: int, u0: float, u1: float, accepted: np.ndarray) -> None:
        """Categorical element ``e`` to another of its levels (uniformly: a symmetric proposal,
        its prior uniform), the continuous elements shifted (`learn_level_shifts`); Metropolis
        on the touched models' log-likelihood change and the shifted elements' priors."""
        lv = self.levels[e]
        x = float(self.g[e])
        others = lv[lv != x]
        if others.size == 0:
            return
        new = float(others[int(u0 * others.size)])
        cand = self.g.copy()
        cand[e] = new
        d_lp = 0.0
        if e in self.shifts:
            rows, table, cont = self.shifts[e]
            d_lp = level_moves.shift(cand, cont, table[rows[x]][rows[new]],
                                     lambda k, v: self._theta_lp(cont[k], v))  # fmt: skip
            if d_lp == -math.inf:
                return
        touched = self.touched[e]
        dll = 0.0
        for i in touched:
            lik = self.states[i].lik
            ll = lik.propose_theta(cand[list(self.layout.index[i])])
            if ll == -math.inf:
                return
            dll += ll - lik.loglik
        if log_uniform(u1) < dll * self._beta + d_lp:
            for i in touched:
                self.states[i].lik.accept()
            self.g = cand
            accepted[e] += 1


def _models_of(layout: Layout, els: list[int]) -> list[int]:
    """The models that use any of the study elements ``els``, in order."""
    return sorted({i for e in els for i, _ in layout.elements[e].uses})


def element_names(states: list[ChainState], layout: Layout) -> list[str]:
    """Names of the sweep's elements ("E[beam]", "beam.lamOs[0]", "E.mu", "E.lam", ...)."""
    names = [el.name for el in layout.elements]
    for lab, s in zip(layout.labels, states, strict=True):
        names += [f"{lab}.{n}{list(idx)}" for n, idx in s.els]
    for g in layout.groups:
        names += [f"{g}.mu", f"{g}.lam"]
    return names


def _tuning_kinds(states: list[ChainState], layout: Layout) -> list[str]:
    """The parameter kind of each element for GPM/SA's tuning levels."""
    kinds = ["theta"] * layout.n_elements
    for s in states:
        kinds += [n for n, _ in s.els]
    return kinds + ["theta", "lamOs"] * len(layout.groups)


def _start(problems, layout, hyper, how, rng):
    """Each model's start, the study elements' and the groups' (mu, lam)."""
    start = [starts.draw_start(p, how, rng) for p in problems]
    g = np.array([start[el.uses[0][0]]["theta"][el.uses[0][1]] for el in layout.elements])
    H = len(layout.groups)
    if how == "gpmsa":
        mu, lam = np.full(H, 0.5), np.full(H, hyper.lam_start)
    else:
        mu = np.array([np.mean(g[layout.members_of(h)]) for h in range(H)])
        lo = max(hyper.lam_start / 10.0, hyper.lam_min * (1.0 + 1e-9))  # inside the prior
        lam = np.exp(rng.uniform(np.log(lo), np.log(hyper.lam_start * 10.0), H))
    return start, g, mu, lam


def _default_widths(state: StudyState, layout: Layout) -> np.ndarray:
    """GPM/SA's initial step widths of the sweep's elements, in sweep order."""
    w = [np.full(layout.n_elements, DEFAULT_WIDTHS["theta"])]
    for s in state.states:
        dw = default_widths(s.problem)
        w.append(np.array([float(dw[n][idx]) for n, idx in s.els]))
    w.append(np.tile([MU_WIDTH, LOG_LAM_WIDTH], len(layout.groups)))
    return np.concatenate(w)


def run_study_chain(
    problems: list[Problem], layout: Layout, hyper: HyperPriors, n_iter: int, *, tune: bool,
    seed: np.random.SeedSequence, init: str = "gpmsa", tune_rounds: int = tuning.N_BURN,
    tune_levels: int = tuning.N_LEVELS, progress: bool = False, desc: str = "study",
    start: tuple | None = None, widths: np.ndarray | None = None, prop_mh: bool | None = None,
    temperatures: tuple[float, ...] | None = None, swap_every: int = 1,
    adapt_ladder: bool = False, hot: list | None = None,
) -> dict:  # fmt: skip
    """One chain: its start (``gpmsa.mcmc.starts`` rule ``init``; a continuation's ``start``:
    (models' starts, g, mu, lam)), tuning, ``n_iter`` sweeps; ``widths``: the initial step
    widths in sweep order (None: GPM/SA's); ``prop_mh``: GPM/SA's proportional precision steps
    (None: when not tuned). ``temperatures``: a ladder from 1 (``tempering.ladder``), a copy of
    the study state per temperature from the same start, each tuned at its temperature, a swap
    round every ``swap_every`` sweeps (``tempering.run_ladder``); the T = 1 copy's draws kept;
    ``adapt_ladder``: the ladder adapted during tuning, then frozen (``tempering.adapt_ladder``);
    ``hot``: each hot copy's (start, as ``start``; widths, sweep order), K - 1 of them (a
    continuation resuming them where they stopped, run with those widths where not ``tune``).

    Returns plain arrays: theta (N, G), mu, lam (N, H), log_post (N,), members (per model,
    name -> (N, *shape)), accept_rate and widths per element, level_offsets (the (T = 1)
    state's level moves, ``StudyState.level_record``); with ``temperatures`` also swap_rate
    (K - 1,), each neighbour pair's swap acceptance over the draws, "hot" (the hot copies' last
    states and widths, `hot_states`), and with ``adapt_ladder`` ladder (K,), the adapted one.
    """
    rng = np.random.default_rng(seed)
    if start is None:
        start = _start(problems, layout, hyper, init, starts.start_generator(seed))
    at = [start] + [h for h, _ in hot or [(start, None)] * (len(temperatures or (1.0,)) - 1)]
    copies = [StudyState(problems, layout, hyper, *a, rng) for a in at]
    state = copies[0]
    if math.isnan(state.log_post()):
        raise GPMSAError("the starting values give a log posterior of NaN; check the data")
    w = _default_widths(state, layout) if widths is None else np.array(widths, dtype=float)
    prop_mh = not tune if prop_mh is None else prop_mh
    n_tune = tune_rounds * tune_levels * (1 + adapt_ladder) if tune else 0
    total = len(copies) * (n_iter + n_tune)
    own = [s.problem.sampled for s in state.states]
    out = {"theta": np.empty((n_iter, layout.n_elements)), "log_post": np.empty(n_iter),
           "mu": np.empty((n_iter, len(layout.groups))),
           "lam": np.empty((n_iter, len(layout.groups)))}  # fmt: skip
    members = [{n: np.empty((n_iter, *s.params[n].shape)) for n in names}
               for s, names in zip(state.states, own, strict=True)]  # fmt: skip

    def record(it: int) -> None:  # the (T = 1) state's sweep it
        out["theta"][it], out["mu"][it], out["lam"][it] = state.g, state.mu, state.lam
        for s, names, rec in zip(state.states, own, members, strict=True):
            for n in names:
                rec[n][it] = s.params[n]
        out["log_post"][it] = state.log_post()

    kinds = _tuning_kinds(state.states, layout)
    ran: dict = {}
    with progress_bar(progress, total, desc, unit="it") as bar, one_thread(None):
        if temperatures is not None:
            for copy, t in zip(copies, temperatures, strict=True):
                copy.beta = 1.0 / t
            accepted, w, out["swap_rate"], adapted = tempering.run_ladder(
                copies, rng, n_iter, w, kinds, record, swap_every=swap_every, tune=tune,
                tune_rounds=tune_rounds, tune_levels=tune_levels, prop_mh=prop_mh, bar=bar,
                desc=desc, adapt=temperatures if adapt_ladder else None,
                copy_widths=None if hot is None else [np.asarray(v, dtype=float) for _, v in hot],
                out=ran,
            )  # fmt: skip
            out["hot"] = hot_states(copies[1:], ran["widths"][1:])
            if adapt_ladder:
                out["ladder"] = np.asarray(adapted)
        else:
            if tune:
                bar.set_description(f"{desc}: tuning step widths")
                state.learn_level_shifts()  # the widths tuned with the level moves: both modes
                w = tuning.tune_widths(state.sweep, kinds, w, tune_rounds, tune_levels,
                                       bar.update)  # fmt: skip
            state.learn_level_shifts()  # found anew, frozen before the draws (categorical)
            bar.set_description(f"{desc}: sampling")
            accepted = np.zeros(w.size)
            for it in range(n_iter):
                state.sweep(w, prop_mh, accepted)
                record(it)
                if it % 100 == 99:
                    bar.update(100)
            bar.update(n_iter % 100)
    out.update(members=members, accept_rate=accepted / max(n_iter, 1), widths=w,
               names=element_names(state.states, layout),
               level_offsets=state.level_record())  # fmt: skip
    return out


def hot_states(copies: list[StudyState], widths: list[np.ndarray]) -> dict:
    """The hot copies' last states and widths: "theta" (K - 1, G), "mu", "lam" (K - 1, H),
    "members" (per model, its sampled parameters name -> (K - 1, *shape)) and "widths"
    (K - 1, n_el; sweep order)."""
    models = [{n: np.stack([c.states[i].params[n] for c in copies]) for n in s.problem.sampled}
              for i, s in enumerate(copies[0].states)] if copies else []  # fmt: skip
    return {"theta": np.array([c.g for c in copies]), "mu": np.array([c.mu for c in copies]),
            "lam": np.array([c.lam for c in copies]), "members": models,
            "widths": np.array(widths)}  # fmt: skip


def _wrong_run(run, n_iter: int, n_elements: int, n_temps: int = 0,
               adapt: bool = False) -> str | None:  # fmt: skip
    """``run_chains``' check of a study chain's result: None when it is the task's own, as
    `run_study_chain` makes it (``n_temps`` > 0: with the swap rates of that many copies, and
    their adapted ladder with ``adapt``), else the draws it should hold."""
    keys = {"theta", "mu", "lam", "log_post", "members", "accept_rate", "widths", "names"}
    if isinstance(run, dict) and keys <= set(run):
        if np.shape(run["theta"]) == (n_iter, n_elements) and np.shape(run["log_post"]) == (
            n_iter,
        ):
            if not n_temps or np.shape(run.get("swap_rate")) == (n_temps - 1,):
                if not adapt or np.shape(run.get("ladder")) == (n_temps,):
                    return None
    return f"{n_iter} sweeps" + (f" at {n_temps} temperatures" if n_temps else "")


def sample_study(
    problems: list[Problem], layout: Layout, hyper: HyperPriors, *, n_iter: int,
    n_chains: int = 1, tune: bool = True, seed=None, init: str = "auto",
    tune_rounds: int = tuning.N_BURN, tune_levels: int = tuning.N_LEVELS,
    progress: bool = False, n_jobs: int | None = None, executor=None,
    chain_starts: list | None = None, widths: list | None = None, prop_mh: bool | None = None,
    temperatures: tuple[float, ...] | None = None, swap_every: int = 1,
    adapt_ladder: bool = False, hot_copies: list | None = None,
) -> StudyChains:  # fmt: skip
    """``n_chains`` study chains, chain c on ``SeedSequence(seed).spawn(n_chains)[c]`` (its draws
    do not depend on where it runs: ``n_jobs`` processes or ``executor``, as
    ``gpmsa.mcmc.parallel.run_chains``). A continuation gives ``chain_starts`` (per chain:
    models' starts, g, mu, lam; init "continued"), ``widths`` (per chain, sweep order; None:
    GPM/SA's) and ``prop_mh`` (``run_study_chain``'s). ``temperatures`` (a checked ladder,
    ``tempering.ladder``, or an (n_chains, K) array, chain c at row c: a continuation of chains
    that adapted their ladders) and ``swap_every``: parallel tempering (``run_study_chain``);
    info records "temperatures" (per chain where they differ), "swap_every" and "swap_rate"
    (n_chains, K - 1); ``adapt_ladder``
    (a checked flag, ``tempering.check_adapt``): each chain's ladder adapted during tuning, then
    frozen, info "adapt_ladder" and "adapted_temperatures" (n_chains, K); with a categorical
    element's joint level move, "level_offsets": element -> {"shifted": the continuous
    elements it shifts, "offsets": (n_chains, n_levels, len(shifted)), unit scale} (as
    ``level_moves.chains_record``, per element). Tempered, info "hot" holds the hot copies'
    last states and widths (`hot_states`, each with a leading chain axis: (n_chains, K - 1,
    ...)); ``hot_copies`` (per chain, ``run_study_chain``'s ``hot``) resumes them. A model's
    callable mean basis (``Problem.callables``) keeps the chains in this process, one after
    another (an ``executor`` is refused: ``parallel.in_this_process``). ChainError names a
    chain that failed or whose draws are not finite."""
    tune_rounds, tune_levels = tuning.check_tuning(tune_rounds, tune_levels)
    held_elements(problems, layout)  # a held element the models disagree on: before any work
    element_levels(problems, layout)  # a categorical element the study cannot sample: likewise
    how = "continued" if chain_starts else starts.check_init(init, int(n_chains))
    ladders = tempering.chain_ladders(temperatures, int(n_chains))  # each chain's
    seq = np.random.SeedSequence(seed)
    tasks = [
        {"problems": problems, "layout": layout, "hyper": hyper, "n_iter": int(n_iter),
         "tune": tune, "seed": s, "init": how, "tune_rounds": tune_rounds,
         "tune_levels": tune_levels}
        for s in seq.spawn(int(n_chains))
    ]  # fmt: skip
    for c, task in enumerate(tasks):  # a fresh study's tasks as before
        if chain_starts:
            task.update(start=chain_starts[c], prop_mh=prop_mh)
        if widths is not None:
            task["widths"] = widths[c]
        if temperatures is not None:
            task.update(temperatures=ladders[c], swap_every=int(swap_every))
        if adapt_ladder:
            task["adapt_ladder"] = True
        if hot_copies is not None:
            task["hot"] = hot_copies[c]
    n_temps = 0 if temperatures is None else len(ladders[0])
    held = sorted({name for p in problems for name in p.callables})  # a model's callable mean
    n_jobs, executor = in_this_process(held, n_jobs, executor, int(n_chains))  # basis: run here
    runs = run_chains(run_study_chain, tasks, n_jobs=n_jobs, executor=executor,
                      progress=progress, desc="study chain",
                      check=lambda _, r: _wrong_run(r, int(n_iter), layout.n_elements,
                                                    n_temps, adapt_ladder))  # fmt: skip
    members = tuple(
        {n: np.stack([r["members"][i][n] for r in runs]) for n in runs[0]["members"][i]}
        for i in range(len(problems))
    )
    out = StudyChains(
        theta=np.stack([r["theta"] for r in runs]), mu=np.stack([r["mu"] for r in runs]),
        lam=np.stack([r["lam"] for r in runs]), log_post=np.stack([r["log_post"] for r in runs]),
        members=members, accept_rate=np.stack([r["accept_rate"] for r in runs]),
        widths=np.stack([r["widths"] for r in runs]), names=tuple(runs[0]["names"]),
        info={"n_iter": int(n_iter), "n_chains": int(n_chains), "tune": bool(tune),
              "tune_rounds": tune_rounds, "tune_levels": tune_levels, "seed": seed,
              "seed_entropy": str(seq.entropy), "init": how},
    )  # fmt: skip
    if temperatures is not None:  # the ladder and each neighbour pair's swap rate
        same = ladders.count(ladders[0]) == len(ladders)  # else a ladder per chain
        out.info.update(temperatures=list(ladders[0]) if same else [list(t) for t in ladders],
                        swap_every=int(swap_every),
                        swap_rate=np.stack([r["swap_rate"] for r in runs]))  # fmt: skip
        hot = [r["hot"] for r in runs]  # (n_chains, K - 1, ...): a continuation resumes them
        out.info["hot"] = {k: np.stack([h[k] for h in hot]) for k in ("theta", "mu", "lam",
                                                                       "widths")}  # fmt: skip
        out.info["hot"]["members"] = [{n: np.stack([h["members"][i][n] for h in hot]) for n in m}
                                      for i, m in enumerate(hot[0]["members"])]  # fmt: skip
    if adapt_ladder:  # each chain's ladder, adapted in its tuning and frozen for its draws
        out.info.update(adapt_ladder=True,
                        adapted_temperatures=np.stack([r["ladder"] for r in runs]))  # fmt: skip
    moves = runs[0].get("level_offsets") or {}
    if moves:  # a categorical element's joint level move: its offsets, per chain
        out.info["level_offsets"] = {
            e: {"shifted": rec["shifted"],
                "offsets": np.stack([np.asarray(r["level_offsets"][e]["offsets"],
                                                dtype=np.float64) for r in runs])}
            for e, rec in moves.items()}  # fmt: skip
    require_finite({"theta": out.theta, "mu": out.mu, "lam": out.lam}, out.log_post)
    return out
