"""Parallel tempering (opt-in): a move between the modes of a posterior.

GPM/SA's Metropolis-within-Gibbs sweep moves one element a short step at a time; a chain that
ends tuning in a mode tens of log-posterior units below the main one stays there for thousands
of sweeps (docs/internals.md, "What the starts cannot fix"). With ``temperatures`` a chain runs
a ladder of copies at temperatures 1 = T_0 < T_1 < ... < T_{K-1}; copy k targets

    pi_k(x) ∝ L(x)^(1/T_k) p(x),

the likelihood tempered, the prior not (a hot copy roams the prior's support, which the bounds
keep proper). Each copy sweeps with its own step widths (tuned at its temperature by GPM/SA's
tuning, ``gpmsa.mcmc.tuning``, or the widths given), holds its own likelihood state and runs
the nugget-ridge moves (the likelihood cancels there, so they are the same at every
temperature). Every ``swap_every`` sweeps of all copies, neighbours k, k + 1 (k = 0 .. K - 2 in
turn) propose to exchange their states, accepted with probability

    min(1, exp((1/T_k - 1/T_{k+1}) (log L(x_{k+1}) - log L(x_k)))),

the priors cancelling: each swap leaves the product of the copies' targets invariant, so the
T = 1 copy, whose draws alone are kept, samples the posterior. Swaps run through the tuning
sweeps too (the cold copy can reach the main mode before any draw). A categorical theta's level
move learns its shifts at T = 1 and every copy uses them (any shifts keep the move exact).
Every uniform comes from the chain's own Generator: the draws depend on the seed alone.
The torch backend runs the same definition with every chain's copies as rows of one batch
(``gpmsa.backends.torch_backend``, ``sample``'s ``temperatures``; with ``chain_groups`` > 1 a
group holds whole chains with all their copies; ``ladder`` and ``check_swap_every`` check its
arguments).

An adaptive ladder (opt-in, numpy and torch: ``adapt_ladder=True``, `adapt_ladder`): before
GPM/SA's tuning, ``tune_rounds`` x ``tune_levels`` further sweeps of every copy (GPM/SA's
candidate widths in turn), a swap round after each, move the temperatures between T_0 = 1 and
the hottest (both fixed: the hottest must cross the barrier, which no swap rate measures) so
that the neighbours' swap rates become equal: after swap round n, each gap's logarithm
S_k = log(T_{k+1} - T_k) moves by kappa_n (a_k - mean(a)), a_k the pair's acceptance
probability min(1, r_k) in that round (the swap rate's Rao-Blackwellised estimate), kappa_n =
``ADAPT_RATE`` ``ADAPT_LAG`` / (n + ``ADAPT_LAG``) (Vousden, Farr & Mandel 2016, MNRAS 455,
1919, their dynamics of log(T_k - T_{k-1}), with the gaps rescaled to keep the hottest
temperature); the ladder kept is the mean of S over the second half of the rounds (Polyak
averaging). The ladder is then FROZEN: the copies' widths are tuned at it and every kept draw
comes from the fixed-ladder chain above, an exact MCMC (the adaptation only chooses the
ladder, as the tuning chooses the widths). The torch backend adapts every chain's ladder in
its batch by the same rule (`adapt_gaps`, `gap_ladder`, `kept_ladder`, on a leading chain
axis), each chain's rows at its own ladder.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tuning
from gpmsa.mcmc.acceptance import log_uniform
from gpmsa.model.data import check_count, check_flag
from gpmsa.model.problem import Problem

RATIO = 2.0
"""Ratio of neighbouring temperatures of ``temperatures=n``: T_k = RATIO**k, k = 0 .. n - 1."""
MAX_TEMPERATURES = 32
"""Most copies per chain (each holds its own likelihood state and costs a sweep)."""
MAX_SWAP_EVERY = 1_000_000
"""Largest ``swap_every`` (sweeps between swap rounds)."""
ADAPT_RATE = 0.1
"""The adaptive ladder's initial step kappa_0 on the log gaps (per swap round; `adapt_ladder`)."""
ADAPT_LAG = 200.0
"""Swap rounds over which the adaptive ladder's step halves (kappa_n = kappa_0 lag / (n + lag))."""


def ladder(temperatures) -> tuple[float, ...] | None:
    """The temperatures of ``sample``'s ``temperatures``: None (no tempering), 1 (one
    temperature: no tempering either; how a continuation of a tempered study or fit asks for
    plain chains), an integer n in [2, ``MAX_TEMPERATURES``] (RATIO**k, k = 0 .. n - 1), or a
    sequence of 2 to
    ``MAX_TEMPERATURES`` finite temperatures, strictly increasing from exactly 1 (the copy
    whose draws are kept). GPMSAError naming the value otherwise."""
    if temperatures is None:
        return None
    if isinstance(temperatures, int | np.integer) and not isinstance(temperatures, bool):
        if temperatures == 1:
            return None
        n = check_count(temperatures, "temperatures", 1, MAX_TEMPERATURES)
        return tuple(RATIO**k for k in range(n))
    if isinstance(temperatures, str | bytes | dict) or not hasattr(temperatures, "__len__"):
        raise GPMSAError(
            f"temperatures must be None, 1 (no tempering), an integer n in [2, "
            f"{MAX_TEMPERATURES}] (the ladder "
            f"{RATIO:g}**k) or a sequence of temperatures from 1, got {temperatures!r}"
        )
    try:
        arr = np.asarray(temperatures, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.ndim != 1 or not 2 <= arr.size <= MAX_TEMPERATURES:
        raise GPMSAError(
            f"temperatures: a ladder must be a flat sequence of 2 to {MAX_TEMPERATURES} numbers, "
            f"got {temperatures!r}"
        )
    if not (np.all(np.isfinite(arr)) and arr[0] == 1.0 and np.all(np.diff(arr) > 0)):
        raise GPMSAError(
            "temperatures: a ladder must start at exactly 1 (the copy whose draws are kept) and "
            f"increase strictly, every temperature finite, got {arr.tolist()}"
        )
    return tuple(float(v) for v in arr)


def chain_ladders(temperatures, n_chains: int) -> list[tuple[float, ...]] | None:
    """Each chain's ladder of a sampler's ``temperatures``: `ladder`'s, the same for every
    chain, or a (n_chains, K) array (a continuation of a fit whose chains adapted their ladders,
    ``settings["adapted_temperatures"]``), row c chain c's ladder (each checked by `ladder`);
    None without tempering. GPMSAError naming the value otherwise."""
    if isinstance(temperatures, np.ndarray) and temperatures.ndim == 2:
        if temperatures.shape[0] != n_chains:
            raise GPMSAError(
                f"temperatures: one ladder per chain must have {n_chains} rows (n_chains), got "
                f"shape {temperatures.shape}"
            )
        return [ladder(row) for row in temperatures]
    one = ladder(temperatures)
    return None if one is None else [one] * n_chains


def recorded_ladders(record: dict, source_settings: dict) -> dict:
    """A tempered run's settings ``record`` as a fresh tempered run records its ladders: where
    its chains ran at a ladder each ("temperatures" (n_chains, K): a continuation of chains
    that adapted theirs), "temperatures" becomes the source's (``source_settings``', the ladder
    they started from) and "adapted_temperatures" each chain's, unless the run adapted them
    again (its own "adapted_temperatures" kept). Other records are returned as given."""
    if np.ndim(record.get("temperatures")) != 2:
        return record
    per_chain = np.asarray(record["temperatures"]).tolist()
    return {**record, "temperatures": list(source_settings["temperatures"]),
            "adapted_temperatures": record.get("adapted_temperatures", per_chain)}  # fmt: skip


def check_swap_every(swap_every, temperatures, n_iter: int | None = None,
                     what: str = "n_iter") -> int:  # fmt: skip
    """``swap_every`` as an int in [1, ``MAX_SWAP_EVERY``]; GPMSAError for another value, for
    a value other than 1 without ``temperatures`` (there is nothing to swap), or for one above
    ``n_iter`` (the caller's argument ``what``) with them (no swap round among the draws: its
    swap rate would read 0)."""
    n = check_count(swap_every, "swap_every", 1, MAX_SWAP_EVERY)
    if temperatures is None and n != 1:
        raise GPMSAError(f"swap_every={n} needs temperatures= (parallel tempering)")
    if temperatures is not None and n_iter is not None and n > n_iter:
        raise GPMSAError(
            f"swap_every={n} exceeds {what}={n_iter}: no swap round would run among the draws "
            "(the copies would never exchange states, and the swap rates would read 0); give "
            f"swap_every <= {what}"
        )
    return n


def swap(states: list, betas: tuple[float, ...], u: np.ndarray, accepted: np.ndarray,
         probs: np.ndarray | None = None) -> None:  # fmt: skip
    """One round of neighbour swaps: for k = 0 .. K - 2, copies k and k + 1 (``states``,
    ``ChainState``s or a study's ``StudyState``s at inverse temperatures ``betas``) exchange
    their states (``exchange``: the likelihood states, the parameters with them, and the running
    log priors) where log u[k] is below the log acceptance ratio (u[k] = 0: log u = -inf), on
    each copy's ``loglik``; adds 1 to ``accepted[k]`` per swap and, given ``probs`` (K - 1,),
    sets probs[k] to the proposal's acceptance probability min(1, exp(log ratio))."""
    for k in range(len(states) - 1):
        a, b = states[k], states[k + 1]
        log_r = (betas[k] - betas[k + 1]) * (b.loglik - a.loglik)
        if probs is not None:
            probs[k] = math.exp(min(log_r, 0.0))
        if log_uniform(u[k]) < log_r:  # (u = 0: -inf)
            a.exchange(b)
            accepted[k] += 1


def check_adapt(adapt_ladder, temperatures: tuple[float, ...] | None, tune: bool) -> bool:
    """``adapt_ladder`` as a bool; GPMSAError for a non-bool, or for True without
    ``temperatures`` (a checked ladder), with fewer than 3 of them (T_0 = 1 and the hottest
    stay: nothing between them to move) or without tuning (the ladder adapts during it)."""
    if not check_flag(adapt_ladder, "adapt_ladder"):
        return False
    if temperatures is None:
        raise GPMSAError("adapt_ladder=True needs temperatures= (parallel tempering)")
    if len(temperatures) < 3:
        raise GPMSAError(
            f"adapt_ladder=True needs at least 3 temperatures, got {list(temperatures)}: T_0 = "
            "1 and the hottest stay fixed, the ones between them move"
        )
    if not tune:
        raise GPMSAError(
            "adapt_ladder=True with tune=False: the ladder adapts during tuning, before the "
            "draws; give tune=True, or a fixed ladder"
        )
    return True


def adapt_ladder(states: list, temperatures, rng, names, widths, n_rounds, n_levels, on_round):
    """The adaptive ladder (module docstring) of the copies ``states`` at ``temperatures`` (the
    starting ladder; their ``beta`` set to the adapted one): ``n_rounds`` rounds of a sweep of
    every copy at each of GPM/SA's ``n_levels`` candidate widths (``tuning.level_widths`` of
    ``widths``, as the tuning's; the acceptances not kept), a swap round after each, the log
    gaps moved after each swap round (`adapt_gaps`). Returns the adapted ladder (K,): 1,
    strictly increasing, the hottest unchanged; the starting ladder where the averaged one is
    not that in float64 (`kept_ladder`)."""
    temps = np.asarray(temperatures, dtype=float)
    top, n_temps = temps[-1], len(states)
    log_gap = np.log(np.diff(temps))
    mean_gap, n_mean = np.zeros_like(log_gap), 0
    cands = tuning.level_widths(names, widths, n_levels)
    acc, swaps, probs = np.zeros(widths.size), np.zeros(n_temps - 1), np.empty(n_temps - 1)
    n_total = n_rounds * n_levels
    for n in range(n_total):
        lev = n % n_levels
        for state in states:
            state.sweep(cands[lev], False, acc)
        betas = tuple(state.beta for state in states)
        swap(states, betas, rng.random(n_temps - 1), swaps, probs)
        log_gap = adapt_gaps(log_gap, probs, n, top)
        _set_ladder(states, gap_ladder(log_gap, top))
        if 2 * n >= n_total:  # the second half's mean (Polyak averaging)
            mean_gap += log_gap
            n_mean += 1
        if lev == n_levels - 1:
            on_round(n_levels * n_temps)
    out = kept_ladder(mean_gap / max(n_mean, 1), temps)
    _set_ladder(states, out, first=0)
    return tuple(float(t) for t in out)


def adapt_gaps(log_gap: np.ndarray, probs: np.ndarray, n: int, top: float) -> np.ndarray:
    """The adaptive ladder's move after swap round ``n`` (from 0; module docstring): the log
    gaps ``log_gap`` (..., K - 1), S_k = log(T_{k+1} - T_k), moved by kappa_n (a_k - mean(a)),
    a = ``probs`` (..., K - 1) the round's swap acceptance probabilities, then shifted so that
    the ladder's hottest stays ``top``; a leading axis holds one ladder per chain. Returns the
    new log gaps (the arrays given unchanged)."""
    mean = probs.mean(axis=-1, keepdims=True)
    log_gap = log_gap + ADAPT_RATE * ADAPT_LAG / (n + ADAPT_LAG) * (probs - mean)
    return log_gap + (math.log(top - 1.0) - np.log(np.sum(np.exp(log_gap), -1, keepdims=True)))


def gap_ladder(log_gap: np.ndarray, top: float) -> np.ndarray:
    """The ladder (..., K) 1, 1 + cumsum(exp(log_gap)) of the log gaps (..., K - 1), its last
    entry ``top`` exactly."""
    ones = np.ones((*log_gap.shape[:-1], 1))
    temps = np.concatenate([ones, 1.0 + np.cumsum(np.exp(log_gap), -1)], -1)
    temps[..., -1] = top
    return temps


def kept_ladder(mean_gap: np.ndarray, start) -> np.ndarray:
    """The adapted ladder kept (..., K): `gap_ladder` of the averaged log gaps ``mean_gap``
    (..., K - 1), or the starting ladder ``start`` (K,) in each where that is not strictly
    increasing in float64 (swap rates stuck at 0 and 1 can shrink a gap below a rung's
    resolution: rungs merged or past the hottest)."""
    start = np.asarray(start, dtype=float)
    out = gap_ladder(mean_gap, start[-1])
    ok = np.all(np.diff(out, axis=-1) > 0, axis=-1)  # (so every rung finite: in [1, top])
    return np.where(ok[..., None], out, start)


def _set_ladder(states: list, temps: np.ndarray, first: int = 1) -> None:
    """The copies' ``beta`` from the ladder ``temps`` (K,), from copy ``first`` on."""
    for state, t in zip(states[first:], temps[first:], strict=True):
        state.beta = 1.0 / t


def tune_ladder(states: list, betas, rng, names, widths, n_rounds, n_levels, swaps, on_round):
    """GPM/SA's tuning (``tuning.tune_widths``) of every copy at its temperature, the copies'
    sweeps interleaved (round, level, copy), a swap round after each level (counted in
    ``swaps``); returns each copy's tuned widths."""
    cands = tuning.level_widths(names, widths, n_levels)
    acc = np.zeros((len(states), n_levels, widths.size))
    for _ in range(n_rounds):
        for lev in range(n_levels):
            for k, state in enumerate(states):
                state.sweep(cands[lev], False, acc[k, lev])
            swap(states, betas, rng.random(len(states) - 1), swaps)
        on_round(n_levels * len(states))
    return [tuning.choose_widths(widths, cands, a, n_rounds) for a in acc]


def run_ladder(states: list, rng: np.random.Generator, n_iter: int, widths: np.ndarray,
               kinds: list[str], record: Callable[[int], None], *, swap_every: int, tune: bool,
               tune_rounds: int, tune_levels: int, prop_mh: bool, bar, desc: str,
               adapt: tuple[float, ...] | None = None, copy_widths: list | None = None,
               out: dict | None = None):  # fmt: skip
    """The ladder's run (module docstring) over ``states``, its copies at the inverse
    temperatures of their ``beta`` (each a ``sampler.ChainState``, or a study's
    ``StudyState``, at the chain's start): the categorical level shifts learnt at T = 1 and
    shared, the ladder adapted (``adapt``: the copies' temperatures, to adapt with ``tune``,
    `adapt_ladder`, then frozen; None: the ladder stays), every
    copy tuned at its temperature from ``widths`` (``tune``; GPM/SA's tuning ``kinds``, per
    element), then ``n_iter`` sweeps of every copy, a swap round every ``swap_every``,
    ``record(it)`` after each (the T = 1 copy, ``states[0]``, is the one to keep). Returns the
    T = 1 copy's accepted counts and widths, the swap acceptance rate (K - 1,) of each
    neighbour pair over the draws' swap rounds and the adapted ladder (K,; None without
    ``adapt``). ``copy_widths``: the hot copies' flat widths (K - 1), which they run with where
    not tuned (a resumed continuation; else ``widths``, each copy's); ``out`` (a dict) gets
    "widths", every copy's widths as run (K)."""
    n_temps = len(states)
    temps = None if adapt is None else tuple(adapt)
    w = [widths] * n_temps if copy_widths is None else [widths, *copy_widths]
    swaps = np.zeros(n_temps - 1)
    if tune and adapt is not None and widths.size:
        _share_level_shifts(states)  # the level moves as in the tuning (categorical)
        bar.set_description(f"{desc}: adapting the ladder ({n_temps} temperatures)")
        temps = adapt_ladder(states, adapt, rng, kinds, widths, tune_rounds, tune_levels,
                             bar.update)  # fmt: skip
    betas = tuple(state.beta for state in states)  # frozen from here: the draws' ladder
    if tune and widths.size:
        _share_level_shifts(states)  # the widths tuned with the level moves (categorical)
        bar.set_description(f"{desc}: tuning step widths ({n_temps} temperatures)")
        w = tune_ladder(states, betas, rng, kinds, widths, tune_rounds, tune_levels, swaps,
                        bar.update)  # fmt: skip
    _share_level_shifts(states)  # anew at T = 1, shared: any shifts keep the move exact
    bar.set_description(f"{desc}: sampling ({n_temps} temperatures)")
    accepted = [np.zeros(widths.size) for _ in states]
    swaps[:] = 0.0
    for it in range(n_iter):
        for k, state in enumerate(states):
            state.sweep(w[k], prop_mh, accepted[k])
        if it % swap_every == swap_every - 1:
            swap(states, betas, rng.random(n_temps - 1), swaps)
        record(it)
        if it % 100 == 99:
            bar.update(100 * n_temps)
    bar.update((n_iter % 100) * n_temps)
    if out is not None:
        out["widths"] = w
    return accepted[0], w[0], swaps / max(n_iter // swap_every, 1), temps


def _share_level_shifts(states: list) -> None:
    """The T = 1 copy's categorical level shifts learnt at its state, every copy given them."""
    cold = states[0]
    cold.learn_level_shifts()
    for state in states[1:]:
        state.use_level_shifts(cold)


def run_tempered_chain(
    problem: Problem,
    n_iter: int,
    new_state: Callable[[dict | None], object],
    *,
    temperatures: tuple[float, ...],
    swap_every: int,
    tune: bool,
    widths: dict[str, np.ndarray],
    rng: np.random.Generator,
    tune_rounds: int,
    tune_levels: int,
    progress: bool = False,
    desc: str = "MCMC",
    proportional_steps: bool | None = None,
    record: dict | None = None,
    adapt_ladder: bool = False,
    copies: list[tuple[dict, dict]] | None = None,
):
    """``sampler.run_chain`` with a ladder of tempered copies (module docstring, `run_ladder`),
    each a ``new_state(start)`` (a ``sampler.ChainState`` at ``start``, None: the chain's start,
    drawing from ``rng``): ``n_iter`` sweeps of every copy after its tuning; the T = 1 copy's
    draws are kept. ``copies``: each hot copy's (start, widths) (K - 1; a continuation resuming
    the copies where they stopped, its widths run with where not ``tune``); None: every copy at
    the chain's start. Returns ``run_chain``'s draws, log_post, accept rates and widths (of the
    T = 1 copy) and the swap acceptance rate (K - 1,) of each neighbour pair over the draws'
    swap rounds, and with ``adapt_ladder`` (and ``tune``) the adapted ladder (K,), frozen before
    the tuning of the widths and the draws; ``record`` as ``run_chain``'s (the T = 1 copy's
    level moves, shared by the ladder) with "hot": the hot copies' last states and widths (each
    a list of K - 1 dicts name -> array, widths NaN where not sampled)."""
    starts = [None] + [start for start, _ in copies or [(None, None)] * (len(temperatures) - 1)]
    states = []
    for t, start in zip(temperatures, starts, strict=True):
        state = new_state(start)
        state.beta = 1.0 / t
        states.append(state)
    cold = states[0]
    cold.check_start()
    n_temps = len(states)
    n_tune = tune_rounds * tune_levels * (1 + adapt_ladder) if tune else 0
    draws = {n: np.empty((n_iter, *problem.init[n].shape)) for n in problem.names}
    log_post = np.empty(n_iter)
    names = problem.names

    def keep(it: int) -> None:
        prm = cold.params
        for n in names:
            draws[n][it] = prm[n]
        log_post[it] = cold.log_post()

    prop_mh = (not tune) if proportional_steps is None else proportional_steps
    hot_widths = None if copies is None else [cold.flat_widths(w) for _, w in copies]
    ran: dict = {}
    total = n_temps * (n_iter + n_tune)
    with progress_bar(progress, total, desc, unit="it") as bar, one_thread(None):
        accepted, w, rates, adapted = run_ladder(
            states, rng, n_iter, cold.flat_widths(widths), [n for n, _ in cold.els], keep,
            swap_every=swap_every, tune=tune, tune_rounds=tune_rounds, tune_levels=tune_levels,
            prop_mh=prop_mh, bar=bar, desc=desc, adapt=temperatures if adapt_ladder else None,
            copy_widths=hot_widths, out=ran,
        )  # fmt: skip
    rate, wid = cold.element_records(accepted, w, n_iter)
    if record is not None:
        record["level"] = cold.level_record()
        record["hot"] = (
            [{n: np.array(state.params[n]) for n in names} for state in states[1:]],
            [cold.element_records(accepted, v, n_iter)[1] for v in ran["widths"][1:]],
        )
    if adapt_ladder:
        return draws, log_post, rate, wid, rates, np.asarray(adapted)
    return draws, log_post, rate, wid, rates
