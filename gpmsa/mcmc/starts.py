"""Starting values of chains: GPM/SA's, dispersed around them, or drawn from the prior.

R-hat can only reveal chains that have not forgotten where they started when the starts are
spread wider than the posterior (Gelman and Rubin 1992; Vehtari et al. 2021), so several chains
start from dispersed values by default (``init="auto"``); one chain starts at GPM/SA's initial
values, as GPM/SA does.

- ``"gpmsa"``: ``problem.init`` (theta 0.5, betaU 0.1, lamUz 1, lamWs 1000, ...), inside
  each prior's bounds (``default_start``).
- ``"jitter"``: around GPM/SA's start: theta ~ U(0.1, 0.9); beta through rho = exp(-beta/4)
  ~ U(RHO_JITTER); each precision log-uniform on [x0 / f, x0 f] (x0 its ``default_start``, f
  = ``PRECISION_JITTER``) cut to its prior's bounds (bounds too narrow for the cut: x0).
- ``"prior"``: from the (data-corrected) prior: theta from the truncated normal, rho from
  Beta(rho_a, rho_b) (betaV's: Beta(rhoV_a, rhoV_b) where set, ``Priors.rho_arrays``) capped at
  rho_cap, precisions from their truncated Gammas.

- given: a dict name -> (n_chains, *shape) of each chain's start, on the model's scales (as
  ``Chains.info["starts"]`` records them; ``gpmsa.fit(..., init=emulator)`` builds it from a
  fit's last kept draws, to continue its chains). Parameters left out start at
  ``problem.init``.

A precision whose GPM/SA start lies outside its prior's bounds (lamVz 20 under a per-group
prior with bounds (1000, inf), lamWs 1000 under (1e4, 1e5)) starts instead at its prior's median
inside those bounds (``default_start``; every start inside them is GPM/SA's, as before), under
"gpmsa", as the centre of "jitter", and for a parameter a given dict leaves out. A value the
user gives (``init=``, ``theta_init=``, ``fixed=``) is never moved: outside, a GPMSAError.

Fixed parameters and held elements (``problem.fixed_elements``) keep ``problem.init``. With a
theta constraint (``problem.constraint``),
dispersed and prior starts of theta are redrawn until the constraint holds (``MAX_REDRAWS``).
Each chain draws its start from its own generator
(``start_generator``), separate from the stream of its sweeps.
"""

from __future__ import annotations

import os

import numpy as np
from scipy.special import gammainc, gammaincc, gammainccinv, gammaincinv

from gpmsa.errors import GPMSAError, StartRejectedError
from gpmsa.model.data import as_float
from gpmsa.model.priors import PRECISIONS, GammaPrior, Priors
from gpmsa.model.problem import Problem

CHOICES = ("auto", "gpmsa", "jitter", "prior")
RHO_JITTER = (0.5, 0.99)
"""Range of the uniform start of rho = exp(-beta/4) under ``"jitter"`` (GPM/SA's: 0.975)."""
MAX_REDRAWS = 1000
"""Draws of a dispersed or prior theta start tried against a theta constraint."""
PRECISION_JITTER = 10.0
"""Factor f of the log-uniform start of a precision under ``"jitter"``."""


def check_init(init, n_chains: int, reader: str | None = None) -> str:
    """The init rule for ``n_chains`` chains ("auto" resolved); GPMSAError for an unknown one.
    ``reader``: the function whose result continues a run from a saved file ("gpmsa.load",
    "gpmsa.load_study"), named in the message when ``init`` is some other str or a path."""
    if not isinstance(init, str) or init not in CHOICES:
        hint = ""
        if reader is not None and isinstance(init, str | os.PathLike):
            hint = f"; to continue from a saved file pass init={reader}(path)"
        raise GPMSAError(f"init must be one of {CHOICES}, got {init!r}{hint}")
    if init == "auto":
        return "gpmsa" if n_chains == 1 else "jitter"
    return init


def chain_starts(
    problem: Problem, init, seeds: list[np.random.SeedSequence]
) -> tuple[str, list[dict[str, np.ndarray]]]:
    """The init rule's name ("given" for a dict) and each chain's start (one per seed);
    GPMSAError for an unknown rule, a start of the wrong names or shapes, or one where a prior
    (or the theta constraint) has no mass."""
    if not isinstance(init, dict):
        how = check_init(init, len(seeds))
        return how, [draw_start(problem, how, start_generator(s)) for s in seeds]
    unknown = sorted(set(init) - set(problem.init))
    if unknown:
        raise GPMSAError(f"init: unknown parameter(s) {unknown}; this model has {problem.names}")
    firsts, base = [], default_start(problem)
    for c in range(len(seeds)):
        start = {k: v.copy() for k, v in base.items()}
        for name in set(init) - problem.fixed:
            shape = problem.init[name].shape
            want = (len(seeds), *shape)
            val = as_float(init[name], f"init[{name!r}]")
            if len(seeds) == 1 and val.shape == shape:  # one chain: its start
                val = val[None]
            if val.shape != want:
                one = f" or {shape} for one chain" if len(seeds) == 1 else ""
                raise GPMSAError(
                    f"init[{name!r}] must have shape {want} (chains, *shape){one}, got {val.shape}"
                )
            start[name] = hold(problem, name, val[c].copy())
        bad = [k for k, v in start.items() if not np.all(np.isfinite(v))]
        if bad:
            got = np.ravel(start[bad[0]]).tolist()
            raise GPMSAError(
                f"init[{bad[0]!r}] must be finite numbers, got {got!r:.80} (chain {c})"
            )
        check_start(problem, start, "given")
        if problem.constraint is not None and "theta" in start:
            problem.constraint.check_start(start["theta"], f"init: chain {c}'s theta")
        firsts.append(start)
    return "given", firsts


def default_start(problem: Problem) -> dict[str, np.ndarray]:
    """GPM/SA's start (a copy of ``problem.init``), each element of a sampled precision that
    lies outside its prior's bounds moved to that prior's median inside them (``inside_median``):
    GPM/SA's values are defaults, not the user's, and a chain can only start where the prior
    has density. Every element inside its bounds keeps GPM/SA's value exactly."""
    out = {k: np.array(v, dtype=np.float64) for k, v in problem.init.items()}
    for name in set(problem.sampled) & set(PRECISIONS):
        x = out[name].reshape(-1)  # a view: moved in place
        a, b, lower, upper = problem.priors.gamma_arrays(name, x.size)
        bad = (x <= lower) | (x >= upper)
        if bad.any():
            x[bad] = inside_median(a[bad], b[bad], lower[bad], upper[bad])
    return out


def inside_median(a: np.ndarray, b: np.ndarray, lower: np.ndarray, upper: np.ndarray):
    """The median of each Gamma(a, rate b) truncated to (lower, upper), from the tail holding
    less of the prior's mass (where the other's CDF rounds to 1); where that mass underflows,
    the median of the density's exponential approximation at the bound it piles against
    (``_edge_median``)."""
    lo_p, hi_p = gammainc(a, b * lower), gammainc(a, b * upper)
    lo_q, hi_q = gammaincc(a, b * lower), gammaincc(a, b * upper)
    upper_tail = lo_p > 0.5
    with np.errstate(all="ignore"):
        x = np.where(upper_tail, gammainccinv(a, 0.5 * (lo_q + hi_q)),
                     gammaincinv(a, 0.5 * (lo_p + hi_p))) / b  # fmt: skip
    mass = np.where(upper_tail, lo_q > hi_q, hi_p > lo_p)
    ok = mass & np.isfinite(x) & (x > lower) & (x < upper)
    return np.where(ok, x, _edge_median(a, b, lower, upper))


def _edge_median(a: np.ndarray, b: np.ndarray, lower: np.ndarray, upper: np.ndarray):
    """Median of a truncated Gamma whose mass inside (lower, upper) underflows: it piles at
    the bound nearer the mode (a - 1)/b, where the density is ~exp(-s |x - bound|), s = |(a -
    1)/bound - b|, so ln 2 / s inside that bound; the bounds' geometric middle
    (``_bounds_middle``) where that is not inside them."""
    at_upper = np.maximum(a - 1.0, 0.0) / b >= upper
    edge = np.where(at_upper, upper, lower)
    with np.errstate(all="ignore"):
        step = np.log(2.0) / np.abs((a - 1.0) / edge - b)
        x = np.where(at_upper, edge - step, edge + step)
    ok = np.isfinite(x) & (x > lower) & (x < upper)
    return np.where(ok, x, _bounds_middle(a, b, lower, upper))


def _bounds_middle(a: np.ndarray, b: np.ndarray, lower: np.ndarray, upper: np.ndarray):
    """The geometric middle of bounds (lower, upper) (an infinite upper as 10 max(lower, a/b))."""
    hi = np.where(np.isfinite(upper), upper, 10.0 * np.maximum(lower, a / b))
    return np.sqrt(np.maximum(lower, 1e-12) * hi)


def hold(problem: Problem, name: str, value: np.ndarray) -> np.ndarray:
    """``value`` (a start of parameter ``name``) with its held elements
    (``problem.fixed_elements``) set to ``problem.init``'s, in place."""
    for idx in problem.fixed_elements.get(name, ()):
        value[idx] = problem.init[name][idx]
    return value


def start_generator(seed: np.random.SeedSequence) -> np.random.Generator:
    """The generator of a chain's start: a child of its SeedSequence (not its sweep stream)."""
    child = np.random.SeedSequence(seed.entropy, spawn_key=(*seed.spawn_key, 0x5EED))
    return np.random.default_rng(child)


def _gamma(pri: Priors, name: str, size: int, rng: np.random.Generator) -> np.ndarray:
    """A draw of each of ``size`` elements of precision ``name`` from its truncated Gamma."""
    a, b, lower, upper = pri.gamma_arrays(name, size)
    out = rng.gamma(a, 1.0 / b)
    for _ in range(1000):
        bad = (out <= lower) | (out >= upper)
        if not bad.any():
            return out
        out[bad] = rng.gamma(a[bad], 1.0 / b[bad])
    # a prior with little mass inside its bounds: the bounds' geometric middle
    out[bad] = _bounds_middle(a, b, lower, upper)[bad]
    return out


def _truncnorm01(mean, sd, size: int, rng: np.random.Generator) -> np.ndarray:
    """``size`` draws of Normal(mean, sd) truncated to (0, 1) by redrawing those outside;
    ``mean``, ``sd``: floats, or arrays (size,) (per-element priors, element k under the k-th);
    after 1000 rounds, those still outside uniform on (0.01, 0.99)."""
    out = rng.normal(mean, sd, size)
    each = np.ndim(mean) > 0 or np.ndim(sd) > 0
    if each:
        mean, sd = np.broadcast_arrays(np.asarray(mean, float), np.asarray(sd, float))
    for _ in range(1000):
        bad = (out <= 0.0) | (out >= 1.0)
        if not bad.any():
            return out
        if each:
            out[bad] = rng.normal(mean[bad], sd[bad])
        else:
            out[bad] = rng.normal(mean, sd, int(bad.sum()))
    out[bad] = rng.uniform(0.01, 0.99, int(bad.sum()))
    return out


def check_start(problem: Problem, start: dict[str, np.ndarray], how: str) -> None:
    """GPMSAError naming the parameter and its prior when a start lies where that prior has no
    density (e.g. a given start lamUz = 0.1 outside a prior's bounds (0.3, inf)): no chain could
    have a finite log posterior there."""
    pri = problem.priors
    for name in problem.sampled:
        value = start[name]
        lp = problem.theta_log_prior(value) if name == "theta" else pri.log_prior(name, value)
        if lp == -np.inf:
            prior = getattr(pri, name, None)
            where = f"the support of the {name} prior"
            if isinstance(prior, GammaPrior):
                where = f"the bounds ({prior.lower:g}, {prior.upper:g}) of Priors.{name}"
            elif isinstance(prior, tuple):
                cells = ", ".join(f"({g.lower:g}, {g.upper:g})" for g in prior)
                where = f"the bounds of the per-group Priors.{name} [{cells}]"
            hint = "init='prior', or a fixed= value"
            if how == "given":  # the user's own value: refused, never moved
                hint = f"init[{name!r}] inside them, or leave {name} out of init="
            raise GPMSAError(
                f"the chains' start {name} = {np.ravel(value).tolist()} ({how!r} start) lies "
                f"outside {where}: zero prior density. Widen the prior's bounds, or start inside "
                f"them ({hint})"
            )


def draw_start(problem: Problem, how: str, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One chain's starting values (name -> array of the init's shape) under rule ``how``;
    GPMSAError (``check_start``) for one where a prior has no density, `StartRejectedError`
    for one the theta constraint rejects."""
    if how == "gpmsa":
        start = default_start(problem)
        check_start(problem, start, how)
        if problem.constraint is not None and "theta" in problem.sampled:
            problem.constraint.check_start(start["theta"], "init='gpmsa': the chains' theta")
        return start
    pri = problem.priors
    out = default_start(problem)
    for name in problem.sampled:
        x0 = out[name]
        size = x0.size
        if name == "theta":
            val = _theta_start(problem, how, size, rng)
        elif name in ("betaU", "betaV"):
            if how == "jitter":
                rho = rng.uniform(*RHO_JITTER, size)
            else:
                a, b = pri.rho_arrays(name, x0.shape[-1] if x0.ndim else 1)
                if isinstance(a, np.ndarray):  # betaV's per-group priors, column by column
                    a, b = (np.broadcast_to(v, x0.shape).ravel() for v in (a, b))
                rho = np.minimum(rng.beta(a, b, size), pri.rho_cap)
            val = -4.0 * np.log(rho)
        elif how == "jitter":  # log-uniform on [x0 / f, x0 f] cut to the bounds
            x = x0.ravel()
            _, _, lower, upper = pri.gamma_arrays(name, size)
            lo = np.maximum(x / PRECISION_JITTER, lower * (1.0 + 1e-3) + 1e-12)
            hi = np.minimum(x * PRECISION_JITTER, upper * (1.0 - 1e-3))
            lo, hi = _jitter_range(name, lower, upper, x, lo, hi)
            val = np.exp(rng.uniform(np.log(lo), np.log(hi)))
        else:
            val = _gamma(pri, name, size, rng)
        out[name] = hold(problem, name, np.asarray(val, dtype=np.float64).reshape(x0.shape))
    check_start(problem, out, how)
    return out


def _jitter_range(name: str, lower: np.ndarray, upper: np.ndarray, x: np.ndarray,
                  lo: np.ndarray, hi: np.ndarray):  # fmt: skip
    """(lo, hi) of a precision's jittered start where the cut [x0 / f, x0 f] is empty: x0 itself
    when it lies inside the prior's bounds (lower, upper) (bounds narrower than their 1e-3
    margins), a GPMSAError naming the parameter and its bounds when it lies outside them (as
    the 'gpmsa' start's, ``check_start``)."""
    empty = lo > hi
    if not empty.any():
        return lo, hi
    inside = (x > lower) & (x < upper)
    if np.any(empty & ~inside):
        k = int(np.argmax(empty & ~inside))
        group = f" (group {k}'s)" if name == "lamVz" and x.size > 1 else ""
        raise GPMSAError(
            f"the chains' start {name} = {x.tolist()} ('jitter' start: log-uniform on "
            f"[x0 / {PRECISION_JITTER:g}, x0 * {PRECISION_JITTER:g}]) cannot reach the bounds "
            f"({lower[k]:g}, {upper[k]:g}) of Priors.{name}{group}: zero prior density. Widen "
            "the prior's bounds, or start inside them (init='prior', or a fixed= value)"
        )
    return np.where(empty, x, lo), np.where(empty, x, hi)


def _theta_start(problem: Problem, how: str, size: int, rng: np.random.Generator) -> np.ndarray:
    """A dispersed ("jitter") or prior theta start inside the theta constraint (if any)."""
    pri = problem.priors
    for _ in range(MAX_REDRAWS):
        if how == "jitter":
            val = rng.uniform(0.1, 0.9, size)
        else:
            val = _truncnorm01(*pri.theta_moments(size), size, rng)
        if problem.theta_levels is not None:  # a categorical element starts at its nearest level
            val = problem.snap_theta(val)
        val = hold(problem, "theta", val)
        if problem.constraint is None or problem.constraint(val):
            return val
    raise StartRejectedError(
        f"no {how!r} start of theta inside the theta constraint in {MAX_REDRAWS} draws; pass "
        "init='gpmsa' with theta_init= inside the allowed region",
        {"init": "gpmsa", "theta_init": ...},
    )
